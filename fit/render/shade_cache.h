/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_SHADE_CACHE_H
#define GLINT_FIT_RENDER_SHADE_CACHE_H

/*
 * The fitter's fast path: trace once, re-shade only.
 *
 * For a model that is linear in its RGB albedos (model->bxdf->nlobes > 0) a
 * pixel's radiance is  I = sum_j albedo_j * A_j(p),  where
 *   A_j = integral of L(wi) b_j(wo, wi; p) cos(theta_i) dwi
 * (RGB, averaged over the pixel's primary samples).  Lobes that depend on
 * no parameter (the diffuse one) are integrated once, with many samples.
 * The others are re-estimated per evaluation on fixed sample sets (common
 * random numbers): env-map samples with fixed directions, and lobe samples
 * whose fixed uniforms are mapped through the current parameters, combined
 * by the balance heuristic with a continuous light pdf in the weights.  So
 * the estimate is a deterministic, continuous function of the parameters,
 * which Levenberg-Marquardt needs.
 *
 * The env map's few brightest texels (a sun: glint_env_hot_new) are not
 * sampled but integrated for every hit on fixed points, skipped where the
 * lobe cannot reach them: the highlight, which carries most of what the
 * photo says about roughness, is then exact rather than the noisiest part.
 * Where a lobe is narrower than a pixel's turn of mirror direction (a
 * near-mirror), the hot texels are integrated over the pixel's footprint
 * on a grid instead, the lobe widened by their quadrature points'
 * spacing: a sun covers part of such a pixel, which the hits alias.
 *
 * The cache holds a chosen set of pixels (e.g. the sphere's interior, or a
 * coarse subset of it).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: built on its own threads, then
 * evaluated by one caller at a time (each evaluation spreads over the
 * cache's threads); a light may be shared by caches.  Who frees:
 * glint_shade_cache_free(), glint_shade_light_free().
 */

#include "fit/scene/envmap.h"
#include "fit/brdf/model.h"
#include "irradiance.h"
#include "tracer.h"

struct glint_shade_cache;

struct glint_shade_cache_opts {
	int light_samples;  /* fixed env samples per hit (varying lobes) */
	int lobe_samples;   /* fixed lobe samples per hit (varying lobes) */
	int static_samples; /* per hit and technique for constant lobes */
	int no_hot;	    /* sample the env map's brightest texels too */
	/* Hot texels on the hits' points even where the lobe is narrower
	 * than a pixel's turn of mirror direction (the footprint integral
	 * off: benchmarks' previous path). */
	int no_footprint;
	/* Sample-set seed: caches with different seeds are independent
	 * Monte Carlo estimates of the same integrals (0: glint's fixed
	 * sets). */
	uint32_t seed;
	int nthreads;
	/* What the caches of one map share (glint_shade_light_new()),
	 * borrowed: it must outlive them.  NULL: the cache makes its own. */
	const struct glint_shade_light *light;
};

/* The map's split into hot texels and the rest (no_hot honoured) and the
 * rest's irradiance, which every cache of the map reads. */
struct glint_shade_light {
	struct glint_env_hot *hot;
	struct glint_irradiance irr;
	/* Half the spacing of the hot texels' quadrature points (radians):
	 * the Gaussian that makes them integrate the texels' area. */
	double spread;
};
int glint_shade_light_new(const struct glint_envmap *env,
			  const struct glint_shade_cache_opts *opts,
			  struct glint_shade_light **out);
void glint_shade_light_free(struct glint_shade_light *l);

/*
 * Build a cache for pixels pix[0..n) (indices y * width + x of gb) that
 * are wholly covered by the sample.  The env map and model must outlive
 * the cache; gb and pix are copied from.  *out is the caller's, freed with
 * glint_shade_cache_free().
 */
int glint_shade_cache_new(const struct glint_gbuffer *gb, const int32_t *pix,
			  int n, const struct glint_envmap *env,
			  const struct glint_model *model,
			  const struct glint_shade_cache_opts *opts,
			  struct glint_shade_cache **out);
void glint_shade_cache_free(struct glint_shade_cache *c);

/*
 * One cache over several scenes' pixels (a joint fit of several photos
 * of one material): its pixels are parts[0]'s, then parts[1]'s, ...;
 * each is shaded in its own scene.  The parts (same model) become the
 * joint cache's, freed with it, and on failure here.
 */
int glint_shade_cache_join(struct glint_shade_cache **parts, int nparts,
			   struct glint_shade_cache **out);

/*
 * Lobe integrals for parameters p: lobes[(i * nlobes + j) * 3 + c] for
 * pixel i, lobe j, channel c.  Only varying lobes are recomputed.
 * lobes has n * nlobes * 3 doubles.
 */
void glint_shade_cache_lobes(struct glint_shade_cache *c, const double *p,
			     double *lobes);

/* The same for the cached pixels sel[0..nsel) only; lobes is indexed by
 * position in sel. */
void glint_shade_cache_lobes_sel(struct glint_shade_cache *c, const double *p,
				 const int *sel, int nsel, double *lobes);

/* The same with each lobe's derivative by the model's factor parameter
 * (struct glint_fit_lobes' factor_param, an ior), shaded on the same
 * samples, in dlobes (laid out as lobes; constant lobes 0).  Only for a
 * model with factor_dlog: dlobes is left untouched otherwise. */
void glint_shade_cache_lobes_d(struct glint_shade_cache *c, const double *p,
			       const int *sel, int nsel, double *lobes,
			       double *dlobes);

/*
 * The footprint's blends (the share of a near-mirror's lobe samples
 * spread over the pixel, and the hot texels' grid levels, both following
 * the lobe's width against the pixel's turn of mirror direction) taken
 * at parameters p from now on, rather than at each shading's own; NULL:
 * at each shading's own again.  A blend that follows the roughness gives
 * the objective a slope of its own (the blend's rate times the
 * difference of the estimates it blends), which a solve follows: the
 * sample sets' polish fixes them at its start (docs/fitting.md).  A
 * joint cache fixes its parts'.
 */
void glint_shade_cache_fix_footprint(struct glint_shade_cache *c,
				     const double *p);

/* The constant lobes alone (the varying ones 0), which depend on no
 * parameter: integrated once when the cache was built. */
void glint_shade_cache_constant_lobes_sel(struct glint_shade_cache *c,
					  const int *sel, int nsel,
					  double *lobes);

#endif
