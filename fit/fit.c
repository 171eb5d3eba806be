/* SPDX-License-Identifier: MIT */
#include "fit.h"
#include "fit_data.h"
#include "misfit.h"
#include "fit/optim/anneal.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/suggest.h"
#include "core/log.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const glint_fit_method_names[] = { "three-pass", "naive", "varpro",
					       NULL };
const char *const glint_fit_optimizer_names[] = { "auto", "lm", "anneal",
						  NULL };

const char *glint_fit_method_name(enum glint_fit_method m)
{
	return glint_fit_method_names[m];
}

int glint_fit_method_parse(const char *s, enum glint_fit_method *m)
{
	for (int i = 0; glint_fit_method_names[i]; i++)
		if (!strcmp(s, glint_fit_method_names[i])) {
			*m = (enum glint_fit_method)i;
			return 0;
		}
	const char *hint = glint_suggest_hint(s, glint_fit_method_names);
	return glint_error_set(EINVAL,
			       "fit method '%s': expected three-pass, naive or "
			       "varpro%s",
			       s, hint);
}

void glint_fit_default_opts(struct glint_fit_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->method = GLINT_FIT_THREE_PASS;
	o->coarse_to_fine = 1;
	o->mask_threshold = 0.1;
	/* 4096 pixels and 8 + 8 samples: a 512 x 512 fit in under 2 s here
	 * with roughness within 5 % (README, bench/fit). */
	o->max_pixels = 4096;
	o->light_samples = 8;
	o->lobe_samples = 8;
	o->static_samples = 128;
	o->max_samples = 64;
	o->max_iter = 60;
	o->optimizer = GLINT_OPT_AUTO;
	o->seed = 1;
	o->anneal_evals = 150;
	o->mc_draws = 2;
	o->polish_iter = 4;
	o->level = 0.95;
}

int glint_fit_optimizer_parse(const char *s, enum glint_fit_optimizer *o)
{
	for (int i = 0; glint_fit_optimizer_names[i]; i++)
		if (!strcmp(s, glint_fit_optimizer_names[i])) {
			*o = (enum glint_fit_optimizer)i;
			return 0;
		}
	const char *hint = glint_suggest_hint(s, glint_fit_optimizer_names);
	return glint_error_set(EINVAL,
			       "optimizer '%s': expected lm, anneal or auto%s",
			       s, hint);
}

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
	const struct glint_model_ops *m;
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
	/* memo of lobe integrals at the nonlinear parameters memo_p */
	double *lobes, *lobes2;
	double memo_p[GLINT_MAX_PARAMS];
	int memo_valid;
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
	double *set_lobes[MAX_SETS];
	double set_lobes_p[MAX_SETS][GLINT_MAX_PARAMS];
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
	double mc_over_noise; /* the largest such ratio at the last check */
	double model_noise;   /* the sets' variance over the residual's */
};

/* The photo holding fitted pixel s. */
static int view_of(const struct objective *ob, int s)
{
	int v = 0;

	while (v + 1 < ob->nviews && s >= ob->views[v + 1].off)
		v++;
	return v;
}

static int nonlinear_same(const struct objective *ob, const double *a,
			  const double *b)
{
	for (int k = 0; k < ob->m->nparams; k++)
		if (ob->lobe_of[k] < 0 && a[k] != b[k])
			return 0;
	return 1;
}

static void lobes_at(struct objective *ob, const double *p, double *dst)
{
	glint_shade_cache_lobes_sel(ob->cache, p, ob->sel, ob->nsel, dst);
}

static const double *memo_lobes(struct objective *ob, const double *p)
{
	if (!ob->memo_valid || !nonlinear_same(ob, p, ob->memo_p)) {
		lobes_at(ob, p, ob->lobes);
		memcpy(ob->memo_p, p, sizeof(ob->memo_p));
		ob->memo_valid = 1;
	}
	return ob->lobes;
}

static double pixel_value(const struct objective *ob, const double *p,
			  const double *lobes, int s, int c)
{
	int nj = ob->m->nlobes;
	double v = 0;
	for (int j = 0; j < nj; j++)
		v += p[ob->m->lobe_param[j] + c] *
		     lobes[((size_t)s * nj + j) * 3 + c];
	return v;
}

/*
 * Bounded linear least squares for the albedos of one channel, k <= 3
 * unknowns: every assignment of each unknown to {free, lower, upper} is
 * tried, the free ones solved from the normal equations, and the best
 * feasible one kept (exact for a convex quadratic over a box).
 */
static void solve_albedos(struct objective *ob, double *p, const double *lobes,
			  int c)
{
	const struct glint_model_ops *m = ob->m;
	int nj = m->nlobes;
	double g[3][3] = { { 0 } }, b[3] = { 0 }, yy = 0;

	for (int t = 0; t < ob->nsel; t++) {
		int s = ob->sel[t];
		double w = ob->d->sw[3 * s + c] * ob->d->sw[3 * s + c];
		double y = ob->d->y[3 * s + c];
		const double *a = lobes + (size_t)t * nj * 3;
		for (int j = 0; j < nj; j++) {
			b[j] += w * a[j * 3 + c] * y;
			for (int k = 0; k < nj; k++)
				g[j][k] += w * a[j * 3 + c] * a[k * 3 + c];
		}
		yy += w * y * y;
	}
	int combos = 1;
	for (int j = 0; j < nj; j++)
		combos *= 3;
	double best = INFINITY, best_a[3] = { 0 };
	for (int code = 0; code < combos; code++) {
		double a[3], lo[3], hi[3];
		int st[3], fr[3], nf = 0, cc = code;
		for (int j = 0; j < nj; j++) {
			const struct glint_param *pi =
				&m->params[m->lobe_param[j] + c];
			lo[j] = pi->lo;
			hi[j] = pi->hi;
			st[j] = cc % 3;
			cc /= 3;
			a[j] = st[j] == 1 ? lo[j] : hi[j];
			if (st[j] == 0)
				fr[nf++] = j;
		}
		if (nf) {
			/* Solve G_ff a_f = b_f - G_fb a_b by Gaussian
			 * elimination (nf <= 3). */
			double mm[3][4];
			for (int u = 0; u < nf; u++) {
				double rhs = b[fr[u]];
				for (int j = 0; j < nj; j++)
					if (st[j])
						rhs -= g[fr[u]][j] * a[j];
				for (int v = 0; v < nf; v++)
					mm[u][v] = g[fr[u]][fr[v]];
				mm[u][nf] = rhs;
			}
			int ok = 1;
			for (int u = 0; u < nf && ok; u++) {
				int piv = u;
				for (int v = u + 1; v < nf; v++)
					if (fabs(mm[v][u]) > fabs(mm[piv][u]))
						piv = v;
				if (fabs(mm[piv][u]) < 1e-300) {
					ok = 0;
					break;
				}
				for (int k = 0; k <= nf; k++) {
					double tmp = mm[u][k];
					mm[u][k] = mm[piv][k];
					mm[piv][k] = tmp;
				}
				for (int v = 0; v < nf; v++) {
					if (v == u)
						continue;
					double f = mm[v][u] / mm[u][u];
					for (int k = u; k <= nf; k++)
						mm[v][k] -= f * mm[u][k];
				}
			}
			if (!ok)
				continue;
			for (int u = 0; u < nf; u++) {
				double v = mm[u][nf] / mm[u][u];
				if (v < lo[fr[u]] || v > hi[fr[u]])
					ok = 0;
				a[fr[u]] = v;
			}
			if (!ok)
				continue;
		}
		double cost = yy;
		for (int j = 0; j < nj; j++) {
			cost -= 2 * a[j] * b[j];
			for (int k = 0; k < nj; k++)
				cost += a[j] * g[j][k] * a[k];
		}
		if (cost < best) {
			best = cost;
			memcpy(best_a, a, sizeof(best_a));
		}
	}
	for (int j = 0; j < nj; j++)
		p[m->lobe_param[j] + c] = best_a[j];
}

static int render_full(struct objective *ob, const double *p)
{
	struct glint_renderer *r = ob->r;
	struct glint_gbuffer gb;
	struct glint_shade_opts so = {
		.light_samples = r->scene.light_samples,
		.brdf_samples = r->scene.brdf_samples,
		.nthreads = ob->o->nthreads,
	};
	/* The paper's way: trace and render the whole image each time. */
	int ret = glint_tracer_primary(r->tracer, &r->scene.cam, r->scene.spp,
				       ob->o->nthreads, NULL, &gb);
	if (ret < 0)
		return ret;
	ret = glint_render_shade(&gb, r->tracer, r->env, ob->m, p, &so, ob->img,
				 NULL);
	glint_gbuffer_free(&gb);
	return ret;
}

static int obj_residuals(void *ctx, const double *q, double *res)
{
	struct objective *ob = ctx;
	double p[GLINT_MAX_PARAMS];

	memcpy(p, ob->p, sizeof(p));
	for (int k = 0; k < ob->nfree; k++)
		p[ob->free_idx[k]] = q[k];
	ob->evals++;
	if (!ob->cache) {
		int ret = render_full(ob, p);
		if (ret < 0)
			return ret;
		for (int t = 0; t < ob->nsel; t++) {
			int s = ob->sel[t];
			const float *v =
				glint_image_px(ob->img, ob->d->xy[2 * s],
					       ob->d->xy[2 * s + 1]);
			for (int c = 0; c < 3; c++)
				res[3 * t + c] = ob->d->sw[3 * s + c] *
						 (v[c] - ob->d->y[3 * s + c]);
		}
		return 0;
	}
	const double *lobes = memo_lobes(ob, p);
	if (ob->varpro) {
		for (int c = 0; c < 3; c++)
			solve_albedos(ob, p, lobes, c);
		memcpy(ob->p, p, sizeof(p)); /* keep the albedos found */
	}
	for (int t = 0; t < ob->nsel; t++) {
		int s = ob->sel[t];
		for (int c = 0; c < 3; c++)
			res[3 * t + c] = ob->d->sw[3 * s + c] *
					 (pixel_value(ob, p, lobes, t, c) -
					  ob->d->y[3 * s + c]);
	}
	return 0;
}

/*
 * Forward-difference step for the nonlinear parameters, relative.  The
 * objective is a Monte Carlo estimate on fixed samples: smooth, but with a
 * fine-scale ripple (lobe samples move with the roughness); 1e-4 steps
 * pick the ripple up and stalled LM in flat valleys (silver under Venice
 * ended 8 % above the truth's cost), 1e-2 steps see the trend.
 */
#define FD_REL_STEP 1e-2

/* Analytic columns for albedos, forward differences for the rest. */
static int obj_jacobian(void *ctx, const double *q, const double *r,
			double *jac)
{
	struct objective *ob = ctx;
	int nf = ob->nfree, nj = ob->m->nlobes;
	double p[GLINT_MAX_PARAMS];

	(void)r;
	memcpy(p, ob->p, sizeof(p));
	for (int k = 0; k < nf; k++)
		p[ob->free_idx[k]] = q[k];
	const double *lobes = memo_lobes(ob, p);
	for (int k = 0; k < nf; k++) {
		int pk = ob->free_idx[k];
		if (ob->lobe_of[pk] >= 0) {
			int j = ob->lobe_of[pk], c = ob->chan_of[pk];
			for (int t = 0; t < ob->nsel; t++) {
				int s = ob->sel[t];
				for (int cc = 0; cc < 3; cc++)
					jac[(size_t)(3 * t + cc) * nf + k] =
						cc != c ? 0
							: ob->d->sw[3 * s + c] *
								  lobes[((size_t)t *
										 nj +
									 j) * 3 +
									c];
			}
			continue;
		}
		const struct glint_param *pi = &ob->m->params[pk];
		double h = FD_REL_STEP * fmax(fabs(p[pk]), 1e-2);
		if (p[pk] + h > pi->hi)
			h = -h;
		double pp[GLINT_MAX_PARAMS];
		memcpy(pp, p, sizeof(pp));
		pp[pk] += h;
		lobes_at(ob, pp, ob->lobes2);
		ob->evals++;
		for (int t = 0; t < ob->nsel; t++) {
			int s = ob->sel[t];
			for (int c = 0; c < 3; c++)
				jac[(size_t)(3 * t + c) * nf + k] =
					ob->d->sw[3 * s + c] *
					(pixel_value(ob, p, ob->lobes2, t, c) -
					 pixel_value(ob, p, lobes, t, c)) /
					h;
		}
	}
	return 0;
}

struct progress_ctx {
	const struct glint_fit_opts *o;
	const char *pass;
};

static void lm_progress(void *ctx, int iter, double cost, const double *p)
{
	struct progress_ctx *pc = ctx;
	(void)p;
	if (pc->o->progress)
		pc->o->progress(pc->o->progress_ctx, pc->pass, iter, cost);
}

/* Weighted cost with the albedos solved for ob->p's other parameters. */
static double projected_cost(struct objective *ob, const int *sel, int nsel,
			     double *p, double *scratch)
{
	double c = 0;

	ob->sel = sel;
	ob->nsel = nsel;
	ob->varpro = 1;
	ob->nfree = 0;
	ob->memo_valid = 0;
	memcpy(ob->p, p, sizeof(ob->p));
	obj_residuals(ob, p, scratch);
	memcpy(p, ob->p, sizeof(ob->p));
	ob->varpro = 0;
	for (int k = 0; k < 3 * nsel; k++)
		c += scratch[k] * scratch[k];
	return c;
}

/* Start from the best of ob->p and roughness at n log-spaced values in
 * [lo, hi] (the other nonlinear parameters held), albedos solved exactly
 * for each. */
static int rescan_roughness(struct objective *ob, const int *sel, int nsel,
			    double lo, double hi, int n)
{
	const struct glint_model_ops *m = ob->m;
	int rk = m->roughness_param;
	double *scratch = malloc((size_t)3 * nsel * sizeof(double));
	double best_p[GLINT_MAX_PARAMS], p[GLINT_MAX_PARAMS];

	if (!scratch)
		return glint_error_set(ENOMEM, "out of memory");
	memcpy(best_p, ob->p, sizeof(best_p));
	memcpy(p, ob->p, sizeof(p));
	double best = projected_cost(ob, sel, nsel, p, scratch);
	memcpy(best_p, p, sizeof(best_p));
	for (int i = 0; i < n && hi > lo; i++) {
		memcpy(p, best_p, sizeof(p));
		p[rk] = lo * pow(hi / lo, i / (n - 1.0));
		double c = projected_cost(ob, sel, nsel, p, scratch);
		if (c < best) {
			best = c;
			memcpy(best_p, p, sizeof(best_p));
		}
	}
	memcpy(ob->p, best_p, sizeof(ob->p));
	ob->memo_valid = 0;
	free(scratch);
	return 0;
}

/*
 * Before LM from a start: a lobe far wider than the truth's sees no
 * gradient toward a small highlight, and LM walks to a bound (green
 * acrylic from roughness 0.69: bench/stability, tests/sim/
 * test_stability_cases.c).  So LM starts from the best of the start and a
 * log-spaced scan of roughness over what the level can resolve, albedos
 * solved exactly for each, and the same at three other values of ior (28
 * evaluations on at most 256 of the pixels).  Roughness in [lo, hi].
 */
static int scan_range(struct objective *ob, const int *sel, int nsel, double lo,
		      double hi)
{
	const struct glint_model_ops *m = ob->m;
	/* The other nonlinear parameter (ior), if one: its start and four
	 * values across its bounds, for specular x F(ior) trades off and LM
	 * stays where it starts (naive from ior 4.86). */
	int other = -1, nother = 0;
	for (int k = 0; k < m->nparams; k++)
		if (ob->lobe_of[k] < 0 && k != m->roughness_param) {
			other = k;
			nother++;
		}
	if (nother != 1)
		return rescan_roughness(ob, sel, nsel, lo, hi, 8);
	static const double frac[3] = { 0.1, 0.3, 0.6 };
	double start[GLINT_MAX_PARAMS], best_p[GLINT_MAX_PARAMS];
	double best = INFINITY;
	/* A start needs no more than about 256 of each photo's pixels:
	 * every step-th of each photo's (a joint fit of one photo twice
	 * scans the same pixels of each, and so chooses as one photo). */
	int count[GLINT_FIT_MAX_VIEWS] = { 0 },
	    seen[GLINT_FIT_MAX_VIEWS] = { 0 };
	int nsub = 0;
	int *sub = malloc((size_t)nsel * sizeof(int));
	double *scratch = malloc((size_t)3 * nsel * sizeof(double));
	if (!scratch || !sub) {
		free(sub);
		free(scratch);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int i = 0; i < nsel; i++)
		count[view_of(ob, sel[i])]++;
	for (int i = 0; i < nsel; i++) {
		int v = view_of(ob, sel[i]);
		int step = count[v] > 256 ? count[v] / 256 : 1;
		if (seen[v]++ % step == 0)
			sub[nsub++] = sel[i];
	}
	sel = sub;
	nsel = nsub;
	memcpy(start, ob->p, sizeof(start));
	for (int i = 0; i <= 3; i++) {
		const struct glint_param *po = &m->params[other];
		memcpy(ob->p, start, sizeof(start));
		if (i > 0)
			ob->p[other] = po->lo + frac[i - 1] * (po->hi - po->lo);
		int ret = rescan_roughness(ob, sel, nsel, lo, hi, 6);
		if (ret < 0) {
			free(sub);
			free(scratch);
			return ret;
		}
		double p[GLINT_MAX_PARAMS];
		memcpy(p, ob->p, sizeof(p));
		double c = projected_cost(ob, sel, nsel, p, scratch);
		if (c < best) {
			best = c;
			memcpy(best_p, p, sizeof(best_p));
		}
	}
	free(sub);
	free(scratch);
	memcpy(ob->p, best_p, sizeof(ob->p));
	ob->memo_valid = 0;
	return 0;
}

static int scan_start(struct objective *ob, const int *sel, int nsel)
{
	const struct glint_model_ops *m = ob->m;
	if (m->roughness_param < 0 || !ob->cache || ob->o->no_start_scan)
		return 0;
	const struct glint_param *pr = &m->params[m->roughness_param];
	return scan_range(ob, sel, nsel, fmax(fmax(pr->lo, 1e-3), ob->rough_lo),
			  fmin(pr->hi, 0.5));
}

struct anneal_ctx {
	struct objective *ob;
	double *r;
};

static int opaque_cost(void *ctx, const double *q, double *c)
{
	struct anneal_ctx *a = ctx;
	int ret = obj_residuals(a->ob, q, a->r);
	double s = 0;
	for (int k = 0; k < 3 * a->ob->nsel; k++)
		s += a->r[k] * a->r[k];
	*c = 0.5 * s;
	return ret;
}

/* Record a pass in res (the first GLINT_FIT_MAX_PASSES of them). */
static void add_pass(struct glint_fit_result *res, const char *name, int pixels,
		     int iterations, int evaluations, double cost0, double cost,
		     double t0)
{
	if (res->npasses >= GLINT_FIT_MAX_PASSES)
		return;
	struct glint_fit_pass *fp = &res->passes[res->npasses++];
	snprintf(fp->name, sizeof(fp->name), "%s", name);
	fp->pixels = pixels;
	fp->iterations = iterations;
	fp->evaluations = evaluations;
	fp->cost0 = cost0;
	fp->cost = cost;
	fp->seconds = glint_clock_monotonic() - t0;
}

/* LM options for glint's objective, reporting progress through pc. */
static void objective_lm_opts(struct glint_lm_opts *lo, int max_iter,
			      struct progress_ctx *pc)
{
	glint_lm_default_opts(lo);
	/* The objective is a Monte Carlo estimate good to ~1e-3: a relative
	 * cost drop below 1e-6 is no progress. */
	lo->ftol = 1e-6;
	lo->se_tol = 0.1;
	lo->max_iter = max_iter;
	lo->progress = lm_progress;
	lo->progress_ctx = pc;
}

/* Adaptive simulated annealing over every parameter on selection sel
 * (fit/optim/anneal.h); the caller polishes with LM. */
static int anneal_pass(struct objective *ob, const int *sel, int nsel,
		       struct glint_fit_result *res)
{
	const struct glint_model_ops *m = ob->m;
	double q[GLINT_MAX_PARAMS], lo[GLINT_MAX_PARAMS], hi[GLINT_MAX_PARAMS];
	struct glint_anneal_opts ao;
	struct glint_anneal_result ar;
	struct anneal_ctx a = { ob, malloc((size_t)3 * nsel * sizeof(double)) };
	double t0 = glint_clock_monotonic();

	if (!a.r)
		return glint_error_set(ENOMEM, "out of memory");
	ob->sel = sel;
	ob->nsel = nsel;
	ob->varpro = 0;
	ob->memo_valid = 0;
	ob->nfree = m->nparams;
	ob->evals = 0;
	for (int k = 0; k < m->nparams; k++) {
		ob->free_idx[k] = k;
		q[k] = ob->p[k];
		lo[k] = m->params[k].lo;
		if (k == m->roughness_param)
			lo[k] = fmax(lo[k], ob->rough_lo);
		hi[k] = m->params[k].hi;
	}
	glint_anneal_default_opts(&ao);
	ao.seed = ob->o->seed;
	ao.max_evals = ob->o->anneal_evals * m->nparams;
	ao.stall_evals = ao.max_evals / 3;
	int ret =
		glint_anneal(m->nparams, lo, hi, opaque_cost, &a, &ao, q, &ar);
	free(a.r);
	if (ret < 0)
		return ret;
	memcpy(ob->p, q, sizeof(double) * (size_t)m->nparams);
	ob->memo_valid = 0;
	add_pass(res, "anneal", nsel, ar.accepted, ar.evals, ar.cost0, ar.cost,
		 t0);
	glint_log_info("anneal: %d evaluations (%d accepted, %d re-anneals), "
		       "cost %.4g -> %.4g: %s",
		       ar.evals, ar.accepted, ar.reanneals, ar.cost0, ar.cost,
		       ar.reason);
	return 0;
}

/* Run LM over the parameters `freev` of ob->p on selection sel. */
static int run_pass(struct objective *ob, const char *name, const int *sel,
		    int nsel, const int *freev, int varpro,
		    struct glint_fit_result *res, struct glint_lm_result *lr)
{
	const struct glint_model_ops *m = ob->m;
	double q[GLINT_MAX_PARAMS], lo[GLINT_MAX_PARAMS], hi[GLINT_MAX_PARAMS];
	struct glint_lm_opts lo_opts;
	struct progress_ctx pc = { ob->o, name };
	double t0 = glint_clock_monotonic();

	ob->sel = sel;
	ob->nsel = nsel;
	ob->varpro = varpro;
	ob->memo_valid = 0;
	ob->nfree = 0;
	ob->evals = 0;
	for (int k = 0; k < m->nparams; k++)
		if (freev[k]) {
			ob->free_idx[ob->nfree] = k;
			q[ob->nfree] = ob->p[k];
			lo[ob->nfree] = m->params[k].lo;
			if (k == m->roughness_param)
				lo[ob->nfree] =
					fmax(lo[ob->nfree], ob->rough_lo);
			hi[ob->nfree] = m->params[k].hi;
			ob->nfree++;
		}
	if (!ob->nfree)
		return 0;
	struct glint_lm_problem pr = {
		ob->nfree,
		3 * nsel,
		lo,
		hi,
		obj_residuals,
		ob->cache && !varpro ? obj_jacobian : NULL,
		ob,
	};
	/* The fine pass polishes a coarse optimum: a few steps do. */
	objective_lm_opts(&lo_opts,
			  !strcmp(name, "fine") && ob->o->max_iter > 20
				  ? 20
				  : ob->o->max_iter,
			  &pc);
	int ret = glint_lm_solve(&pr, &lo_opts, q, lr);
	if (ret < 0)
		return ret;
	for (int k = 0; k < ob->nfree; k++)
		ob->p[ob->free_idx[k]] = q[k];
	if (varpro) { /* the albedos that belong to the final q */
		double *scratch = malloc((size_t)3 * nsel * sizeof(double));
		if (!scratch)
			return glint_error_set(ENOMEM, "out of memory");
		obj_residuals(ob, q, scratch);
		free(scratch);
	}
	add_pass(res, name, nsel, lr->iterations, ob->evals, lr->cost0,
		 lr->cost, t0);
	return 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Median of v[0..n) (reorders v). */
static double median_of(double *v, int n)
{
	qsort(v, (size_t)n, sizeof(double), cmp_double);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/*
 * Relative RMSE of the photo against the bare backdrop: the env map seen
 * along the same primary rays, as if there were no sphere.  A photo that
 * matches the backdrop better than any fitted sphere does not show the
 * sphere where the scene says.
 */
static double backdrop_error(const struct glint_gbuffer *gb,
			     const struct glint_envmap *env,
			     const struct fit_data *d, double sums[3])
{
	double se = 0, sy = 0;
	int n = 0;

	for (int i = 0; i < d->n; i++) {
		double bg[3] = { 0, 0, 0 }, l[3];
		for (int s = 0; s < gb->spp; s++) {
			const float *dir =
				glint_gbuffer_pixel(gb, (size_t)d->pix[i])[s].d;
			glint_envmap_lookup(env, v3(dir[0], dir[1], dir[2]), l);
			for (int c = 0; c < 3; c++)
				bg[c] += l[c] / gb->spp;
		}
		for (int c = 0; c < 3; c++) {
			if (d->sw[3 * i + c] <= 0)
				continue;
			double e = bg[c] - d->y[3 * i + c];
			se += e * e;
			sy += d->y[3 * i + c];
			n++;
		}
	}
	sums[0] += se;
	sums[1] += sy;
	sums[2] += n;
	return n && sy > 0 ? sqrt(se / n) / (sy / n) : INFINITY;
}

/* Photo v's pixels of the joint data d (borrowed: not to be freed). */
static struct fit_data view_data(const struct fit_data *d, const struct view *v)
{
	struct fit_data sub = *d;

	sub.n = v->n;
	sub.pix += v->off;
	sub.xy += 2 * (size_t)v->off;
	sub.y += 3 * (size_t)v->off;
	sub.sw += 3 * (size_t)v->off;
	sub.va += 3 * (size_t)v->off;
	sub.vb += 3 * (size_t)v->off;
	sub.stride = v->stride;
	sub.frame_x = v->frame_x;
	sub.frame_y = v->frame_y;
	return sub;
}

/* The baselines a fit is judged against (glint_fit_judge()), per photo
 * and over all. */
static void baselines(const struct objective *ob, const struct fit_data *d,
		      struct glint_fit_result *res)
{
	double sums[3] = { 0, 0, 0 };

	for (int v = 0; v < ob->nviews; v++) {
		const struct view *vw = &ob->views[v];
		struct glint_fit_view_stats *st = &res->view[v];
		struct fit_data sub = view_data(d, vw);
		st->backdrop_rel_rmse =
			backdrop_error(&vw->r->gb, vw->r->env, &sub, sums);
		fit_data_baselines(&sub, &st->flat_rel_rmse, &st->noise_rmse);
	}
	res->backdrop_rel_rmse =
		sums[2] && sums[1] > 0
			? sqrt(sums[0] / sums[2]) / (sums[1] / sums[2])
			: INFINITY;
	fit_data_baselines(d, &res->flat_rel_rmse, &res->noise_rmse);
}

/* Lobes at ob->p on sel: the mean over the sample sets when there are
 * several (a pixel is linear in its lobes), else the cache's. */
static void mean_lobes(struct objective *ob, const int *sel, int nsel,
		       double *lobes)
{
	size_t sz = (size_t)nsel * ob->m->nlobes * 3;
	double *tmp = ob->nsets > 1 ? malloc(sz * sizeof(double)) : NULL;

	glint_shade_cache_lobes_sel(ob->cache, ob->p, sel, nsel, lobes);
	if (!tmp)
		return;
	for (int k = 1; k < ob->nsets; k++) {
		glint_shade_cache_lobes_sel(ob->sets[k], ob->p, sel, nsel, tmp);
		for (size_t i = 0; i < sz; i++)
			lobes[i] += tmp[i];
	}
	for (size_t i = 0; i < sz; i++)
		lobes[i] /= ob->nsets;
	free(tmp);
}

static void finish_stats(struct objective *ob, const int *sel, int nsel,
			 struct glint_fit_result *res)
{
	double se = 0, sy = 0, wcost = 0;
	double vse[GLINT_FIT_MAX_VIEWS] = { 0 },
	       vsy[GLINT_FIT_MAX_VIEWS] = { 0 },
	       vw[GLINT_FIT_MAX_VIEWS] = { 0 };
	int n = 0, vn[GLINT_FIT_MAX_VIEWS] = { 0 },
	    vp[GLINT_FIT_MAX_VIEWS] = { 0 };
	/* The uncertainty stage's residuals are these pixels' at ob->p. */
	const double *fr =
		ob->final_r && ob->final_rows == 3 * nsel ? ob->final_r : NULL;
	double *lobes = ob->cache && !fr ? malloc((size_t)nsel * ob->m->nlobes *
						  3 * sizeof(double))
					 : NULL;

	if (ob->cache && lobes)
		mean_lobes(ob, sel, nsel, lobes);
	else if (!ob->cache)
		render_full(ob, ob->p);
	for (int t = 0; t < nsel; t++) {
		int s = sel[t], view = view_of(ob, s);
		vp[view]++;
		for (int c = 0; c < 3; c++) {
			if (ob->d->sw[3 * s + c] <= 0)
				continue;
			double v;
			if (fr)
				v = ob->d->y[3 * s + c] +
				    fr[3 * t + c] / ob->d->sw[3 * s + c];
			else if (lobes)
				v = pixel_value(ob, ob->p, lobes, t, c);
			else
				v = glint_image_px(ob->img, ob->d->xy[2 * s],
						   ob->d->xy[2 * s + 1])[c];
			double e = v - ob->d->y[3 * s + c];
			double we = ob->d->sw[3 * s + c] * e;
			vw[view] += 0.5 * we * we;
			vse[view] += e * e;
			vsy[view] += ob->d->y[3 * s + c];
			vn[view]++;
		}
	}
	free(lobes);
	res->nviews = ob->nviews;
	for (int v = 0; v < ob->nviews; v++) {
		struct glint_fit_view_stats *st = &res->view[v];
		st->pixels = vp[v];
		st->interior = ob->views[v].interior;
		st->wcost = vw[v];
		st->rmse = vn[v] ? sqrt(vse[v] / vn[v]) : NAN;
		st->rel_rmse =
			vn[v] && vsy[v] > 0 ? st->rmse / (vsy[v] / vn[v]) : NAN;
		wcost += vw[v];
		se += vse[v];
		sy += vsy[v];
		n += vn[v];
	}
	res->rmse = n ? sqrt(se / n) : NAN;
	res->wcost = wcost;
	res->rel_rmse = n && sy > 0 ? res->rmse / (sy / n) : NAN;
	res->pixels = nsel;
}

/* The pixel sets the passes run on, as indices into the fit's pixels. */
struct selections {
	int *all, *coarse, *spec, *diff;
	int nall, ncoarse, nspec, ndiff;
};

static void selections_free(struct selections *s)
{
	free(s->all);
	free(s->coarse);
	free(s->spec);
	free(s->diff);
}

static void objective_free(struct objective *ob)
{
	for (int k = 1; k < ob->nsets; k++)
		glint_shade_cache_free(ob->sets[k]);
	glint_shade_cache_free(ob->cache);
	for (int v = 0; v < ob->nviews; v++)
		glint_shade_light_free(ob->views[v].light);
	free(ob->final_r);
	glint_image_free(ob->img);
	free(ob->lobes);
	free(ob->lobes2);
	for (int k = 0; k < MAX_SETS; k++)
		free(ob->set_lobes[k]);
}

/* A shade cache over every fitted pixel at the objective's sample counts
 * (one per photo, joined); seed 0 is glint's fixed set, others
 * independent ones. */
static int new_cache(const struct objective *ob, uint32_t seed,
		     struct glint_shade_cache **out)
{
	const struct glint_fit_opts *o = ob->o;
	struct glint_shade_cache_opts co = {
		.light_samples = o->light_samples * ob->sample_scale,
		.lobe_samples = o->lobe_samples * ob->sample_scale,
		.static_samples = o->static_samples,
		.no_footprint = o->no_footprint,
		.seed = seed,
		.nthreads = o->nthreads,
	};
	struct glint_fit_view in[GLINT_FIT_MAX_VIEWS];
	struct fit_data_part parts[GLINT_FIT_MAX_VIEWS];
	struct glint_shade_light *lights[GLINT_FIT_MAX_VIEWS];

	for (int v = 0; v < ob->nviews; v++) {
		const struct view *vw = &ob->views[v];
		in[v] = (struct glint_fit_view){ .r = vw->r };
		parts[v] = (struct fit_data_part){ .off = vw->off, .n = vw->n };
		lights[v] = vw->light;
	}
	return fit_data_cache_new(in, ob->nviews, ob->d, parts, ob->m, &co,
				  lights, out);
}

/* The objective over d at the start values: lobe buffers and the shade
 * cache (or the faithful path's image). */
static int objective_init(struct objective *ob, const struct view *views,
			  int nviews, const struct glint_model_ops *model,
			  const struct fit_data *d,
			  const struct glint_fit_opts *o)
{
	memset(ob, 0, sizeof(*ob));
	memcpy(ob->views, views, (size_t)nviews * sizeof(*views));
	ob->nviews = nviews;
	ob->r = views[0].r;
	ob->m = model;
	ob->d = d;
	ob->o = o;
	ob->sample_scale = 1;
	for (int k = 0; k < model->nparams; k++) {
		ob->p[k] = o->start ? o->start[k] : model->params[k].def;
		ob->lobe_of[k] = ob->chan_of[k] = -1;
	}
	for (int j = 0; j < model->nlobes; j++)
		for (int c = 0; c < 3; c++) {
			ob->lobe_of[model->lobe_param[j] + c] = j;
			ob->chan_of[model->lobe_param[j] + c] = c;
		}
	size_t nl = (size_t)d->n * model->nlobes * 3;
	ob->lobes = malloc(nl * sizeof(double));
	ob->lobes2 = malloc(nl * sizeof(double));
	if (!ob->lobes || !ob->lobes2)
		return glint_error_set(ENOMEM, "out of memory");
	if (o->faithful) {
		ob->img = glint_image_new(ob->r->gb.width, ob->r->gb.height);
		return ob->img ? 0 : glint_error_set(ENOMEM, "out of memory");
	}
	struct glint_shade_cache_opts co = { .nthreads = o->nthreads };
	int ret = 0;
	for (int v = 0; v < nviews && ret == 0; v++)
		ret = glint_shade_light_new(views[v].r->env, &co,
					    &ob->views[v].light);
	return ret < 0 ? ret : new_cache(ob, 0, &ob->cache);
}

/* The white render at every fitted pixel: the constant lobes at albedo 1
 * (the faithful path renders a white Lambertian sphere in full). */
static int white_render(struct objective *ob, const int *all, double *white)
{
	const struct fit_data *d = ob->d;
	const struct glint_model_ops *model = ob->m;

	if (!ob->cache) {
		double white_p[GLINT_MAX_PARAMS] = { 1, 1, 1 };
		struct objective wob = *ob;
		wob.m = &glint_model_lambert;
		int ret = render_full(&wob, white_p);
		for (int s = 0; s < d->n && !ret; s++)
			for (int c = 0; c < 3; c++)
				white[3 * s + c] =
					glint_image_px(ob->img, d->xy[2 * s],
						       d->xy[2 * s + 1])[c];
		return ret;
	}
	int nj = model->nlobes;
	double *wl = malloc((size_t)d->n * nj * 3 * sizeof(double));
	if (!wl)
		return glint_error_set(ENOMEM, "out of memory");
	glint_shade_cache_lobes_sel(ob->cache, ob->p, all, d->n, wl);
	for (int s = 0; s < d->n; s++)
		for (int c = 0; c < 3; c++) {
			double w = 0;
			for (int j = 0; j < nj; j++)
				if (!model->lobe_varies[j])
					w += wl[((size_t)s * nj + j) * 3 + c];
			white[3 * s + c] = w;
		}
	free(wl);
	return 0;
}

/*
 * The specular mask.  The paper marks pixels where the photo exceeds the
 * white render by more than a threshold; but a dark glossy material's
 * highlights never outshine a white sphere (satin paint: 0.27 against
 * 1.5), which leaves the mask empty and pass 1 fitting diffuse albedo on
 * highlights.  A Lambertian surface of unknown albedo a shows photo = a x
 * white everywhere, so glint marks the pixels whose ratio photo / white
 * exceeds the median ratio by more than the threshold; the paper's rule is
 * the case a = 1.
 */
static int specular_mask(struct objective *ob, const int *all,
			 unsigned char *is_spec)
{
	const struct fit_data *d = ob->d;
	double *white = malloc((size_t)d->n * 3 * sizeof(double));
	double *ratio = malloc((size_t)d->n * sizeof(double));
	double *tmp = malloc((size_t)d->n * sizeof(double));
	int ret = white && ratio && tmp
			  ? 0
			  : glint_error_set(ENOMEM, "out of memory");

	if (!ret)
		ret = white_render(ob, all, white);
	for (int s = 0; s < d->n && !ret; s++) {
		double pw = rgb_luminance(d->y[3 * s], d->y[3 * s + 1],
					  d->y[3 * s + 2]);
		double ww = rgb_luminance(white[3 * s], white[3 * s + 1],
					  white[3 * s + 2]);
		ratio[s] = ww > 0 ? pw / ww : 0;
	}
	/* Each photo's median: their lights differ. */
	for (int v = 0; v < ob->nviews && !ret; v++) {
		const struct view *vw = &ob->views[v];
		memcpy(tmp, ratio + vw->off, (size_t)vw->n * sizeof(double));
		double med = median_of(tmp, vw->n);
		for (int s = vw->off; s < vw->off + vw->n; s++)
			is_spec[s] =
				ratio[s] > (1 + ob->o->mask_threshold) * med;
	}
	free(white);
	free(ratio);
	free(tmp);
	return ret;
}

/*
 * The selections.  The masks are computed on every fitted pixel; the
 * coarse set is every 4th row and column plus every specular pixel: a
 * grid alone can miss a small glint, and the glint is what pins roughness
 * down (without it the coarse passes drift to any lobe).  The diffuse set
 * is the coarse set's non-specular pixels.
 */
static int make_selections(struct objective *ob, struct selections *sl)
{
	const struct fit_data *d = ob->d;
	size_t sz = (size_t)(d->n > 0 ? d->n : 1) * sizeof(int);
	unsigned char *is_spec = NULL;
	int ret = 0;

	memset(sl, 0, sizeof(*sl));
	sl->all = malloc(sz);
	sl->coarse = malloc(sz);
	sl->spec = malloc(sz);
	sl->diff = malloc(sz);
	is_spec = calloc((size_t)d->n + 1, 1);
	if (!sl->all || !sl->coarse || !sl->spec || !sl->diff || !is_spec) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	sl->nall = d->n;
	for (int i = 0; i < d->n; i++)
		sl->all[i] = i;
	ret = specular_mask(ob, sl->all, is_spec);
	if (ret < 0)
		goto out;
	for (int s = 0; s < d->n; s++) {
		const struct view *vw = &ob->views[view_of(ob, s)];
		int on_grid =
			(d->xy[2 * s] + vw->frame_x) % (4 * vw->stride) == 0 &&
			(d->xy[2 * s + 1] + vw->frame_y) % (4 * vw->stride) ==
				0;
		if (is_spec[s])
			sl->spec[sl->nspec++] = s;
		if (on_grid || is_spec[s])
			sl->coarse[sl->ncoarse++] = s;
	}
	if (!ob->o->coarse_to_fine || sl->ncoarse < 64 ||
	    sl->ncoarse > sl->nall / 2) {
		memcpy(sl->coarse, sl->all, (size_t)sl->nall * sizeof(int));
		sl->ncoarse = sl->nall;
	}
	for (int t = 0; t < sl->ncoarse; t++)
		if (!is_spec[sl->coarse[t]])
			sl->diff[sl->ndiff++] = sl->coarse[t];
out:
	free(is_spec);
	return ret;
}

/* The paper's three passes on the coarse set. */
static int three_pass(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res)
{
	const struct glint_model_ops *model = ob->m;
	const struct glint_fit_opts *o = ob->o;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], any = 0, ret;

	/* Pass 1: constant lobes only, the others switched off. */
	for (int k = 0; k < model->nparams; k++) {
		int j = ob->lobe_of[k];
		freev[k] = j >= 0 && !model->lobe_varies[j];
		if (j >= 0 && model->lobe_varies[j])
			ob->p[k] = 0;
	}
	if (sl->ndiff < 8) {
		memcpy(sl->diff, sl->coarse, (size_t)sl->ncoarse * sizeof(int));
		sl->ndiff = sl->ncoarse;
	}
	ret = run_pass(ob, "1 diffuse", sl->diff, sl->ndiff, freev, 0, res,
		       &lr);
	if (ret < 0)
		return ret;
	/* Pass 2: the rest from the paper's values, diffuse held. */
	for (int k = 0; k < model->nparams; k++) {
		int j = ob->lobe_of[k];
		freev[k] = !(j >= 0 && !model->lobe_varies[j]);
		any |= freev[k];
		if (freev[k])
			ob->p[k] =
				o->start ? o->start[k] : model->params[k].def;
	}
	if (any) {
		const int *sel = sl->nspec >= 8 ? sl->spec : sl->coarse;
		int nsel = sl->nspec >= 8 ? sl->nspec : sl->ncoarse;
		ret = scan_start(ob, sel, nsel);
		if (ret == 0)
			ret = run_pass(ob, "2 specular", sel, nsel, freev, 0,
				       res, &lr);
		if (ret < 0)
			return ret;
	}
	/* Pass 3: everything, all pixels. */
	for (int k = 0; k < model->nparams; k++)
		freev[k] = 1;
	return run_pass(ob, "3 all", sl->coarse, sl->ncoarse, freev, 0, res,
			&lr);
}

/* Variable projection: a log-spaced scan of the first nonlinear parameter
 * (roughness for Torrance-Sparrow), then LM over the nonlinear ones with
 * the albedos solved inside. */
static int varpro_pass(struct objective *ob, const struct selections *sl,
		       struct glint_fit_result *res)
{
	const struct glint_model_ops *model = ob->m;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], nl = -1;

	if (!ob->cache)
		return glint_error_set(EINVAL, "variable projection needs the "
					       "shade cache (not --faithful)");
	for (int k = 0; k < model->nparams; k++) {
		freev[k] = ob->lobe_of[k] < 0;
		if (freev[k] && nl < 0)
			nl = k;
	}
	if (nl < 0)
		return 0;
	const struct glint_param *pi = &model->params[nl];
	double best = INFINITY, bestv = pi->def;
	double lo = fmax(pi->lo, 1e-3), hi = fmin(pi->hi, 0.6);
	if (nl == model->roughness_param)
		lo = fmax(lo, ob->rough_lo);
	double *scratch = malloc((size_t)3 * sl->ncoarse * sizeof(double));
	if (!scratch)
		return glint_error_set(ENOMEM, "out of memory");
	ob->sel = sl->coarse;
	ob->nsel = sl->ncoarse;
	ob->varpro = 1;
	ob->nfree = 0;
	for (int i = 0; i < 10; i++) {
		double v = lo * pow(hi / lo, i / 9.0);
		ob->p[nl] = v;
		ob->memo_valid = 0;
		obj_residuals(ob, ob->p, scratch);
		double c = 0;
		for (int k = 0; k < 3 * sl->ncoarse; k++)
			c += scratch[k] * scratch[k];
		if (c < best) {
			best = c;
			bestv = v;
		}
	}
	free(scratch);
	ob->p[nl] = bestv;
	return run_pass(ob, "varpro", sl->coarse, sl->ncoarse, freev, 1, res,
			&lr);
}

/* Annealing over everything, then LM over everything. */
static int anneal_coarse(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS];
	int ret = anneal_pass(ob, sl->coarse, sl->ncoarse, res);
	for (int k = 0; k < ob->m->nparams; k++)
		freev[k] = 1;
	if (ret == 0)
		ret = run_pass(ob, "anneal-polish", sl->coarse, sl->ncoarse,
			       freev, 0, res, &lr);
	return ret;
}

/* Every parameter at once from a scanned start (the naive method). */
static int naive_coarse(struct objective *ob, struct selections *sl,
			struct glint_fit_result *res)
{
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS];
	int ret = scan_start(ob, sl->coarse, sl->ncoarse);
	if (ret < 0)
		return ret;
	for (int k = 0; k < ob->m->nparams; k++)
		freev[k] = 1;
	return run_pass(ob, "all at once", sl->coarse, sl->ncoarse, freev, 0,
			res, &lr);
}

static int varpro_coarse(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	return varpro_pass(ob, sl, res);
}

/*
 * The fit methods, one interface: a method is its coarse stage (what it
 * optimises on the coarse pixel set, from the objective's start) and
 * whether its fine pass solves the linear parameters exactly.  Indexed by
 * enum glint_fit_method, named as glint_fit_method_names; annealing is the
 * coarse stage --optimizer anneal puts in place of any method's.
 */
struct fit_method {
	int (*coarse)(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res);
	int linear_fine; /* the fine pass projects out the albedos */
};

static const struct fit_method methods[] = {
	[GLINT_FIT_THREE_PASS] = { three_pass, 0 },
	[GLINT_FIT_NAIVE] = { naive_coarse, 0 },
	[GLINT_FIT_VARPRO] = { varpro_coarse, 1 },
};
static const struct fit_method annealing = { anneal_coarse, 0 };

static const struct fit_method *method_of(const struct glint_fit_opts *o)
{
	if (o->optimizer == GLINT_OPT_ANNEAL)
		return &annealing;
	if ((unsigned)o->method >= sizeof(methods) / sizeof(methods[0]))
		return NULL;
	return &methods[o->method];
}

/* The method's passes (or annealing and a polish) on the coarse set. */
static int coarse_passes(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	const struct fit_method *fm = method_of(ob->o);
	if (!fm)
		return glint_error_set(EINVAL, "unknown fit method %d",
				       ob->o->method);
	return fm->coarse(ob, sl, res);
}

/*
 * Below the pixel footprint a near-mirror's cost flattens into a plateau
 * toward roughness 0 (every lobe there is narrower than a pixel sees),
 * and LM can step onto it from the basin near the truth and stall on it
 * (copper under Poly Haven's royal esplanade, clean: 0.0001, where 0.0045
 * cost half as much).  So where the fine pass ends below the footprint,
 * roughness is scanned from its bound to twice the footprint (albedos
 * solved for each) and the pass runs again from the best scan point when
 * it beats the end; otherwise the end stands untouched.
 */
static int leave_plateau(struct objective *ob, const struct selections *sl,
			 double footprint, const int *freev, int vp,
			 struct glint_fit_result *res)
{
	int rk = ob->m->roughness_param;
	double keep[GLINT_MAX_PARAMS];
	struct glint_lm_result lr;

	memcpy(keep, ob->p, sizeof(keep));
	int ret = rescan_roughness(ob, sl->all, sl->nall,
				   fmax(ob->m->params[rk].lo, 1e-4),
				   2 * footprint, 10);
	if (ret < 0 || ob->p[rk] != keep[rk]) /* a lower point: go on */
		return ret < 0 ? ret
			       : run_pass(ob, "fine, off the plateau", sl->all,
					  sl->nall, freev, vp, res, &lr);
	memcpy(ob->p, keep, sizeof(keep));
	ob->memo_valid = 0;
	return 0;
}

/*
 * Coarse to fine: the coarse level could not see lobes below its spacing,
 * so before polishing, compare the coarse result with sharper lobes at
 * full resolution (log-spaced down to the model's bound, albedos solved
 * exactly for each), start from the best, and polish everything on the
 * full pixel set.
 */
static int fine_pass(struct objective *ob, const struct selections *sl,
		     double coarse_rough_lo, double footprint,
		     struct glint_fit_result *res)
{
	const struct glint_model_ops *model = ob->m;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], ret;

	ob->rough_lo = 0;
	if (sl->ncoarse >= sl->nall)
		return 0;
	if (model->roughness_param >= 0) {
		double lo =
			fmax(model->params[model->roughness_param].lo, 1e-3);
		/* A near-mirror's ior, fitted where its lobe could not be
		 * seen, can hold the coarse result in a wider lobe's basin
		 * (copper through the sensor under quarry: roughness 0.070
		 * at ior 1.37, the truth 0.005 at 2.60 costing a twelfth):
		 * the sharper lobes with other iors too, on 256 pixels. */
		ret = ob->cache && !ob->o->no_start_scan
			      ? scan_range(ob, sl->all, sl->nall, lo,
					   coarse_rough_lo)
			      : 0;
		if (ret == 0)
			ret = rescan_roughness(ob, sl->all, sl->nall, lo,
					       coarse_rough_lo, 6);
		if (ret < 0)
			return ret;
	}
	int vp = methods[ob->o->method].linear_fine;
	for (int k = 0; k < model->nparams; k++)
		freev[k] = vp ? ob->lobe_of[k] < 0 : 1;
	ret = run_pass(ob, "fine", sl->all, sl->nall, freev, vp, res, &lr);
	int rk = model->roughness_param;
	if (ret == 0 && rk >= 0 && ob->cache && !ob->o->no_start_scan &&
	    ob->p[rk] < footprint)
		ret = leave_plateau(ob, sl, footprint, freev, vp, res);
	return ret;
}

/* The Jacobian of the residuals by forward differences of obj_residuals
 * (the faithful path, which has no cache to difference). */
static int jacobian_fd(struct objective *ob, const double *q, const double *r,
		       double *jac)
{
	int nf = ob->nfree, m = 3 * ob->nsel, ret = 0;
	double *r2 = malloc((size_t)m * sizeof(double));
	double qq[GLINT_MAX_PARAMS];

	if (!r2)
		return glint_error_set(ENOMEM, "out of memory");
	for (int k = 0; k < nf && !ret; k++) {
		const struct glint_param *pi = &ob->m->params[ob->free_idx[k]];
		double h = FD_REL_STEP * fmax(fabs(q[k]), 1e-2);
		if (q[k] + h > pi->hi)
			h = -h;
		memcpy(qq, q, sizeof(double) * (size_t)nf);
		qq[k] += h;
		ret = obj_residuals(ob, qq, r2);
		for (int i = 0; i < m && !ret; i++)
			jac[(size_t)i * nf + k] = (r2[i] - r[i]) / h;
	}
	free(r2);
	return ret;
}

/* The block of each residual: an 8 x 8 grid over each photo's fitted
 * pixels' bounding box, numbered densely; returns the number of
 * blocks. */
static int pixel_blocks(const struct objective *ob, const int *sel, int nsel,
			int *block)
{
	enum { G = 8 };
	const struct fit_data *d = ob->d;
	int x0[GLINT_FIT_MAX_VIEWS], y0[GLINT_FIT_MAX_VIEWS],
		x1[GLINT_FIT_MAX_VIEWS], y1[GLINT_FIT_MAX_VIEWS],
		ids[GLINT_FIT_MAX_VIEWS * G * G], nb = 0;

	for (int v = 0; v < ob->nviews; v++) {
		x0[v] = y0[v] = INT32_MAX;
		x1[v] = y1[v] = 0;
	}
	for (int t = 0; t < nsel; t++) {
		int x = d->xy[2 * sel[t]], y = d->xy[2 * sel[t] + 1];
		int v = view_of(ob, sel[t]);
		x0[v] = x < x0[v] ? x : x0[v];
		y0[v] = y < y0[v] ? y : y0[v];
		x1[v] = x > x1[v] ? x : x1[v];
		y1[v] = y > y1[v] ? y : y1[v];
	}
	for (int b = 0; b < ob->nviews * G * G; b++)
		ids[b] = -1;
	for (int t = 0; t < nsel; t++) {
		int v = view_of(ob, sel[t]);
		double sx = (x1[v] - x0[v] + 1.0) / G,
		       sy = (y1[v] - y0[v] + 1.0) / G;
		int bx = (int)((d->xy[2 * sel[t]] - x0[v]) / sx),
		    by = (int)((d->xy[2 * sel[t] + 1] - y0[v]) / sy);
		int b = v * G * G + (by < G ? by : G - 1) * G +
			(bx < G ? bx : G - 1);
		if (ids[b] < 0)
			ids[b] = nb++;
		for (int c = 0; c < 3; c++)
			block[3 * t + c] = ids[b];
	}
	return nb;
}

/* The fitted cache and `more` independent ones (seeds 1, 2, ...). */
static int sample_sets(struct objective *ob, int more,
		       struct glint_shade_cache **sets, int *nsets)
{
	int ret = 0;

	sets[0] = ob->cache;
	*nsets = 1;
	for (int k = 1; k <= more && !ret; k++) {
		ret = new_cache(ob, (uint32_t)k, &sets[k]);
		if (ret == 0)
			(*nsets)++;
	}
	return ret;
}

/* The average of several sample sets' estimates, as an LM problem over
 * every parameter (ob selects them all). */
struct sets_objective {
	struct objective *ob;
	struct glint_shade_cache *const *sets;
	int nsets;
	double *each; /* nsets x rows: each set's residuals at the last p */
	/* The last points evaluated and their Jacobian (jac_last: rows x n,
	 * may be NULL), which the polish's end need not evaluate again. */
	double q_res[GLINT_MAX_PARAMS], q_jac[GLINT_MAX_PARAMS];
	int have_res, have_jac;
	double *jac_last;
};

/* The mean of the sets' residuals in so->each. */
static void sets_mean(const struct sets_objective *so, int rows, double *r)
{
	memset(r, 0, sizeof(double) * (size_t)rows);
	for (int k = so->nsets - 1; k >= 0; k--)
		for (int i = 0; i < rows; i++)
			r[i] += so->each[(size_t)k * rows + i] / so->nsets;
}

static int sets_residuals(void *ctx, const double *q, double *r)
{
	struct sets_objective *so = ctx;
	struct objective *ob = so->ob;
	struct glint_shade_cache *fitted = ob->cache;
	int rows = 3 * ob->nsel, ret = 0;

	so->have_res = 0;
	/* The fitted set last: its lobes stay memoised for the Jacobian. */
	size_t nl = (size_t)ob->nsel * ob->m->nlobes * 3 * sizeof(double);
	for (int k = so->nsets - 1; k >= 0 && !ret; k--) {
		ob->cache = so->sets[k];
		ob->memo_valid = 0;
		ret = obj_residuals(ob, q, so->each + (size_t)k * rows);
		if (!ob->set_lobes[k])
			ob->set_lobes[k] =
				malloc((size_t)ob->d->n * ob->m->nlobes * 3 *
				       sizeof(double));
		if (ret == 0 && ob->set_lobes[k] && ob->memo_valid) {
			memcpy(ob->set_lobes[k], ob->lobes, nl);
			memcpy(ob->set_lobes_p[k], ob->memo_p,
			       sizeof(ob->memo_p));
		}
	}
	ob->cache = fitted;
	if (ret < 0 || so->sets[0] != fitted)
		ob->memo_valid = 0;
	if (ret < 0)
		return ret;
	sets_mean(so, rows, r);
	memcpy(so->q_res, q, sizeof(double) * (size_t)ob->nfree);
	so->have_res = 1;
	return 0;
}

/* The fitted set's Jacobian stands for the average's: the polish then
 * stops where J_fitted^T r_mean = 0, which differs from the average's
 * own optimum only by the fitted set's share of the error in J (a third
 * of it with three sets), at a third of the cost. */
static int sets_jacobian(void *ctx, const double *q, const double *r,
			 double *jac)
{
	struct sets_objective *so = ctx;
	int n = so->ob->nfree, ret;

	(void)r;
	so->have_jac = 0;
	ret = obj_jacobian(so->ob, q, NULL, jac);
	if (ret == 0 && so->jac_last) {
		memcpy(so->jac_last, jac,
		       sizeof(double) * (size_t)n * 3 * so->ob->nsel);
		memcpy(so->q_jac, q, sizeof(double) * (size_t)n);
		so->have_jac = 1;
	}
	return ret;
}

/*
 * The final estimate on the average of several independent sample sets.
 * A fit on one fixed set minimises that set's estimate, whose Monte Carlo
 * error grows or shrinks with the parameters, and the optimum leans
 * towards where the error is smallest, the same way for every set: at
 * 192 px and 8 + 8 samples, silver under Venice came out 9 % low in
 * roughness for every seed, a fit at 32 + 32 samples within 1 %.  So
 * from the fitted optimum a short LM polish on the sets' average (their
 * mean residuals; the fitted set's Jacobian).  Leaves each set's
 * residuals and their mean at the final ob->p in each and r, the
 * Jacobian in jac.
 */
static int refine_on_sets(struct objective *ob,
			  struct glint_shade_cache *const *sets, int nsets,
			  const double *lo, const double *hi, double *each,
			  double *r, double *jac, struct glint_fit_result *res)
{
	struct sets_objective so = {
		.ob = ob, .sets = sets, .nsets = nsets, .each = each
	};
	int n = ob->nfree, rows = 3 * ob->nsel, ret = 0;
	struct glint_lm_opts lo_opts;
	struct glint_lm_result lr;
	struct progress_ctx pc = { ob->o, "sample sets" };
	double q[GLINT_MAX_PARAMS], t0 = glint_clock_monotonic();
	size_t qb = sizeof(double) * (size_t)n;

	memcpy(q, ob->p, sizeof(q));
	if (nsets > 1) {
		struct glint_lm_problem pr = {
			n, rows, lo, hi, sets_residuals, sets_jacobian, &so,
		};
		so.jac_last = malloc(sizeof(double) * (size_t)rows * n);
		objective_lm_opts(&lo_opts, ob->o->polish_iter, &pc);
		ret = glint_lm_solve(&pr, &lo_opts, q, &lr);
		if (ret < 0)
			goto out;
		memcpy(ob->p, q, qb);
		char name[32];
		snprintf(name, sizeof(name), "%d sample sets", nsets);
		add_pass(res, name, ob->nsel, lr.iterations, lr.evaluations,
			 lr.cost0, lr.cost, t0);
	}
	/* At the polish's end, usually where it last evaluated both. */
	if (so.have_res && !memcmp(so.q_res, ob->p, qb))
		sets_mean(&so, rows, r);
	else
		ret = sets_residuals(&so, ob->p, r);
	if (ret == 0 && so.have_jac && !memcmp(so.q_jac, ob->p, qb))
		memcpy(jac, so.jac_last, sizeof(double) * (size_t)rows * n);
	else if (ret == 0)
		ret = sets_jacobian(&so, ob->p, r, jac);
out:
	free(so.jac_last);
	return ret;
}

/* Every pixel and every parameter, no variable projection. */
static void select_all(struct objective *ob, const struct selections *sl)
{
	ob->sel = sl->all;
	ob->nsel = sl->nall;
	ob->varpro = 0;
	ob->memo_valid = 0;
	ob->nfree = ob->m->nparams;
	for (int k = 0; k < ob->m->nparams; k++)
		ob->free_idx[k] = k;
}

/* Each selected value's squared residual over the noise model's
 * variance at the prediction, z[3 t + c] (NAN without a weight or a
 * variance); with s2, the scale of a model known up to it,
 * (median sqrt z / 0.6745)^2 (1 when none).  From the model at the
 * prediction, not the current weights, so that a fit and an evaluation
 * at its parameters agree. */
static int residual_z(const struct objective *ob, const struct fit_data *d,
		      const double *r, double *z, double *s2)
{
	double *a = malloc((size_t)3 * (ob->nsel > 0 ? ob->nsel : 1) *
			   sizeof(double));
	int n = 0;

	if (!a)
		return glint_error_set(ENOMEM, "out of memory");
	for (int t = 0; t < ob->nsel; t++)
		for (int c = 0; c < 3; c++) {
			int i = 3 * ob->sel[t] + c;
			double e = d->sw[i] > 0 ? r[3 * t + c] / d->sw[i] : 0,
			       v = d->sw[i] > 0 ? fit_data_variance(d, i,
								    d->y[i] + e)
						: 0;
			z[3 * t + c] = v > 0 ? e * e / v : NAN;
			if (v > 0)
				a[n++] = z[3 * t + c];
		}
	if (s2) {
		qsort(a, (size_t)n, sizeof(double), cmp_double);
		double med = n ? sqrt(a[n / 2]) / 0.6745 : 1;
		*s2 = med > 0 ? med * med : 1;
	}
	free(a);
	return 0;
}

/*
 * Weights from the noise model at the fit's prediction (fit_data.h), for
 * a photo whose weights came with it (a weight image: a real noise model)
 * or without (the default signal-proportional variance, known up to its
 * scale, which residual_z() estimates; evaluated at the photo's own
 * values alone until 2026-11-27, it left a dark photo's albedos 20 % low)
 * and for the values the fit explains to within 3 standard deviations:
 * there the photo's own noise is what is left, and weights made from it
 * bias the fit.  Elsewhere the misfit is far above the noise, its weight
 * correlates with nothing that matters, and moving the weights there
 * would move the optimum (a near-mirror's sharp reflections: copper
 * under the studio map ended 3x above the truth's cost).
 */
static int reweight(struct objective *ob, struct fit_data *d, double *r)
{
	double *pred, *z;
	int ret;

	if (!d->noise_model && !d->shape_only)
		return 0;
	pred = malloc((size_t)3 * d->n * sizeof(double));
	z = malloc((size_t)3 * (ob->nsel > 0 ? ob->nsel : 1) * sizeof(double));
	ret = pred && z ? 0 : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = obj_residuals(ob, ob->p, r);
	for (int i = 0; i < 3 * d->n && ret == 0; i++)
		pred[i] = d->y[i];
	/* A model known up to its scale (no weight image): the scale from
	 * the residuals' median, robust to a misfit's; a weight image's
	 * model is the noise's own (scale 1). */
	double s2 = 1;
	if (ret == 0)
		ret = residual_z(ob, d, r, z, d->noise_model ? NULL : &s2);
	/* Within 3 standard deviations of the noise model at the
	 * prediction, not of the photo's own weight: a value that came out
	 * dark by chance has a small variance of its own and so a large
	 * weighted residual, and leaving it on its own weight kept the very
	 * bias this removes (every albedo low at 1 000 electrons). */
	for (int t = 0; t < ob->nsel && ret == 0; t++)
		for (int c = 0; c < 3; c++)
			if (z[3 * t + c] < 9 * s2) /* NAN: no weight */
				pred[3 * ob->sel[t] + c] +=
					r[3 * t + c] /
					d->sw[3 * ob->sel[t] + c];
	if (ret == 0)
		fit_data_reweight(d, pred);
	ob->memo_valid = 0;
	free(pred);
	free(z);
	return ret;
}

/* Weights from the noise model at the coarse result's prediction
 * before the fine pass, so that its iterations, not only the short
 * polish, go to the optimum on them: at 1 000 electrons the polish alone
 * left matte paint's diffuse 2-6 % low, 3.5 % above the truth's cost. */
static int reweight_all(struct objective *ob, struct fit_data *d,
			const struct selections *sl)
{
	double *r;
	int ret;

	if ((!d->noise_model && !d->shape_only) || !ob->cache)
		return 0;
	r = malloc((size_t)3 * (sl->nall > 0 ? sl->nall : 1) * sizeof(double));
	if (!r)
		return glint_error_set(ENOMEM, "out of memory");
	select_all(ob, sl);
	ret = reweight(ob, d, r);
	free(r);
	return ret;
}

/*
 * The systematic standard uncertainty of each parameter: the accuracy of
 * glint's fast render against the independent reference renderer, which
 * no residual or sample set of one fit can show (fitter and reference
 * differ in how they integrate the sun and the diffuse lobe: roughness
 * comes out 3-9 % off depending on where the sun falls).  Measured by
 * tests/sim/test_coverage.c (quick, two maps, 16-48 noise-free fits per
 * group): the 68th percentile of |fit - truth| / truth is 0.4 % for the
 * diffuse albedos, 4.6 % for the specular, 4.1 % for roughness and 1.1 %
 * for ior; these are the standard uncertainties used (with an absolute
 * 0.0005 floor on albedos, whose small values make relative errors large).
 * Checked on the full study (every opaque Table-1 material, new
 * placements): README, "Uncertainty".
 */
static void systematic(const struct glint_model_ops *m, const double *p,
		       double *sys)
{
	for (int k = 0; k < m->nparams; k++) {
		double rel = 0.011, floor = 0;
		for (int j = 0; j < m->nlobes; j++)
			if (k >= m->lobe_param[j] && k < m->lobe_param[j] + 3) {
				rel = m->lobe_varies[j] ? 0.046 : 0.004;
				floor = 0.0005;
			}
		if (k == m->roughness_param)
			rel = 0.041;
		sys[k] = hypot(rel * fabs(p[k]), floor);
	}
}

double glint_fit_discrepancy_scale(const struct glint_model_ops *m,
				   const double *p, int k, int *cls)
{
	*cls = k == m->roughness_param ? 2 : 3;
	for (int j = 0; j < m->nlobes && *cls == 3; j++) {
		int a = m->lobe_param[j];
		if (k < a || k >= a + 3)
			continue;
		*cls = m->lobe_varies[j] ? 1 : 0;
		double mean =
			(fabs(p[a]) + fabs(p[a + 1]) + fabs(p[a + 2])) / 3;
		return fmax(fabs(p[k]), mean);
	}
	return fabs(p[k]);
}

/*
 * The model-discrepancy standard uncertainty of each parameter when the
 * model misses the photo with structure (misfit_regions()): for a material
 * the model does not hold, the answer is the model that best imitates it
 * under this light, and moves under another; the jackknife over regions
 * sees that only where regions of one photo disagree, not where every
 * region leans the same way (one sun: every pixel sees the lobe at the
 * same half-angle).  u = c x share x scale (glint_fit_discrepancy_scale()),
 * share the structure's part of the relative RMSE.  How far answers move
 * was measured (bench/misfit) on six materials none of glint's models
 * (Phong, Ward, GGX over Lambert, a Blinn-Phong metal, Oren-Nayar's rough
 * diffuse under a Blinn-Phong lobe, Burley's diffuse under GGX) under four
 * maps at four headings: per material and class, the 95th percentile over
 * pairs of lights of the c that puts the two answers within their combined
 * interval; c is the largest over the materials (each of the six gets its
 * pairs' 95 %).  Held out: the Ashikhmin-Shirley sphere of
 * tests/sim/test_tabulated.c.
 */
static void discrepancy(const struct glint_model_ops *m, const double *p,
			double share, double *u)
{
	/* diffuse albedo, specular albedo, roughness, other */
	static const double coef[4] = { 1.15, 0, 2.79, 0.42 };

	for (int k = 0; k < m->nparams; k++) {
		int cl;
		double s = glint_fit_discrepancy_scale(m, p, k, &cl);
		u[k] = coef[cl] * share * s;
	}
}

/* Per region of misfit_regions(): the sums of its pixels' residual in
 * radiance (the mean over their channels), of its square, and of the
 * photo's values, and the pixel count. */
struct region_sums {
	double e, e2, y;
	long n;
};

static void region_add(struct region_sums *g, const struct fit_data *d,
		       const double *r, int px)
{
	double e = 0, y = 0;
	int nc = 0;

	for (int c = 0; c < 3; c++) {
		double sw = d->sw[3 * px + c];
		if (!(sw > 0))
			continue;
		e += r[c] / sw;
		y += d->y[3 * px + c];
		nc++;
	}
	if (!nc)
		return;
	g->e += e / nc;
	g->e2 += e * e / (nc * nc);
	g->y += y / nc;
	g->n++;
}

/* The structure's share of the signal: the regions' mean residuals, each
 * less its own noise (the spread within it), as an RMS over the pixels,
 * over the photo's mean there.  Unbiased in the square (no region's term
 * clipped; only the total, at 0), so the right model's is about 0. */
static double structure_share(const struct region_sums *g, int ng)
{
	double st = 0, sy = 0;
	long n = 0;

	for (int k = 0; k < ng; k++) {
		if (g[k].n < 2)
			continue;
		double mean = g[k].e / g[k].n,
		       var = (g[k].e2 - g[k].e * mean) / (g[k].n - 1);
		st += g[k].n * (mean * mean - var / g[k].n);
		sy += g[k].y;
		n += g[k].n;
	}
	return n && sy > 0 && st > 0 ? sqrt(st / n) / (sy / n) : 0;
}

/*
 * The regions of the model-error jackknife (fit/optim/uncertainty.h) for
 * the residuals r (3 per fitted pixel) when they show structure, as
 * fit/misfit.h judges it (a band of either angle more than 5 standard
 * errors off zero, and with a real noise model a chi^2 above 1.5); each
 * pixel's region is its band of the angle from the mirror direction to
 * the brightest light and its third of the view angle (0-30, 30-60,
 * 60-90 degrees), per photo (-1: no hits).  Returns the number of
 * regions, or 0 when the residual shows no structure; *share is the
 * structure's share of the signal (structure_share()) either way: a
 * structure under a noisy photo's chi^2 is still one (the tabulated
 * sphere under the studio map: 11 % of the signal at chi^2 1.4).
 */
static int misfit_regions(const struct objective *ob,
			  const struct selections *sl, const double *r,
			  int *region, double *share)
{
	enum { B = GLINT_MISFIT_BANDS, R = 3 * B };
	const struct fit_data *d = ob->d;
	double s[2][B] = { { 0 } }, s2[2][B] = { { 0 } }, c2 = 0;
	long cnt[2][B] = { { 0 } };
	int ids[GLINT_FIT_MAX_VIEWS * R], nr = 0;
	struct region_sums sums[GLINT_FIT_MAX_VIEWS * R];
	struct vec3 light[GLINT_FIT_MAX_VIEWS];

	memset(sums, 0, sizeof(sums));
	for (int v = 0; v < ob->nviews; v++)
		light[v] = glint_misfit_light(ob->views[v].r->env);
	for (int k = 0; k < ob->nviews * R; k++)
		ids[k] = -1;
	for (int t = 0; t < sl->nall; t++) {
		int px = sl->all[t], v = view_of(ob, px), kv, km;
		const struct glint_gbuffer *gb = &ob->views[v].r->gb;
		const struct glint_hit *hs =
			glint_gbuffer_pixel(gb, (size_t)d->pix[px]);
		double z = (r[3 * t] + r[3 * t + 1] + r[3 * t + 2]) / 3;
		for (int c = 0; c < 3; c++)
			c2 += r[3 * t + c] * r[3 * t + c];
		if (!hs) {
			region[3 * t] = region[3 * t + 1] = region[3 * t + 2] =
				-1;
			continue;
		}
		glint_misfit_bands(hs, gb->spp, light[v], &kv, &km);
		int b[2] = { kv, km };
		for (int a = 0; a < 2; a++) {
			s[a][b[a]] += z;
			s2[a][b[a]] += z * z;
			cnt[a][b[a]]++;
		}
		int g = v * R + km * 3 + kv / 3;
		if (ids[g] < 0)
			ids[g] = nr++;
		for (int c = 0; c < 3; c++)
			region[3 * t + c] = ids[g];
		region_add(&sums[g], d, r + 3 * t, px);
	}
	double zmax = 0;
	for (int a = 0; a < 2; a++)
		for (int k = 0; k < B; k++) {
			long n = cnt[a][k];
			if (n < 20)
				continue;
			double mean = s[a][k] / n,
			       var = (s2[a][k] - s[a][k] * mean) / (n - 1);
			if (var > 0)
				zmax = fmax(zmax, fabs(mean) / sqrt(var / n));
		}
	int noisy = !d->noise_model || c2 / (3.0 * sl->nall) > 1.5;
	*share = structure_share(sums, ob->nviews * R);
	return zmax > 5 && noisy ? nr : 0;
}

/* Per block of residuals, the sum over its residuals i and the sample
 * sets s of (r_s,i - r_i) J_s,ik (uncertainty.h's draws_jr), with J_s
 * set s's own Jacobian at ob->p (jac: the fitted set's), into jr
 * (nblocks x n). */
static int sets_jr(struct objective *ob, int nsets, const double *each,
		   const double *r, const double *jac, const int *block,
		   int nblocks, double *jr)
{
	struct glint_shade_cache *fitted = ob->cache;
	int n = ob->nfree, rows = 3 * ob->nsel, ret = 0;
	double *js = malloc(sizeof(double) * (size_t)rows * n);

	if (!js)
		return glint_error_set(ENOMEM, "out of memory");
	memset(jr, 0, sizeof(double) * (size_t)nblocks * n);
	for (int s = 0; s < nsets && ret == 0; s++) {
		const double *j = jac;
		if (s > 0) {
			ob->cache = ob->sets[s];
			ob->memo_valid = 0;
			/* its lobes at p from the polish's last evaluation */
			if (ob->set_lobes[s] &&
			    nonlinear_same(ob, ob->p, ob->set_lobes_p[s])) {
				memcpy(ob->lobes, ob->set_lobes[s],
				       (size_t)ob->nsel * ob->m->nlobes * 3 *
					       sizeof(double));
				memcpy(ob->memo_p, ob->p, sizeof(ob->memo_p));
				ob->memo_valid = 1;
			}
			ret = obj_jacobian(ob, ob->p, NULL, js);
			j = js;
		}
		for (int i = 0; i < rows && ret == 0; i++) {
			double d = each[(size_t)s * rows + i] - r[i];
			double *x = jr + (size_t)block[i] * n;
			for (int k = 0; k < n; k++)
				x[k] += d * j[(size_t)i * n + k];
		}
	}
	ob->cache = fitted;
	ob->memo_valid = 0;
	free(js);
	return ret;
}

/* The covariance at the optimum from the residuals r, their Jacobian,
 * each sample set's residuals, the blocks (pixel_blocks()) with the
 * sets' jr (sets_jr(), or NULL), and the regions. */
static int covariance(struct objective *ob, const struct selections *sl,
		      int nsets, const double *lo, const double *hi,
		      const double *each, const double *r, const double *jac,
		      const int *block, int nblocks, const double *jr,
		      const int *region, int nregions, double share,
		      struct glint_fit_result *res)
{
	const struct glint_model_ops *m = ob->m;
	double sys[GLINT_MAX_PARAMS];

	if (ob->o->no_systematic)
		memset(sys, 0, sizeof(sys));
	else
		systematic(m, ob->p, sys);
	memset(res->discrepancy, 0, sizeof(res->discrepancy));
	if (!ob->o->no_discrepancy)
		discrepancy(m, ob->p, share, res->discrepancy);
	for (int k = 0; k < m->nparams; k++)
		sys[k] = sqrt(sys[k] * sys[k] + ob->lean_var[k] +
			      res->discrepancy[k] * res->discrepancy[k]);
	struct glint_unc_problem pr = {
		.n = m->nparams,
		.m = 3 * sl->nall,
		.jac = jac,
		.r = r,
		.block = block,
		.nblocks = nblocks,
		.p = ob->p,
		.lo = lo,
		.hi = hi,
		.draws = nsets > 1 ? each : NULL,
		.ndraws = nsets > 1 ? nsets : 0,
		.draws_jr = nsets > 1 ? jr : NULL,
		.sys = sys,
		.level = ob->o->level,
		.region = nregions ? region : NULL,
		.nregions = nregions,
	};
	return glint_uncertainty_compute(&pr, &res->unc);
}

/* One round of the uncertainty stage: reweight, the sample sets, the
 * polish on their mean, the Jacobian and the covariance. */
static int estimate_on_sets(struct objective *ob, struct fit_data *d,
			    const struct selections *sl, int nsets,
			    const double *lo, const double *hi, double *each,
			    double *r, double *jac, int *block, double *jr,
			    struct glint_fit_result *res)
{
	int ret;

	if (ob->cache) {
		ret = reweight(ob, d, r);
		if (ret == 0)
			ret = sample_sets(ob, nsets - 1, ob->sets, &ob->nsets);
		if (ret == 0)
			ret = refine_on_sets(ob, ob->sets, nsets, lo, hi, each,
					     r, jac, res);
	} else {
		ret = obj_residuals(ob, ob->p, r);
		if (ret == 0)
			ret = jacobian_fd(ob, ob->p, r, jac);
	}
	if (ret < 0)
		return ret;
	int nblocks = pixel_blocks(ob, sl->all, sl->nall, block);
	if (ob->cache && nsets > 1)
		ret = sets_jr(ob, nsets, each, r, jac, block, nblocks, jr);
	if (ret < 0)
		return ret;
	return covariance(ob, sl, nsets, lo, hi, each, r, jac, block, nblocks,
			  ob->cache && nsets > 1 ? jr : NULL, NULL, 0, 0, res);
}

/*
 * Is the fitter's own sampling, not the photo, what limits the answer?
 * Two measures from the sample sets: per parameter, the Monte Carlo
 * variance of the optimum against the noise's (a map whose light sits in
 * several softboxes: Blender's studio map moved silver's specular by
 * 0.025 at 8 + 8 samples); per value, the sets' variance (the model's own
 * noise) against the variance of the residual left.  The second catches
 * the bias every set shares (errors in variables: least squares on a
 * noisy model leans to where its noise fits; silver under Venice at
 * 192 px, 0.36 at 8 + 8 and roughness 9 % low, within 5 % at 16 + 16),
 * which the first cannot see.  Over 1, or over 0.25 (the model's noise
 * above half the residual's), the caches are rebuilt with 2x the samples
 * (4x when four times over), up to max_samples (64 + 64 by default),
 * and the stage runs again.
 * Returns 1 to go again, 0 when done, or a negative errno.
 */
static int more_samples(struct objective *ob, const struct glint_uncertainty *u,
			const double *each, const double *r, int rows)
{
	int n = u->n, base = ob->o->light_samples, nsets = ob->nsets;
	int cap = ob->o->max_samples;
	double worst = 0, vm = 0, vr = 0;

	if (!ob->cache || nsets < 2 || !(u->ndraws > 1))
		return 0;
	for (int k = 0; k < n; k++) {
		double vn = u->cov_blocks[k * n + k], vk = u->cov_mc[k * n + k];
		if (vn > 0 && isfinite(vn) && isfinite(vk))
			worst = fmax(worst, vk / vn);
	}
	/* Per value: the sets' variance (the model's own noise) against
	 * what the mean leaves (the photo's noise and any misfit). */
	for (int i = 0; i < rows; i++) {
		double s1 = 0, s2 = 0;
		for (int k = 0; k < nsets; k++) {
			double e = each[(size_t)k * rows + i];
			s1 += e;
			s2 += e * e;
		}
		vm += (s2 - s1 * s1 / nsets) / (nsets - 1);
		vr += r[i] * r[i];
	}
	double vals = vr > 0 ? vm / vr : 0;
	ob->mc_over_noise = worst;
	ob->model_noise = vals;
	if (!(worst > 1 || vals > 0.25) || base * ob->sample_scale * 2 > cap)
		return 0;
	int f = (worst > 4 || vals > 1) && base * ob->sample_scale * 4 <= cap
			? 4
			: 2;
	glint_log_info(
		"the fit's own sampling noise is %.2f of the residual "
		"per value and %.2f of the noise per parameter "
		"(variances): %d + %d samples per hit instead of %d + %d",
		vals, worst, base * ob->sample_scale * f,
		ob->o->lobe_samples * ob->sample_scale * f,
		base * ob->sample_scale,
		ob->o->lobe_samples * ob->sample_scale);
	for (int k = 1; k < ob->nsets; k++)
		glint_shade_cache_free(ob->sets[k]);
	ob->nsets = 0;
	glint_shade_cache_free(ob->cache);
	ob->cache = NULL;
	ob->sample_scale *= f;
	ob->memo_valid = 0;
	int ret = new_cache(ob, 0, &ob->cache);
	return ret < 0 ? ret : 1;
}

/*
 * The sampling lean (fit/optim/uncertainty.h) taken off the optimum:
 * the fit on a mean of K sets still leans by a K-th of one set's lean
 * (teflon under Blender's studio map: specular 0.433 for 0.446 on
 * average over six seeds at 16 + 16 samples, 0.438 at 128).  The
 * estimate's own noise is shrunk away (by 1 - se^2 / lean^2, at least
 * 0) and the rest's variance joins the parameter's systematic
 * uncertainty.  The residuals (each and r) follow to first order, by the
 * Jacobian jac, which stays (the step is below the standard error).
 * Returns 1 when the optimum moved, 0 when not.
 */
static int remove_lean(struct objective *ob, int nsets, const double *lo,
		       const double *hi, double *each, double *r,
		       const double *jac, const struct glint_uncertainty *u)
{
	int n = ob->m->nparams, rows = 3 * ob->nsel, moved = 0;
	double step[GLINT_MAX_PARAMS] = { 0 };

	if (!ob->cache || nsets < 2 || ob->o->keep_lean)
		return 0;
	for (int k = 0; k < n; k++) {
		double l = u->lean[k], s = u->lean_se[k];
		if (!(fabs(l) > s) || !isfinite(l) || !isfinite(s))
			continue;
		double f = 1 - s * s / (l * l);
		double q = fmin(hi[k], fmax(lo[k], ob->p[k] - f * l));
		ob->lean_var[k] = f * s * f * s;
		ob->lean_fix[k] = step[k] = q - ob->p[k];
		moved |= q != ob->p[k];
		ob->p[k] = q;
	}
	if (!moved)
		return 0;
	ob->memo_valid = 0;
	for (int i = 0; i < rows; i++) {
		double d = 0;
		for (int k = 0; k < n; k++)
			d += jac[(size_t)i * n + k] * step[k];
		r[i] += d;
		for (int s = 0; s < nsets; s++)
			each[(size_t)s * rows + i] += d;
	}
	return 1;
}

/* The uncertainty at the optimum over every pixel and parameter
 * (fit/optim/uncertainty.h): the Jacobian, the residuals, their blocks
 * and each sample set's residuals,
 * with more samples while the sets disagree by more than the noise. */
static int uncertainty(struct objective *ob, struct fit_data *d,
		       const struct selections *sl,
		       struct glint_fit_result *res)
{
	const struct glint_model_ops *m = ob->m;
	int n = m->nparams, rows = 3 * sl->nall, ret;
	int nsets = ob->cache ? 1 + ob->o->mc_draws : 1;
	double t0 = glint_clock_monotonic();
	double *jac = malloc((size_t)rows * n * sizeof(double));
	double *r = malloc((size_t)rows * sizeof(double));
	double *each, lo[GLINT_MAX_PARAMS], hi[GLINT_MAX_PARAMS];
	int *block = malloc((size_t)rows * sizeof(int)), *region = NULL;
	double *jr = malloc(sizeof(double) * GLINT_FIT_MAX_VIEWS * 64 * n);

	if (nsets > MAX_SETS)
		nsets = MAX_SETS;
	each = malloc((size_t)nsets * rows * sizeof(double));
	if (!jac || !r || !each || !block || !jr) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	select_all(ob, sl);
	for (int k = 0; k < n; k++) {
		lo[k] = m->params[k].lo;
		hi[k] = m->params[k].hi;
	}
	do
		ret = estimate_on_sets(ob, d, sl, nsets, lo, hi, each, r, jac,
				       block, jr, res);
	while (ret == 0 &&
	       (ret = more_samples(ob, &res->unc, each, r, rows)) > 0);
	if (ret == 0)
		ret = remove_lean(ob, nsets, lo, hi, each, r, jac, &res->unc);
	if (ret > 0)
		ret = covariance(ob, sl, nsets, lo, hi, each, r, jac, block,
				 pixel_blocks(ob, sl->all, sl->nall, block), jr,
				 NULL, 0, 0, res);
	if (ret < 0)
		goto out;
	/* A structured residual: the model-error jackknife over regions. */
	region = malloc((size_t)rows * sizeof(int));
	if (!region) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	double share = 0;
	int nregions = ob->o->no_model_error
			       ? 0
			       : misfit_regions(ob, sl, r, region, &share);
	if (nregions < 3)
		nregions = 0;
	/* The model discrepancy wherever the structure has a share (it may
	 * lie under the noise, where the jackknife has no regions). */
	if (nregions || (share > 0 && !ob->o->no_discrepancy))
		ret = covariance(ob, sl, nsets, lo, hi, each, r, jac, block,
				 pixel_blocks(ob, sl->all, sl->nall, block),
				 ob->cache && nsets > 1 ? jr : NULL,
				 nregions ? region : NULL, nregions, share,
				 res);
	res->misfit_share = share;
	if (ret < 0)
		goto out;
	res->light_samples = ob->o->light_samples * ob->sample_scale;
	res->lobe_samples = ob->o->lobe_samples * ob->sample_scale;
	res->mc_over_noise = ob->mc_over_noise;
	res->model_noise = ob->model_noise;
	for (int k = 0; k < n; k++)
		res->lean_removed[k] = -ob->lean_fix[k];
	res->cost = 0;
	for (int i = 0; i < rows; i++)
		res->cost += 0.5 * r[i] * r[i];
	for (int k = 0; k < n; k++) {
		double tol = 1e-9 * (hi[k] - lo[k]);
		res->se[k] = res->unc.se[k];
		res->at_bound[k] =
			ob->p[k] <= lo[k] + tol || ob->p[k] >= hi[k] - tol;
	}
	res->unc_seconds = glint_clock_monotonic() - t0;
	free(ob->final_r);
	ob->final_r = r;
	ob->final_rows = rows;
	r = NULL;
out:
	free(jac);
	free(r);
	free(each);
	free(block);
	free(jr);
	free(region);
	return ret;
}

/* The evaluation at given parameters on the fit's terms: weights from the
 * noise model at the prediction and the mean of the same sample sets. */
static int eval_like_fit(struct objective *ob, struct fit_data *d,
			 const struct selections *sl)
{
	double *r = malloc((size_t)3 * (sl->nall > 0 ? sl->nall : 1) *
			   sizeof(double));
	int ret = r ? 0 : glint_error_set(ENOMEM, "out of memory");

	if (!ob->cache || ret < 0) {
		free(r);
		return ret;
	}
	select_all(ob, sl);
	double p[GLINT_MAX_PARAMS];
	memcpy(p, ob->p, sizeof(p));
	if (ob->o->weights_at)
		memcpy(ob->p, ob->o->weights_at,
		       sizeof(double) * (size_t)ob->m->nparams);
	ret = reweight(ob, d, r);
	memcpy(ob->p, p, sizeof(p));
	int nsets = 1 + ob->o->mc_draws;
	if (ret == 0)
		ret = sample_sets(ob,
				  nsets < MAX_SETS ? nsets - 1 : MAX_SETS - 1,
				  ob->sets, &ob->nsets);
	free(r);
	return ret;
}

/* Each photo's pixels, joined into d, with where each lies in views[]. */
static int prepare_views(const struct glint_fit_view *in, int nviews,
			 const struct glint_fit_opts *o, struct fit_data *d,
			 struct view *views)
{
	struct fit_data_part parts[GLINT_FIT_MAX_VIEWS];
	int ret = fit_data_prepare_views(in, nviews, o, d, parts);

	for (int v = 0; v < nviews; v++) {
		memset(&views[v], 0, sizeof(views[v]));
		views[v].r = in[v].r;
		if (ret < 0)
			continue;
		views[v].off = parts[v].off;
		views[v].n = parts[v].n;
		views[v].interior = parts[v].interior;
		views[v].stride = parts[v].stride;
		views[v].frame_x = parts[v].frame_x;
		views[v].frame_y = parts[v].frame_y;
	}
	return ret;
}

static int fit_or_eval(const struct glint_fit_view *in, int nviews,
		       const struct glint_model_ops *model,
		       const struct glint_fit_opts *o, const double *eval_p,
		       struct glint_fit_result *res)
{
	struct fit_data d = { 0 };
	struct objective ob = { 0 };
	struct selections sl = { 0 };
	struct view views[GLINT_FIT_MAX_VIEWS];
	int ret, interior = 0;
	double t0 = glint_clock_monotonic();

	if (nviews < 1 || nviews > GLINT_FIT_MAX_VIEWS)
		return glint_error_set(EINVAL,
				       "%d photos: a joint fit takes 1 to %d",
				       nviews, GLINT_FIT_MAX_VIEWS);
	if (nviews > 1 && (model->transparent || o->faithful))
		return glint_error_set(
			EINVAL,
			"a joint fit of several photos needs the shade cache: "
			"not %s",
			o->faithful ? "--faithful" : "a transparent model");
	if (model->transparent)
		return glint_fit_dielectric(in->r, model, in->photo, in->weight,
					    o, NULL, eval_p, res);
	memset(res, 0, sizeof(*res));
	res->model = model;
	if (model->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "model %s cannot be fitted by LM here "
				       "(no linear lobes)",
				       model->name);
	ret = prepare_views(in, nviews, o, &d, views);
	if (ret < 0)
		goto out;
	for (int v = 0; v < nviews; v++)
		interior += views[v].interior;
	res->interior = interior;
	ret = objective_init(&ob, views, nviews, model, &d, o);
	if (ret < 0)
		goto out;
	res->setup_seconds = glint_clock_monotonic() - t0;
	if (eval_p) {
		memcpy(ob.p, eval_p, (size_t)model->nparams * sizeof(double));
		memcpy(res->p, ob.p, sizeof(res->p));
		sl.all = malloc((size_t)(d.n > 0 ? d.n : 1) * sizeof(int));
		if (!sl.all) {
			ret = glint_error_set(ENOMEM, "out of memory");
			goto out;
		}
		for (int i = 0; i < d.n; i++)
			sl.all[i] = i;
		sl.nall = d.n;
		ret = eval_like_fit(&ob, &d, &sl);
		if (ret < 0)
			goto out;
		finish_stats(&ob, sl.all, d.n, res);
		res->seconds = glint_clock_monotonic() - t0;
		goto out;
	}
	ret = make_selections(&ob, &sl);
	if (ret < 0)
		goto out;
	res->specular_pixels = sl.nspec;
	/*
	 * A level sampled every `spacing` pixels cannot tell lobes narrower
	 * than the reflected directions between its samples (about
	 * 2 spacing / R radians on a sphere R pixels in radius, i.e. a
	 * roughness of spacing / R): a mirror's glint can fall between
	 * samples and "mirror" becomes a false minimum.  Coarse passes keep
	 * roughness above that (the largest over the photos); the fine pass
	 * is free.
	 */
	double coarse_rough_lo = 0, footprint = INFINITY;
	for (int v = 0; v < nviews; v++) {
		double radius = sqrt(views[v].interior / M_PI);
		coarse_rough_lo =
			fmax(coarse_rough_lo, 4.0 * views[v].stride / radius);
		/* the finest photo's (fit/result.c) */
		footprint = fmin(footprint, 1 / radius);
	}
	if (sl.ncoarse < sl.nall)
		ob.rough_lo = coarse_rough_lo;
	ret = coarse_passes(&ob, &sl, res);
	if (ret == 0)
		ret = reweight_all(&ob, &d, &sl);
	if (ret == 0)
		ret = fine_pass(&ob, &sl, coarse_rough_lo, footprint, res);
	if (ret == 0)
		ret = uncertainty(&ob, &d, &sl, res);
	if (ret < 0)
		goto out;
	memcpy(res->p, ob.p, sizeof(res->p));
	finish_stats(&ob, sl.all, sl.nall, res);
	baselines(&ob, &d, res);
	res->seconds = glint_clock_monotonic() - t0;
out:
	objective_free(&ob);
	selections_free(&sl);
	free_data(&d);
	return ret;
}

int glint_fit(struct glint_renderer *r, const struct glint_model_ops *model,
	      const struct glint_image *photo, const struct glint_image *weight,
	      const struct glint_fit_opts *o, struct glint_fit_result *res)
{
	struct glint_fit_view v = { r, photo, weight };

	return fit_or_eval(&v, 1, model, o, NULL, res);
}

int glint_fit_views(const struct glint_fit_view *views, int nviews,
		    const struct glint_model_ops *model,
		    const struct glint_fit_opts *o,
		    struct glint_fit_result *res)
{
	return fit_or_eval(views, nviews, model, o, NULL, res);
}

int glint_fit_evaluate(struct glint_renderer *r,
		       const struct glint_model_ops *model,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, const double *p,
		       struct glint_fit_result *res)
{
	struct glint_fit_view v = { r, photo, weight };

	return fit_or_eval(&v, 1, model, o, p, res);
}
