/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_SCENE_ENVMAP_H
#define GLINT_FIT_SCENE_ENVMAP_H

/*
 * Distant light as a lat-long (equirectangular) RGB radiance map.
 *
 * Map convention (docs/conventions.md): +Y is up; a map direction
 * d = (x, y, z) has polar angle theta = acos(y) from +Y and azimuth
 * phi = atan2(x, -z); it is stored at u = 0.5 + phi / (2 pi),
 * v = theta / pi (u across, v down; texel (i, j) is centred at
 * ((i + 0.5) / W, (j + 0.5) / H)).  So the centre of the image is the -Z
 * direction, the default camera's view direction.  A rotation R takes map
 * directions to world directions: L_world(d) = scale * map(R^T d).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: a map is built by one thread, then read
 * by many.  Who frees: glint_envmap_free(), glint_env_hot_free().
 */

#include "core/image.h"
#include "core/vec.h"

/* A piecewise-constant distribution over the map's texels. */
struct glint_env_dist {
	double *marginal; /* H + 1 entries, CDF over rows */
	double *cond;	  /* H * (W + 1) entries, CDF over columns per row */
	double total;	  /* sum of the weights */
};

struct glint_envmap {
	struct glint_image *img; /* owned */
	struct mat3 rot;	 /* world from map */
	double scale;		 /* radiance multiplier */
	/* Importance sampling by luminance * sin(theta) (envmap.c). */
	struct glint_env_dist dist;
};

/*
 * Take ownership of img (a lat-long map, width >= 2 height) and build the
 * sampling tables.  rot_deg = rotation about X, then Y, then Z (degrees,
 * m3_rotation_xyz_deg).  Fails on NaN/Inf or negative radiance, naming the
 * pixel; negatives within 1 % of the mean (lossy-compression ringing) are
 * clamped to 0.  `what` names the source in messages.  img is freed on
 * failure.
 */
int glint_envmap_new(struct glint_image *img, const double rot_deg[3],
		     double scale, const char *what, struct glint_envmap **out);
/* Read a map from an image file as radiance (an 8-bit one refused
 * unless srgb: glint_image_read_radiance) and build it (see
 * glint_envmap_new). */
int glint_envmap_load(const char *path, const double rot_deg[3], double scale,
		      int srgb, struct glint_envmap **out);
void glint_envmap_free(struct glint_envmap *env);

/* Bilinear radiance seen along world direction d (unit). */
void glint_envmap_lookup(const struct glint_envmap *env, struct vec3 d,
			 double rgb[3]);

/*
 * Sample a world direction with density proportional to the weight of the
 * texel containing it (luminance of the bilinear interpolant averaged over
 * the texel, times sin theta; uniform inside a texel).
 * Returns the exact solid-angle pdf of that direction (0 if the map is black)
 * and fills *dir; u1, u2 in [0, 1).
 */
double glint_envmap_sample(const struct glint_envmap *env, double u1, double u2,
			   struct vec3 *dir);

/* glint_envmap_sample()'s draws for count pairs (u1[k], u2[k]) at once,
 * their table searches side by side: the same directions and pdfs. */
void glint_envmap_sample_n(const struct glint_envmap *env, int count,
			   const double *u1, const double *u2, struct vec3 *dir,
			   double *pdf);

/* The pdf glint_envmap_sample() has for world direction d. */
double glint_envmap_pdf(const struct glint_envmap *env, struct vec3 d);

/*
 * A continuous stand-in for that pdf: the texel densities interpolated
 * bilinearly in (u, v).  Used in multiple-importance weights where the
 * fitter needs the estimate to vary smoothly with the parameters (weights
 * need not be the sampling pdf to stay unbiased).
 */
double glint_envmap_pdf_smooth(const struct glint_envmap *env, struct vec3 d);

/*
 * A direction located on the map once: glint_envmap_locate() converts it
 * to map coordinates and prefetches the texels that a bilinear read and
 * the pdf take, so that several directions' reads overlap;
 * glint_envmap_located_pdf() and _lookup() then give what
 * glint_envmap_pdf() and glint_envmap_lookup() give for it, bit for bit.
 */
struct glint_envmap_loc {
	double u, v;
};
void glint_envmap_locate(const struct glint_envmap *env, struct vec3 d,
			 struct glint_envmap_loc *q);
double glint_envmap_located_pdf(const struct glint_envmap *env,
				const struct glint_envmap_loc *q);
void glint_envmap_located_lookup(const struct glint_envmap *env,
				 const struct glint_envmap_loc *q,
				 double rgb[3]);

/* The same three for another distribution over this map's texels. */
double glint_env_dist_sample(const struct glint_envmap *env,
			     const struct glint_env_dist *d, double u1,
			     double u2, struct vec3 *dir);
void glint_env_dist_sample_n(const struct glint_envmap *env,
			     const struct glint_env_dist *d, int count,
			     const double *u1, const double *u2,
			     struct vec3 *dir, double *pdf);
double glint_env_dist_pdf(const struct glint_envmap *env,
			  const struct glint_env_dist *d, struct vec3 d_world);
double glint_env_dist_pdf_smooth(const struct glint_envmap *env,
				 const struct glint_env_dist *d,
				 struct vec3 d_world);

/* A group of hot points near one another (a lamp): the points
 * pts[pts0 .. pts1) and part[part0 .. part1) lie within `radius` radians
 * of `axis`, so that a lobe that cannot reach the cone skips them all. */
struct glint_env_hot_cluster {
	struct vec3 axis;
	double radius;
	int pts0, pts1, part0, part1, coarse0, coarse1;
	/* The spread the coarse points leave out (radians, a Gaussian's
	 * standard deviation per axis): each texel's flux spreads over
	 * the texel, its point (at the flux's centroid) over none; the
	 * flux-weighted mean of those variances. */
	double coarse_s;
};

/*
 * The few brightest texels of a map (a sun), to be integrated
 * deterministically rather than sampled: texels whose sampling weight is at
 * least tau times the largest, when there are at most max_texels of them
 * (else none: the map has no compact peak).  `rest` samples everything
 * else.  The map is split two ways:
 * - by area (`pts`): each hot texel covered by q x q points carrying the
 *   map's radiance x solid angle; the rest is every other texel (the
 *   irradiance of the diffuse lobe);
 * - by value (`part`): the map's bilinear radiance made from the hot
 *   texels' values alone, on q x q points of every texel it reaches (the
 *   hot ones and their neighbours), and again on one point a texel
 *   (`coarse`: the same flux, each texel's at its centre); the rest is
 *   the radiance made from the other texels' values (glint_env_query(),
 *   glint_env_rest_lookup()).
 *   Both parts are continuous, so a lobe sample that moves with the
 *   parameters never jumps at a hot texel's edge: the fitter's objective
 *   stays smooth in roughness (shade_cache.c).
 */
struct glint_env_hot {
	int ntexels;
	int npts;
	float *pts; /* npts x 6: world direction, radiance x solid angle */
	int npart;
	float *part; /* npart x 6: the same for the hot part's radiance */
	/* The hot part on one point a texel (none when q is 1: part is
	 * that), for a lobe many texels wide (shade_lobe.c). */
	int ncoarse;
	float *coarse;
	unsigned char *is_hot; /* W x H */
	struct glint_env_dist rest;
	struct vec3 axis; /* a cone holding every hot texel: */
	double radius;	  /* axis and half-angle (radians) */
	/* The points grouped by where they are (pts and part in cluster
	 * order): a map of several lamps has a cone per lamp. */
	struct glint_env_hot_cluster *clusters;
	int nclusters;
	/* The rest as one table for glint_env_query(): per texel its RGB
	 * (hot texels black) and its density under `rest`, with a border of
	 * one texel (wrapped in azimuth, clamped at the poles) so that a
	 * bilinear read needs no wrapping: (W + 2) x (H + 2) x 4 floats. */
	float *tab;
	const struct glint_envmap *env;
};

/*
 * One query for a direction, converting it to map coordinates once: the
 * radiance of the map's rest (bilinear, from the texels that are not hot)
 * and the smooth pdf of hot->rest there (glint_env_dist_pdf_smooth()),
 * from one read of hot->tab: the lobe samples' inner loop.
 */
void glint_env_query(const struct glint_env_hot *hot, struct vec3 d,
		     double rgb[3], double *pdf_smooth);
/* glint_env_query() in two steps, so that several queries' table reads
 * overlap: _start converts the direction and prefetches the texels,
 * _finish reads them; the same values as glint_env_query(). */
struct glint_env_query {
	const float *t;
	size_t stride;
	double tx, ty, cy;
};
void glint_env_query_start(const struct glint_env_hot *hot, struct vec3 d,
			   struct glint_env_query *q);
/* _start for n directions (dx[k], dy[k], dz[k]) into q[k], the
 * conversions in one loop that vectorises. */
void glint_env_query_start_n(const struct glint_env_hot *hot, int n,
			     const double *dx, const double *dy,
			     const double *dz, struct glint_env_query *q);
void glint_env_query_finish(const struct glint_env_hot *hot,
			    const struct glint_env_query *q, double rgb[3],
			    double *pdf_smooth);
/* The radiance of the map's rest alone (glint_env_query()). */
void glint_env_rest_lookup(const struct glint_envmap *env,
			   const struct glint_env_hot *hot, struct vec3 d,
			   double rgb[3]);

/* The map's hot texels: those whose share of the map's sampling
 * distribution is at least tau of the largest share (none when that is
 * more than max_texels: no compact peak), q x q points each.  *out is the
 * caller's, freed with glint_env_hot_free(); env must outlive it. */
int glint_env_hot_new(const struct glint_envmap *env, double tau,
		      int max_texels, int q, struct glint_env_hot **out);
void glint_env_hot_free(struct glint_env_hot *hot);
#endif
