/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_SHADE_CACHE_INTERNAL_H
#define GLINT_FIT_RENDER_SHADE_CACHE_INTERNAL_H

/*
 * What shade_cache.c (set-up, the cache, the parallel evaluation) and
 * shade_lobe.c (one lobe's estimate at a hit or over a pixel's footprint)
 * share; private to fit/render/.
 */

#include "shade_cache.h"

#include "irradiance.h"

#include "core/fastmath.h"

#include <math.h>
#include <stdint.h>

/* One fixed env-map sample of a hit, in the hit's local frame. */
struct env_sample {
	float wi[3];
	float l[3];
	float pdf;	  /* the sampling pdf */
	float pdf_smooth; /* continuous stand-in for the MIS weights */
	float g[4];	  /* model->lobes->geometry() at wo, wi */
};

/* One primary hit: its frame, its view direction, its sample shift. */
struct cache_hit {
	float t[3], b[3], n[3];
	float wo[3]; /* local */
	uint32_t seed;
};

/*
 * A pixel's footprint: its normal and ray direction as affine functions
 * of the position (u, v) in the pixel (centre 0, edges +-1/2), fitted to
 * its primary hits by least squares, and how fast its mirror direction
 * turns across it.  The hot texels of a lobe narrower than that are
 * integrated over the pixel on a grid (hot_footprint()), and its lobe
 * samples spread over the pixel (struct spread): a sun or a softbox's
 * edge seen in a near-mirror covers part of a pixel, which a few point
 * samples alias.
 */
struct cache_foot {
	float n[3], nu[3], nv[3];
	float d[3], du[3], dv[3];
	float r[3]; /* mirror direction at the centre */
	float turn; /* radians per pixel (largest of u and v); 0: no fit */
};

struct glint_shade_cache {
	const struct glint_model *model;
	const struct glint_envmap *env;
	/* The split of the map, and the irradiance of the non-hot texels
	 * for constant 1/pi lobes. */
	const struct glint_shade_light *light;
	const struct glint_env_hot *hot;     /* light->hot */
	struct glint_shade_light *own_light; /* when not shared */
	int lambert[GLINT_MAX_PARAMS];	     /* lobe j is the constant 1/pi */
	int n, spp, nl, nb, nthreads, no_footprint;
	/* The parameters the footprint's blend is taken at when fixed
	 * (glint_shade_cache_fix_footprint()), else each shading's own. */
	int foot_fixed;
	double foot_p[GLINT_MAX_PARAMS];
	int32_t *pix;
	struct cache_hit *hits;	   /* n * spp */
	struct cache_foot *feet;   /* n */
	struct env_sample *envs;   /* n * spp * nl */
	uint32_t (*lobe_sobol)[2]; /* spp nb Sobol points, unshifted */
	double *static_lobes;	   /* n * nlobes * 3, constant lobes only */
	/* A joint cache (glint_shade_cache_join()): its pixels are the
	 * parts' in order; part_of[i] is pixel i's part, part_off[k] part
	 * k's first pixel.  None of the fields above is set. */
	struct glint_shade_cache **parts;
	int nparts;
	unsigned short *part_of;
	int *part_off;
};

/*
 * A near-mirror's lobe samples spread over the pixel (lobes_pixels()):
 * lobe sample k of hit s is taken at the footprint's point q = k spp + s
 * of a stratified set of spp nb points, weight w (the rest, 1 - w, at the
 * hit itself).
 */
struct spread {
	const struct cache_foot *f;
	double w, shift[2];
	uint32_t perm;
	int s;
};

static inline struct vec3 fv(const float f[3])
{
	return v3(f[0], f[1], f[2]);
}

static inline struct vec3 local_to_world(const struct cache_hit *h,
					 struct vec3 v)
{
	return v3_add(v3_add(v3_scale(fv(h->t), v.x), v3_scale(fv(h->b), v.y)),
		      v3_scale(fv(h->n), v.z));
}

static inline double angle(struct vec3 a, struct vec3 b)
{
	return acos(fmin(1, fmax(-1, v3_dot(a, b) / (v3_len(a) * v3_len(b)))));
}

/* angle() to 2e-9 rad without libm (glint_fast_acos()): for the hot
 * clusters' culls, bounds with a texel and more of margin, per hit. */
static inline double angle_fast(struct vec3 a, struct vec3 b)
{
	return glint_fast_acos(glint_clamp(
		v3_dot(a, b) / sqrt(v3_dot(a, a) * v3_dot(b, b)), -1, 1));
}

/*
 * The functions below add lobe j's estimate to out and, where dout is not
 * NULL, its derivative by the model's factor parameter (struct
 * glint_fit_lobes' factor_param, an ior) on the same samples to dout.
 */

/* Lobe j over the hot texels, on their fixed points: the map's
 * radiance on the hot texels' area (by_area: with the irradiance of the
 * other texels) or the hot texels' part of the radiance wherever it
 * reaches (with lobe and env samples of the rest: envmap.h). */
void shade_hot_quadrature(const struct glint_shade_cache *c,
			  const struct cache_hit *h, const double *p, int j,
			  int by_area, double out[3], double *dout);

/*
 * Estimate lobe j's integral at one hit: nl env samples, nb lobe samples,
 * balance-heuristic weights with the smooth light pdf.  The lobe samples'
 * uniforms: for hit hs >= 0 of its pixel, block hs of a Sobol sequence
 * shifted by the pixel's seed pseed (as draw_env_samples()); for hs < 0
 * (constant lobes at set-up), the pairs u[k] shifted by the hit's seed.
 * env samples come from `es`, or are drawn afresh when es is NULL.
 */
void shade_lobe_at_hit(const struct glint_shade_cache *c,
		       const struct cache_hit *h, const struct env_sample *es,
		       int nl, int nb, const double (*u)[2], const double *p,
		       int j, int with_hot, const struct spread *sp, int hs,
		       uint32_t pseed, double out[3], double *dout);

/*
 * Fit pixel pix's footprint to its spp hits g (least squares over their
 * positions in the pixel; glint_gbuffer_pixel_sample() places them as the
 * tracer did).  Fewer than 3 hits, or hits in a line: no footprint (turn 0).
 */
void shade_foot_fit(const struct glint_gbuffer *gb, int32_t pix,
		    const struct glint_hit *g, struct cache_foot *f);

/*
 * Lobe j's hot part over pixel i where the lobe is narrow against the
 * pixel's turn of mirror direction: a near-mirror's sun covers part of a
 * pixel, which the hits' few points alias.  The lobe is widened by the
 * spread of the hot texels' quadrature points (so that they integrate
 * the texels' area, not points of light) and integrated on a grid whose
 * cells turn by at most its width, blending two levels so that the
 * result stays continuous in the parameters.  The levels (and whether
 * the lobe is narrow enough for the grid) are taken at pf, p itself or
 * the blend's fixed parameters (glint_shade_cache_fix_footprint()); the
 * lobe is shaded at p.  Returns 0 (out untouched) when the lobe is wide
 * enough for the hits' own points (shade_hot_quadrature()).
 */
int shade_hot_footprint(const struct glint_shade_cache *c, int i,
			const double *p, const double *pf, int j, double out[3],
			double *dout);

/* How many times (log2) pixel i's mirror direction turns across it by
 * lobe j's width at p; -1 without a footprint. */
double shade_foot_level(const struct glint_shade_cache *c, int i,
			const double *p, int j);

/*
 * The lobe samples are spread over the footprint (shade_lobe_at_hit()'s
 * spread) as the lobe narrows from 2^SPREAD_FROM of the pixel's turn of
 * mirror direction to 2^(SPREAD_FROM - 1), blended between so that the
 * objective stays continuous.  Where the lobe is under about two turns
 * the highlight's profile bends within a pixel, and the hits' 2 x 2
 * points misjudge its area: aluminium bronze under studio.exr's
 * softboxes (roughness 0.023; a turn 0.7 of the lobe's width at the
 * sphere's centre, more toward the rim), at the truth
 * and 64 + 64 samples, differed from the reference photo by 2.8 times
 * the photo's own noise (squared, red), by 1.7 times spread from 2
 * turns (bench/residual; 16 hits a pixel: 1.0).
 */
#define SPREAD_FROM 1

/* A lobe whose core is at least this many texels wide integrates the
 * map's hot part on one point a texel, widened by the spread within a
 * texel those points leave out (shade_hot_quadrature()): at 6 texels the
 * fourth-order error is under 1e-4 of the sun's part. */
#define HOT_COARSE_TEXELS 6

#endif
