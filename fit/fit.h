/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_FIT_H
#define GLINT_FIT_FIT_H

/*
 * Recover a model's parameters from one HDR image of the sphere: minimise
 * the (weighted) sum of squared differences between render and photo over
 * the pixels wholly on the sphere.
 *
 * Methods:
 *   three-pass (Joshi & Jensen): 1. diffuse only from 0.5 on the diffuse
 *     mask; 2. specular, roughness, ior from 0.5, 0.075, 1.5 on the
 *     specular mask (diffuse held); 3. everything from there, all pixels.
 *     The specular mask: pixels whose ratio photo / (render of a 100 %
 *     white Lambertian sphere) exceeds the median ratio by more than a
 *     threshold (the paper compares with the white render itself, which a
 *     dark glossy material never exceeds; docs/fitting.md).
 *   naive: every parameter at once from the paper's initial values.
 *   varpro: variable projection: for given nonlinear parameters (roughness,
 *     ior) the albedos follow from a bounded linear least-squares problem
 *     per channel; LM runs on the nonlinear ones only, from the best of a
 *     coarse scan of roughness.
 * Evaluation: the shade cache (trace once, re-shade), or with `faithful`
 * the paper's way, a full trace and render per evaluation (the baseline).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: a fit runs on its own worker threads
 * (opts.nthreads) and is called from one thread.  Who frees: nothing (a
 * result is a value; the renderer stays the caller's).
 */

#include "fit/optim/lm.h"
#include "fit/optim/uncertainty.h"
#include "fit/render/render.h"
#include "fit/render/shade_cache.h"

#include <stdint.h>

enum glint_fit_method {
	GLINT_FIT_THREE_PASS,
	GLINT_FIT_NAIVE,
	GLINT_FIT_VARPRO,
};

/* "three-pass", ...: static strings. */
const char *glint_fit_method_name(enum glint_fit_method m);
int glint_fit_method_parse(const char *s, enum glint_fit_method *m);

/* lm: Levenberg-Marquardt (the method's passes); anneal: adaptive
 * simulated annealing (fit/optim/anneal.h) then an LM polish; auto: anneal for
 * transparent models, LM otherwise. */
enum glint_fit_optimizer { GLINT_OPT_AUTO, GLINT_OPT_LM, GLINT_OPT_ANNEAL };
/* Their names, indexed by the enums, NULL-terminated. */
extern const char *const glint_fit_method_names[];
extern const char *const glint_fit_optimizer_names[];
int glint_fit_optimizer_parse(const char *s, enum glint_fit_optimizer *o);

/* Weights when no weight image is given. */
enum glint_fit_weighting {
	/* variance ~ signal + 10 % of the mean signal (shot noise): the
	 * brightest highlight pixels do not swamp the rest */
	GLINT_WEIGHT_POISSON,
	/* plain sum of squared differences (the paper) */
	GLINT_WEIGHT_UNIFORM,
};

/* A compact light source of the map whose flux is uncertain (a probe's
 * env-sources.json: capture/probe/probe_sources.h), in the map's frame. */
struct glint_fit_light_source {
	double dir[3];	      /* unit, the map's frame */
	double radius_deg;    /* the map's texels within this angle are its */
	double flux[3];	      /* integral of L d(omega), the map's units */
	double flux_sigma[3]; /* its standard uncertainty, per channel */
	int saturated;	      /* clipped in the probe: its flux a lower bound */
	int view;	      /* the photo (of a joint fit) whose probe it is */
};

struct glint_fit_opts {
	enum glint_fit_method method;
	enum glint_fit_weighting weighting;
	int coarse_to_fine;    /* fit a subsampled pixel set first */
	int faithful;	       /* full trace + render per evaluation */
	double mask_threshold; /* photo / white above (1 + t) x median */
	int max_pixels;	       /* cap on fitted pixels (every s-th pixel) */
	/* Shade cache: env and lobe samples per hit; 0 (the default): 32 a
	 * pixel over the scene's hits (glint_fit_resolve_samples()). */
	int light_samples;
	int lobe_samples;
	int static_samples; /* shade cache: for constant lobes */
	int max_samples;    /* ... light (and lobe) samples per hit the fit
			     * may raise them to where its own sampling noise
			     * limits the answer (intervals.c); 0 (the
			     * default): 256 a pixel over the hits */
	int no_footprint;   /* shade cache: near-mirrors' hot texels on
			     * the hits, not over pixels (benchmarks) */
	int max_iter;	    /* per LM pass */
	enum glint_fit_optimizer optimizer;
	uint64_t seed;	     /* annealing's random stream */
	int anneal_evals;    /* annealing's budget */
	const double *start; /* initial values (NULL: the method's own, the
				paper's) */
	int no_start_scan;   /* LM from the start as given, without the
				roughness scan (fit.c, scan_start): for the
				stability study's failure cases */
	/* Independent sample sets of the shade cache whose spread gives the
	 * fitter's own Monte Carlo error (fit/optim/uncertainty.h); 0: none
	 * (the intervals then ignore it). */
	int mc_draws;
	/* LM iterations of the polish on the sample sets' mean (default
	 * 2; docs/fitting.md, "Uncertainty") */
	int polish_iter;
	double level; /* of the reported intervals (0.95) */
	/* leave out the systematic term (the fast render's accuracy against
	 * the reference renderer: fit.c, systematic()) */
	int no_systematic;
	/* leave out the model-error jackknife a structured residual adds
	 * (fit/optim/uncertainty.h) */
	int no_model_error;
	/* leave out the model-discrepancy term a structured residual adds
	 * (fit.c, discrepancy(); its calibration: bench/misfit) */
	int no_discrepancy;
	/* the relative standard uncertainty of the light's radiance per
	 * channel (the scene's environment.scale_sigma; the largest of a
	 * joint fit's photos): a lobe albedo of channel c gains
	 * |albedo| x light_scale_sigma[c] (the photo is linear in the light
	 * and in the albedos together) */
	double light_scale_sigma[3];
	/* The maps' compact sources with their flux's uncertainty, each with
	 * the photo whose map holds it (fit/light_sources.c): each one's part
	 * of every parameter's standard error joins its systematic part. */
	const struct glint_fit_light_source *sources;
	int nsources;
	/* How finely the map resolves the light, which sizes the systematic
	 * roughness and specular terms (fit/discrepancy.c): 0, the map is
	 * the light itself (no probe's record); > 0, the angle in degrees a
	 * pixel of the probe it was unwrapped from spans (its sources file's
	 * map_pixel_deg; a joint fit's coarsest); < 0, unwrapped from a
	 * probe of unknown resolution. */
	double map_pixel_deg;
	/* leave the sampling lean in the answer (fit.c, remove_lean();
	 * benchmarks' comparison) */
	int keep_lean;
	/* glint_fit_evaluate(): the weights from the noise model at these
	 * parameters' prediction (a fit's result: its own objective at
	 * other parameters); NULL: at the evaluated parameters */
	const double *weights_at;
	int nthreads;
	/* Called as passes run (may be NULL). */
	void (*progress)(void *ctx, const char *pass, int iter, double cost);
	void *progress_ctx;
};

void glint_fit_default_opts(struct glint_fit_opts *o);

/*
 * o with its automatic sample counts (0) resolved for spp primary hits a
 * pixel: light and lobe samples 32 a pixel and max_samples 256 a pixel,
 * shared by the hits when there are more than 4 (at least 1 each), a
 * quarter of it a hit when there are 4 or fewer; a count given (positive)
 * is kept.  A pixel's estimate averages all of its hits' samples, so its
 * noise follows their total: a blurred camera's 16 hits a pixel
 * (fit/scene/scene.c) take 2 env and 2 lobe samples each, the 32 a pixel
 * that 4 hits take at 8.
 */
void glint_fit_resolve_samples(struct glint_fit_opts *o, int spp);

/* The light sources whose flux the fit's intervals carry: at most. */
#define GLINT_FIT_MAX_SOURCES 8

#define GLINT_FIT_MAX_PASSES 8

/* A joint fit's photos of one material (glint_fit_views()): at most. */
#define GLINT_FIT_MAX_VIEWS 16

/* One photo of a joint fit: its scene's renderer (traced already), the
 * photo (the camera's size) and its weights (may be NULL). */
struct glint_fit_view {
	struct glint_renderer *r;
	const struct glint_image *photo;
	const struct glint_image *weight;
};

/* glint_fit_resolve_samples() for the most hits a pixel of the views'
 * scenes. */
void glint_fit_resolve_samples_views(struct glint_fit_opts *o,
				     const struct glint_fit_view *views,
				     int nviews);

/* How the result fits one photo (the fields of glint_fit_result of the
 * same names, over that photo's pixels). */
struct glint_fit_view_stats {
	int pixels, interior;
	double wcost, rmse, rel_rmse;
	double backdrop_rel_rmse, flat_rel_rmse, noise_rmse;
};

struct glint_fit_pass {
	char name[32];
	int pixels;
	int iterations;
	int evaluations;
	double cost0, cost;
	double seconds;
};

struct glint_fit_result {
	const struct glint_model *model;
	double p[GLINT_MAX_PARAMS];
	double se[GLINT_MAX_PARAMS]; /* = unc.se: INFINITY if unseen */
	int at_bound[GLINT_MAX_PARAMS];
	/* Intervals, covariance and how they were made: noise over spatial
	 * blocks of pixels plus the fitter's Monte Carlo spread. */
	struct glint_uncertainty unc;
	double unc_seconds;
	double cost;	 /* 1/2 weighted SSD at the end (fitted pixels) */
	double wcost;	 /* the same cost, recomputed over every pixel */
	double rmse;	 /* unweighted, over the fitted pixels */
	double rel_rmse; /* rmse / mean photo value there */
	double backdrop_rel_rmse; /* the same for the bare backdrop */
	double flat_rel_rmse;	  /* ... for a flat disc of the photo's mean */
	double noise_rmse; /* what noise alone leaves (NAN: no noise model) */
	/* The shade caches' samples per hit at the end: o's, or more where
	 * the sample sets disagreed by more than the photo's noise, and that
	 * variance ratio (largest over the parameters) at the last check */
	int light_samples, lobe_samples;
	double mc_over_noise;
	/* ... and per value: the sets' variance over the residual's */
	double model_noise;
	/* ... and the largest measured sampling lean over the noise's
	 * standard error */
	double lean_over_noise;
	/* The sampling lean taken off each parameter (p is the fit's
	 * optimum minus its estimated lean; fit.c, remove_lean()) */
	double lean_removed[GLINT_MAX_PARAMS];
	/* The part of the relative RMSE the residual's structure makes (the
	 * regions' mean residuals, less their noise: about 0 for the right
	 * model); and the model-discrepancy standard uncertainty it gave
	 * each parameter (fit.c, discrepancy()), in se */
	double misfit_share;
	double discrepancy[GLINT_MAX_PARAMS];
	/* the fast render's gain error per misfit region, as this photo's
	 * residual shows it, in each parameter (fit/render_gain.c), and the
	 * part of the systematic standard error it gives (FIT_GAIN_COVER
	 * times it) */
	double render_gain[GLINT_MAX_PARAMS];
	double render_gain_stderr[GLINT_MAX_PARAMS];
	/* the light scale's standard uncertainty in each parameter
	 * (opts.light_scale_sigma), and the sigma it came from */
	double light_stderr[GLINT_MAX_PARAMS];
	double light_scale_sigma[3];
	/* each of opts.sources' part of each parameter's standard error
	 * (0 for a saturated one, whose flux has no sigma) */
	int nsources;
	struct glint_fit_light_source source[GLINT_FIT_MAX_SOURCES];
	double source_stderr[GLINT_FIT_MAX_SOURCES][GLINT_MAX_PARAMS];
	int pixels;   /* pixels in the final pass */
	int interior; /* pixels wholly on the sphere */
	int specular_pixels;
	struct glint_fit_pass passes[GLINT_FIT_MAX_PASSES];
	int npasses;
	/* Per photo (one for glint_fit()); the fields above are over all. */
	int nviews;
	struct glint_fit_view_stats view[GLINT_FIT_MAX_VIEWS];
	double seconds;
	double setup_seconds;
};

/*
 * Fit `model` to `photo` (the camera's size) seen in the scene of r (traced
 * already).  weight (same size, may be NULL for all ones) gives per-pixel,
 * per-channel weights, 0 for saturated or invalid pixels; non-finite photo
 * values get weight 0 too.
 */
/* The transparent models' fitter (fit_dielectric.c), which glint_fit()
 * hands them to. */
int glint_fit_dielectric(struct glint_renderer *r,
			 const struct glint_model *model,
			 const struct glint_image *photo,
			 const struct glint_image *weight,
			 const struct glint_fit_opts *o, const double *start,
			 const double *eval_p, struct glint_fit_result *res);

int glint_fit(struct glint_renderer *r, const struct glint_model *model,
	      const struct glint_image *photo, const struct glint_image *weight,
	      const struct glint_fit_opts *o, struct glint_fit_result *res);

/*
 * One material fitted to several photos of it at once (different lights,
 * probes or turntable positions): the objective is the sum of each
 * photo's, every photo shaded in its own scene, and the intervals come
 * from all of them (blocks of pixels are each photo's own).  Each photo
 * gets up to o->max_pixels pixels.  res->view[] says how the result fits
 * each photo.  Needs the shade cache: not with o->faithful, and not for
 * transparent models.  nviews 1 is glint_fit().
 */
int glint_fit_views(const struct glint_fit_view *views, int nviews,
		    const struct glint_model *model,
		    const struct glint_fit_opts *o,
		    struct glint_fit_result *res);

/*
 * The objective of glint_fit() at given parameters p, without fitting,
 * on the fit's terms (weights from the noise model at the prediction,
 * the mean of the same sample sets): fills res->rmse, rel_rmse, wcost,
 * pixels and interior (and p).  For judging a
 * fit against the truth, or a material against a photo.
 */
int glint_fit_evaluate(struct glint_renderer *r,
		       const struct glint_model *model,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, const double *p,
		       struct glint_fit_result *res);

/*
 * The model discrepancy's scale of parameter k at p (fit.c,
 * discrepancy()): a lobe's albedo channel the larger of its own value and
 * its lobe's mean channel (energy a misfit moves between lobes moves in
 * every channel alike, so a dark channel moves as far as the others), any
 * other parameter its own magnitude.  *cls gets its class: 0 diffuse
 * albedo, 1 specular albedo, 2 roughness, 3 other.  bench/misfit
 * calibrates the coefficient per class with it.
 */
double glint_fit_discrepancy_scale(const struct glint_model *m, const double *p,
				   int k, int *cls);

/* The upper bound glint reports for a roughness whose interval reaches
 * below the photo's pixel footprint (its interval's top or the
 * footprint, the larger), or NAN when the roughness is reported as a
 * value (params.json's "upper_bound"; its interval is then from the
 * model's lowest roughness to the bound; docs/fitting.md, "What one
 * image determines"). */
double glint_fit_roughness_bound(const struct glint_fit_result *r);

#endif
