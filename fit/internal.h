/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_INTERNAL_H
#define GLINT_FIT_INTERNAL_H

/*
 * What fit/'s parts share (private): the objective, the pixel selections
 * and the functions one part calls in another.  Every function here
 * works on one struct objective from one thread at a time (the
 * renders inside use the objective's own worker threads); errors are
 * negative errno values with glint_error_msg() set.
 */

#include "fit/fit.h"
#include "fit/fit_data.h"
#include "fit/misfit.h"
#include "fit/optim/lm.h"
#include "fit/optim/uncertainty.h"

#define MAX_SETS 16

/* One photo of the fit: its scene, and its pixels [off, off + n) of the
 * joint data (glint_fit_views()). */
struct view {
	struct glint_renderer *r;
	int off, n;
	int interior, stride, frame_x, frame_y;
	struct glint_shade_light *light; /* its map's, shared by its caches */
};

/* What one LM pass optimises. */
struct objective {
	struct glint_renderer *r;
	struct glint_shade_cache *cache; /* NULL: faithful full renders */
	const struct glint_model *m;
	const struct fit_data *d;
	const int *sel;
	int nsel;
	double p[GLINT_MAX_PARAMS]; /* all parameters; free ones overwritten */
	int nfree;
	int free_idx[GLINT_MAX_PARAMS];
	int varpro;	 /* free = nonlinear only; albedos solved inside */
	double rough_lo; /* lower bound on the roughness parameter (coarse) */
	/* which parameters are lobe albedos: lobe and channel, else -1 */
	int lobe_of[GLINT_MAX_PARAMS], chan_of[GLINT_MAX_PARAMS];
	/* memo of lobe integrals at the nonlinear parameters memo_p, and
	 * (memo_d) their derivatives by the model's factor parameter in
	 * dlobes (fit_wants_dlobes()) */
	double *lobes, *lobes2, *dlobes;
	double memo_p[GLINT_MAX_PARAMS];
	int memo_valid, memo_d;
	/* the cache and selection the memo was shaded on (a cache or a
	 * selection freed and made anew clears memo_valid) */
	const struct glint_shade_cache *memo_cache;
	const int *memo_sel;
	int memo_nsel;
	/* faithful path */
	const struct glint_fit_opts *o;
	struct glint_image *img;
	int evals;
	/* independent sample sets of the final estimate (sets[0] = cache;
	 * the others owned), whose mean the statistics use */
	struct glint_shade_cache *sets[MAX_SETS];
	int nsets;
	/* each set's lobes at its last evaluation (sets_residuals()), at
	 * the nonlinear parameters set_lobes_p, for the sets' Jacobians */
	double *set_lobes[MAX_SETS], *set_dlobes[MAX_SETS];
	double set_lobes_p[MAX_SETS][GLINT_MAX_PARAMS];
	int set_has_d[MAX_SETS];
	/* each set's own Jacobian (rows x nfree, one set after another) at
	 * the parameters set_jac_p, from the sets' polish's last
	 * linearisation (fit_refine_on_sets()); set_jac_n sets of it hold,
	 * 0 when none */
	double *set_jac;
	size_t set_jac_size;
	double set_jac_p[GLINT_MAX_PARAMS];
	int set_jac_n;
	struct view views[GLINT_FIT_MAX_VIEWS];
	int nviews;
	/* The sets' mean weighted residuals at the final p over every
	 * fitted pixel (uncertainty()), which the statistics reuse */
	double *final_r;
	int final_rows;
	/* the shade caches' light and lobe samples are o's times this
	 * (raised when the sample sets disagree by more than the noise) */
	int sample_scale;
	/* the sampling lean taken off each parameter (remove_lean()) and
	 * the variance that adds */
	double lean_fix[GLINT_MAX_PARAMS], lean_var[GLINT_MAX_PARAMS];
	/* the fast render's gain term in each parameter (fit_render_gain()
	 * times FIT_GAIN_COVER; none on roughness), 0 until the residual's
	 * regions are known */
	double gain_sys[GLINT_MAX_PARAMS];
	double mc_over_noise; /* the largest such ratio at the last check */
	/* the largest measured sampling lean over the noise's standard
	 * error at the last check */
	double lean_over_noise;
	double model_noise; /* the sets' variance over the residual's */
};

struct progress_ctx {
	const struct glint_fit_opts *o;
	const char *pass;
};

/* The pixel sets the passes run on, as indices into the fit's pixels. */
struct selections {
	int *all, *coarse, *spec, *diff;
	int nall, ncoarse, nspec, ndiff;
};

/*
 * The fit methods, one interface and one file each (method_*.c): a method
 * is its coarse stage (what it optimises on the coarse pixel set, from the
 * objective's start, with fit_run_pass() and fit_scan_start()) and whether
 * its fine pass solves the linear parameters exactly.  methods.c indexes
 * them by enum glint_fit_method (named as glint_fit_method_names);
 * annealing is the coarse stage --optimizer anneal puts in place of any
 * method's.  Adding one: a method_*.c defining its struct fit_method, an
 * enum value and name (fit.h), its line in methods.c and fit/meson.build.
 */
struct fit_method {
	int (*coarse)(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res);
	int linear_fine; /* the fine pass projects out the albedos */
};

extern const struct fit_method fit_method_three_pass;
extern const struct fit_method fit_method_naive;
extern const struct fit_method fit_method_varpro;
extern const struct fit_method fit_method_anneal;

/* Each of o->sources' part of every parameter's standard error at the
 * optimum ob->p (fit/light_sources.c), into res->source_stderr, from the
 * Jacobian jac (3 ob->nsel x nparams) over the selection; a single photo
 * only.  Returns 0 or a negative errno. */
int fit_source_terms(struct objective *ob, const double *jac,
		     struct glint_fit_result *res);

/* (J^T J)^-1 of the weighted Jacobian jac (rows x n, n <= GLINT_UNC_MAX_N)
 * into ainv, with unseen[k] 1 where J cannot see parameter k
 * (glint_unc_normal_inverse()), for carrying a change of the residuals
 * to the optimum (A^-1 J^T c).  Returns 0 or a negative errno. */
int fit_jtj_inverse(const double *jac, int rows, int n, double *ainv,
		    int *unseen);

/* The fast render's error as a gain per misfit region (fit/render_gain.c):
 * each parameter's standard uncertainty from the gain error of the
 * varying lobes' render each region's residual shows (region: per
 * residual row, -1 for none), carried to the optimum, into term
 * (nparams; 0 where not known: no shade cache).  Returns 0 or a negative
 * errno. */
int fit_render_gain(struct objective *ob, const double *jac, const double *r,
		    const int *region, double *term);

/* What the intervals take of fit_render_gain()'s term on the albedos and
 * ior: this many times it (fit/render_gain.c says how it was measured). */
#define FIT_GAIN_COVER 3.0

/* The largest sampling lean, in standard errors of the noise, that the
 * fit takes off to first order rather than raise its samples
 * (fit/intervals.c, more_samples()). */
#define FIT_LEAN_OVER_NOISE 0.5

/* The factor (a power of two, 1: none) to raise samples (light samples
 * per hit now) by, from the sets' Monte Carlo variance over the noise's
 * per parameter, their variance over the residual's per value and the
 * measured lean over the noise's standard error, so that all three fall
 * under their limits (1, 0.25, FIT_LEAN_OVER_NOISE), as far as cap
 * allows (fit/intervals.c, more_samples()). */
int fit_samples_factor(double mc_over_noise, double model_noise,
		       double lean_over_noise, int samples, int cap);

/* The systematic terms that grow as the photos get coarse (fit_systematic(),
 * fit/discrepancy.c says how they were measured): roughness's floor in
 * m^2, FIT_SYS_LIGHT_FLOOR times the square of the probe's pixel angle
 * (radians), squared; the varying lobes' albedos' relative term
 * FIT_SYS_SMALL / R^4 on a sphere R pixels in radius, shared with ior
 * along the specular/ior ridge; the other shape parameters' that times
 * FIT_SYS_SMALL_SHAPE. */
#define FIT_SYS_LIGHT_FLOOR 8.0
#define FIT_SYS_SMALL	    2.2e5
#define FIT_SYS_SMALL_SHAPE 0.15
/* the smallest sphere (pixels of radius) those were measured on */
#define FIT_SYS_SMALLEST_PX 38.0

/* The coarse stage the options ask for (annealing when the optimizer is
 * annealing, else the method's; NULL for an unknown method), and a
 * method's entry by name (a valid enum value). */
const struct fit_method *fit_method_of(const struct glint_fit_opts *o);
const struct fit_method *fit_method_named(enum glint_fit_method m);

int fit_view_of(const struct objective *ob, int s);

int fit_nonlinear_same(const struct objective *ob, const double *a,
		       const double *b);

/* Whether ob's evaluations shade the derivatives by the model's factor
 * parameter (an ior) with the lobes, so that its Jacobian column needs
 * no evaluation of its own: a shade cache, the parameter free, no
 * variable projection (which needs no Jacobian). */
int fit_wants_dlobes(const struct objective *ob);

double fit_pixel_value(const struct objective *ob, const double *p,
		       const double *lobes, int s, int c);

int fit_render_full(struct objective *ob, const double *p);

int fit_obj_residuals(void *ctx, const double *q, double *res);

int fit_obj_jacobian(void *ctx, const double *q, const double *r, double *jac);

int fit_scan_start(struct objective *ob, const int *sel, int nsel);

void fit_add_pass(struct glint_fit_result *res, const char *name, int pixels,
		  int iterations, int evaluations, double cost0, double cost,
		  double t0);

void fit_objective_lm_opts(struct glint_lm_opts *lo, int max_iter,
			   struct progress_ctx *pc);

int fit_anneal_pass(struct objective *ob, const int *sel, int nsel,
		    struct glint_fit_result *res);

int fit_run_pass(struct objective *ob, const char *name, const int *sel,
		 int nsel, const int *freev, int varpro,
		 struct glint_fit_result *res, struct glint_lm_result *lr);

int fit_cmp_double(const void *a, const void *b);

double fit_median_of(double *v, int n);

void fit_baselines(const struct objective *ob, const struct fit_data *d,
		   struct glint_fit_result *res);

void fit_finish_stats(struct objective *ob, const int *sel, int nsel,
		      struct glint_fit_result *res);

void fit_selections_free(struct selections *s);

void fit_objective_free(struct objective *ob);

int fit_new_cache(const struct objective *ob, uint32_t seed,
		  struct glint_shade_cache **out);

int fit_objective_init(struct objective *ob, const struct view *views,
		       int nviews, const struct glint_model *model,
		       const struct fit_data *d,
		       const struct glint_fit_opts *o);

int fit_make_selections(struct objective *ob, struct selections *sl);

int fit_coarse_passes(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res);

int fit_fine_pass(struct objective *ob, const struct selections *sl,
		  double coarse_rough_lo, double footprint,
		  struct glint_fit_result *res);

int fit_jacobian_fd(struct objective *ob, const double *q, const double *r,
		    double *jac);

int fit_pixel_blocks(const struct objective *ob, const int *sel, int nsel,
		     int *block);

int fit_sample_sets(struct objective *ob, int more,
		    struct glint_shade_cache **sets, int *nsets);

int fit_sets_residuals(void *ctx, const double *q, double *r);

/* Set k's lobes at p (the nonlinear parameters as at its last evaluation
 * by fit_sets_residuals()) into the objective's memo, with set k as its
 * cache: its Jacobian then shades only the columns that are not
 * albedos.  Without them the memo is cleared, and shaded anew. */
void fit_set_memo(struct objective *ob, int k, const double *p);

int fit_refine_on_sets(struct objective *ob,
		       struct glint_shade_cache *const *sets, int nsets,
		       const double *lo, const double *hi, double *each,
		       double *r, double *jac, struct glint_fit_result *res);

void fit_select_all(struct objective *ob, const struct selections *sl);

int fit_reweight(struct objective *ob, struct fit_data *d, double *r);

int fit_reweight_all(struct objective *ob, struct fit_data *d,
		     const struct selections *sl);

/* The fast render's and the photos' systematic standard uncertainties of
 * the parameters p of m (fit/discrepancy.c says how each was measured):
 * into sys the independent ones, and into shared (nparams, signed) the
 * one error source that moves several together (the small sphere's,
 * along the specular/ior ridge); with shared NULL, sys holds the two
 * together, per parameter. */
void fit_systematic(const struct glint_model *m, const double *p,
		    double map_pixel_deg, double sphere_px, double *sys,
		    double *shared);

/* The radius in pixels of the smallest sphere the objective's photos show
 * (from each view's interior pixels). */
double fit_sphere_px(const struct objective *ob);

/* ... of those whose camera blurs (a PSF, an OLPF or a colour filter
 * array: where the small sphere's term was measured), 0 when none. */
double fit_blurred_sphere_px(const struct objective *ob);

void fit_discrepancy(const struct glint_model *m, const double *p, double share,
		     double *u);

int fit_misfit_regions(const struct objective *ob, const struct selections *sl,
		       const double *r, int *region, double *share);

int fit_remove_lean(struct objective *ob, int nsets, const double *lo,
		    const double *hi, double *each, double *r,
		    const double *jac, const struct glint_uncertainty *u);

int fit_uncertainty(struct objective *ob, struct fit_data *d,
		    const struct selections *sl, struct glint_fit_result *res);

#endif
