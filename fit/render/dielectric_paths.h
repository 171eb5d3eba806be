/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_DIELECTRIC_PATHS_H
#define GLINT_FIT_RENDER_DIELECTRIC_PATHS_H

/*
 * A transparent sphere: a smooth dielectric interface (exact unpolarised
 * Fresnel, Snell refraction, total internal reflection) around an
 * absorbing interior, lit by the distant environment map.
 *
 * Transmission (docs/conventions.md): T_c is the fraction of light of
 * channel c that survives one traversal of the sphere's diameter d inside
 * the material, Beer-Lambert with sigma_c = -ln(T_c) / d; a path that runs
 * a length L inside is attenuated by exp(-sigma_c L) = T_c^(L / d).
 * Interface losses (Fresnel) are not part of T.
 *
 * Every primary-ray sample on the sphere splits deterministically at each
 * interface into its reflected and refracted parts (no random choice), each
 * followed with Embree until it leaves the sphere or its weight (the
 * product of Fresnel factors, an upper bound of its share of the pixel
 * whatever T) falls below min_weight; the path then ends in one env-map
 * lookup.  For a fixed ior the paths - their Fresnel weights, their lengths
 * inside and the radiance where they leave - do not depend on T, so they
 * are kept (a path cache) and a change of T is a re-sum:
 *   I_c = 1/spp * sum over paths  w * T_c^(L / d) * L_env,c.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: a cache is built by one thread, then
 * read by many.  Who frees: glint_dielectric_cache_free().
 */

#include "fit/scene/envmap.h"
#include "tracer.h"

#include "core/image.h"
#include "core/optics.h"

struct glint_dielectric_opts {
	double min_weight; /* drop a branch below this Fresnel weight */
	int max_depth;	   /* interfaces per path, a safety cap */
};

void glint_dielectric_default_opts(struct glint_dielectric_opts *o);

/* One path's contribution before absorption. */
struct glint_dpath {
	float w;      /* product of Fresnel factors (and 1/spp) */
	float len;    /* length inside, in diameters */
	float rgb[3]; /* env radiance where it leaves */
};

struct glint_dielectric_cache {
	int n;		/* pixels */
	int32_t *pix;	/* their indices y * width + x */
	int64_t *first; /* n + 1 offsets into paths */
	struct glint_dpath *paths;
	int64_t npaths;
	double ior;
	double dropped; /* largest weight of a dropped branch */
	int max_depth_seen;
};

/*
 * Trace the paths of pixels pix[0..n) of gb (all of a pixel's primary
 * samples, misses included: they see the map) for a sphere (centre,
 * radius) of index ior.  tracer holds the sphere.
 */
int glint_dielectric_trace(struct glint_tracer *tracer,
			   const struct glint_gbuffer *gb, const int32_t *pix,
			   int n, const struct glint_envmap *env,
			   struct vec3 centre, double radius, double ior,
			   const struct glint_dielectric_opts *o, int nthreads,
			   struct glint_dielectric_cache *out);
void glint_dielectric_cache_free(struct glint_dielectric_cache *c);

/* The re-sum: rgb[3 * i + c] for pixel i under transmission T[3]. */
void glint_dielectric_shade(const struct glint_dielectric_cache *c,
			    const double T[3], double *rgb);

/* A whole image of the sphere of params (T r, g, b, ior) into out (and
 * the fraction of each pixel's samples on the sphere into cov, may be
 * NULL); misses see the map. */
int glint_dielectric_render(struct glint_tracer *tracer,
			    const struct glint_gbuffer *gb,
			    const struct glint_envmap *env, struct vec3 centre,
			    double radius, const double *p, int nthreads,
			    struct glint_image *out, struct glint_image *cov);

/* d(rgb)/dT_c: the same sum with w T^(L - 1) L (channel c only). */
void glint_dielectric_dshade(const struct glint_dielectric_cache *c,
			     const double T[3], double *drgb);

#endif
