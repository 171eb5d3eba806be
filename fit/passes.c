/* SPDX-License-Identifier: MIT */
/*
 * Passes: the roughness scans, an LM or annealing pass over a selection, the
 * coarse passes, leaving a plateau, the fine pass.
 */
#include "fit/internal.h"
#include "fit/fit_data.h"
#include "fit/misfit.h"
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
	fit_obj_residuals(ob, p, scratch);
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
	const struct glint_model *m = ob->m;
	int rk = m->lobes->roughness_param;
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
	const struct glint_model *m = ob->m;
	/* The other nonlinear parameter (ior), if one: its start and four
	 * values across its bounds, for specular x F(ior) trades off and LM
	 * stays where it starts (naive from ior 4.86). */
	int other = -1, nother = 0;
	for (int k = 0; k < m->nparams; k++)
		if (ob->lobe_of[k] < 0 && k != m->lobes->roughness_param) {
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
		count[fit_view_of(ob, sel[i])]++;
	for (int i = 0; i < nsel; i++) {
		int v = fit_view_of(ob, sel[i]);
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

int fit_scan_start(struct objective *ob, const int *sel, int nsel)
{
	const struct glint_model *m = ob->m;
	if (m->lobes->roughness_param < 0 || !ob->cache || ob->o->no_start_scan)
		return 0;
	const struct glint_param *pr = &m->params[m->lobes->roughness_param];
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
	int ret = fit_obj_residuals(a->ob, q, a->r);
	double s = 0;
	for (int k = 0; k < 3 * a->ob->nsel; k++)
		s += a->r[k] * a->r[k];
	*c = 0.5 * s;
	return ret;
}

/* Record a pass in res (the first GLINT_FIT_MAX_PASSES of them). */
void fit_add_pass(struct glint_fit_result *res, const char *name, int pixels,
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
void fit_objective_lm_opts(struct glint_lm_opts *lo, int max_iter,
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
int fit_anneal_pass(struct objective *ob, const int *sel, int nsel,
		    struct glint_fit_result *res)
{
	const struct glint_model *m = ob->m;
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
		if (k == m->lobes->roughness_param)
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
	fit_add_pass(res, "anneal", nsel, ar.accepted, ar.evals, ar.cost0,
		     ar.cost, t0);
	glint_log_info("anneal: %d evaluations (%d accepted, %d re-anneals), "
		       "cost %.4g -> %.4g: %s",
		       ar.evals, ar.accepted, ar.reanneals, ar.cost0, ar.cost,
		       ar.reason);
	return 0;
}

/* Run LM over the parameters `freev` of ob->p on selection sel. */
int fit_run_pass(struct objective *ob, const char *name, const int *sel,
		 int nsel, const int *freev, int varpro,
		 struct glint_fit_result *res, struct glint_lm_result *lr)
{
	const struct glint_model *m = ob->m;
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
			if (k == m->lobes->roughness_param)
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
		fit_obj_residuals,
		ob->cache && !varpro ? fit_obj_jacobian : NULL,
		ob,
	};
	/* The fine pass polishes a coarse optimum: a few steps do. */
	fit_objective_lm_opts(&lo_opts,
			      !strcmp(name, "fine") && ob->o->max_iter > 20
				      ? 20
				      : ob->o->max_iter,
			      &pc);
	/* the pass hands on its point alone (the uncertainty stage
	 * linearises on the sample sets) */
	lo_opts.no_final_jacobian = 1;
	/* The fine pass stops once its steps are below 0.3 standard
	 * errors: the sample sets' polish takes it on from there (the
	 * quick coverage study under Venice: every class's coverage and
	 * median |error| / se as at 0.1, two evaluations fewer). */
	if (!strcmp(name, "fine"))
		lo_opts.se_tol = 0.3;
	int ret = glint_lm_solve(&pr, &lo_opts, q, lr);
	if (ret < 0)
		return ret;
	for (int k = 0; k < ob->nfree; k++)
		ob->p[ob->free_idx[k]] = q[k];
	if (varpro) { /* the albedos that belong to the final q */
		double *scratch = malloc((size_t)3 * nsel * sizeof(double));
		if (!scratch)
			return glint_error_set(ENOMEM, "out of memory");
		fit_obj_residuals(ob, q, scratch);
		free(scratch);
	}
	fit_add_pass(res, name, nsel, lr->iterations, ob->evals, lr->cost0,
		     lr->cost, t0);
	return 0;
}

/* The method's passes (or annealing and a polish) on the coarse set. */
int fit_coarse_passes(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res)
{
	const struct fit_method *fm = fit_method_of(ob->o);
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
	int rk = ob->m->lobes->roughness_param;
	double keep[GLINT_MAX_PARAMS];
	struct glint_lm_result lr;

	memcpy(keep, ob->p, sizeof(keep));
	int ret = rescan_roughness(ob, sl->all, sl->nall,
				   fmax(ob->m->params[rk].lo, 1e-4),
				   2 * footprint, 10);
	if (ret < 0 || ob->p[rk] != keep[rk]) /* a lower point: go on */
		return ret < 0 ? ret
			       : fit_run_pass(ob, "fine, off the plateau",
					      sl->all, sl->nall, freev, vp, res,
					      &lr);
	memcpy(ob->p, keep, sizeof(keep));
	ob->memo_valid = 0;
	return 0;
}

/*
 * The pixels a full-resolution roughness scan compares its lobes on:
 * every specular pixel (where a sharper lobe's highlight shows) and
 * about 512 of each photo's others, evenly spaced (they pin the
 * albedos the scan solves for); the scan's best point is polished on
 * every pixel after.  *sub is the caller's to free.
 */
static int scan_pixels(const struct objective *ob, const struct selections *sl,
		       int **sub, int *nsub)
{
	int count[GLINT_FIT_MAX_VIEWS] = { 0 },
	    seen[GLINT_FIT_MAX_VIEWS] = { 0 };
	unsigned char *spec = calloc((size_t)sl->nall + 1, 1);

	*nsub = 0;
	*sub = malloc(((size_t)sl->nall + 1) * sizeof(int));
	if (!spec || !*sub) {
		free(spec);
		free(*sub);
		*sub = NULL;
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int t = 0; t < sl->nspec; t++)
		spec[sl->spec[t]] = 1;
	for (int t = 0; t < sl->nall; t++)
		if (!spec[sl->all[t]])
			count[fit_view_of(ob, sl->all[t])]++;
	for (int t = 0; t < sl->nall; t++) {
		int s = sl->all[t], v = fit_view_of(ob, s);
		int step = count[v] > 512 ? count[v] / 512 : 1;
		if (spec[s] || seen[v]++ % step == 0)
			(*sub)[(*nsub)++] = s;
	}
	free(spec);
	return 0;
}

/*
 * Coarse to fine: the coarse level could not see lobes below its spacing,
 * so before polishing, compare the coarse result with sharper lobes at
 * full resolution (log-spaced down to the model's bound, albedos solved
 * exactly for each), start from the best, and polish everything on the
 * full pixel set.
 */
int fit_fine_pass(struct objective *ob, const struct selections *sl,
		  double coarse_rough_lo, double footprint,
		  struct glint_fit_result *res)
{
	const struct glint_model *model = ob->m;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], ret;

	ob->rough_lo = 0;
	if (sl->ncoarse >= sl->nall)
		return 0;
	if (model->lobes->roughness_param >= 0) {
		double lo = fmax(
			model->params[model->lobes->roughness_param].lo, 1e-3);
		/* A near-mirror's ior, fitted where its lobe could not be
		 * seen, can hold the coarse result in a wider lobe's basin
		 * (copper through the sensor under quarry: roughness 0.070
		 * at ior 1.37, the truth 0.005 at 2.60 costing a twelfth):
		 * the sharper lobes with other iors too, on 256 pixels. */
		ret = ob->cache && !ob->o->no_start_scan
			      ? scan_range(ob, sl->all, sl->nall, lo,
					   coarse_rough_lo)
			      : 0;
		int *sub = NULL, nsub = 0;
		if (ret == 0)
			ret = scan_pixels(ob, sl, &sub, &nsub);
		if (ret == 0)
			ret = rescan_roughness(ob, sub, nsub, lo,
					       coarse_rough_lo, 6);
		free(sub);
		if (ret < 0)
			return ret;
	}
	int vp = fit_method_named(ob->o->method)->linear_fine;
	for (int k = 0; k < model->nparams; k++)
		freev[k] = vp ? ob->lobe_of[k] < 0 : 1;
	ret = fit_run_pass(ob, "fine", sl->all, sl->nall, freev, vp, res, &lr);
	int rk = model->lobes->roughness_param;
	if (ret == 0 && rk >= 0 && ob->cache && !ob->o->no_start_scan &&
	    ob->p[rk] < footprint)
		ret = leave_plateau(ob, sl, footprint, freev, vp, res);
	return ret;
}
