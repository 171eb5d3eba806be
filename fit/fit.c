/* SPDX-License-Identifier: MIT */
#include "fit.h"
#include "fit_data.h"
#include "fit/optim/anneal.h"

#include "core/error.h"
#include "core/log.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const method_names[] = { "three-pass", "naive", "varpro" };

const char *glint_fit_method_name(enum glint_fit_method m)
{
	return method_names[m];
}

int glint_fit_method_parse(const char *s, enum glint_fit_method *m)
{
	for (int i = 0; i < 3; i++)
		if (!strcmp(s, method_names[i])) {
			*m = (enum glint_fit_method)i;
			return 0;
		}
	return glint_error_set(EINVAL,
			       "fit method '%s': expected three-pass, naive or "
			       "varpro",
			       s);
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
	o->max_iter = 60;
	o->optimizer = GLINT_OPT_AUTO;
	o->seed = 1;
	o->anneal_evals = 150;
}

int glint_fit_optimizer_parse(const char *s, enum glint_fit_optimizer *o)
{
	if (!strcmp(s, "auto"))
		*o = GLINT_OPT_AUTO;
	else if (!strcmp(s, "lm"))
		*o = GLINT_OPT_LM;
	else if (!strcmp(s, "anneal"))
		*o = GLINT_OPT_ANNEAL;
	else
		return glint_error_set(EINVAL,
				       "optimizer '%s': expected lm, anneal or "
				       "auto",
				       s);
	return 0;
}

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
};

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
 * evaluations on at most 256 of the pixels).
 */
static int scan_start(struct objective *ob, const int *sel, int nsel)
{
	const struct glint_model_ops *m = ob->m;
	if (m->roughness_param < 0 || !ob->cache || ob->o->no_start_scan)
		return 0;
	const struct glint_param *pr = &m->params[m->roughness_param];
	double lo = fmax(fmax(pr->lo, 1e-3), ob->rough_lo);
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
		return rescan_roughness(ob, sel, nsel, lo, fmin(pr->hi, 0.5),
					8);
	static const double frac[3] = { 0.1, 0.3, 0.6 };
	double start[GLINT_MAX_PARAMS], best_p[GLINT_MAX_PARAMS];
	double best = INFINITY;
	/* A start needs no more than about 256 of the pixels. */
	int step = nsel > 256 ? nsel / 256 : 1, nsub = 0;
	int *sub = malloc((size_t)nsel * sizeof(int));
	double *scratch = malloc((size_t)3 * nsel * sizeof(double));
	if (!scratch || !sub) {
		free(sub);
		free(scratch);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int i = 0; i < nsel; i += step)
		sub[nsub++] = sel[i];
	sel = sub;
	nsel = nsub;
	memcpy(start, ob->p, sizeof(start));
	for (int i = 0; i <= 3; i++) {
		const struct glint_param *po = &m->params[other];
		memcpy(ob->p, start, sizeof(start));
		if (i > 0)
			ob->p[other] = po->lo + frac[i - 1] * (po->hi - po->lo);
		int ret = rescan_roughness(ob, sel, nsel, lo, fmin(pr->hi, 0.5),
					   6);
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

/* Adaptive simulated annealing over every parameter on selection sel
 * (fit/anneal.h); the caller polishes with LM. */
static int anneal_pass(struct objective *ob, const int *sel, int nsel,
		       struct glint_fit_result *res)
{
	const struct glint_model_ops *m = ob->m;
	double q[GLINT_MAX_PARAMS], lo[GLINT_MAX_PARAMS], hi[GLINT_MAX_PARAMS];
	struct glint_anneal_opts ao;
	struct glint_anneal_result ar;
	struct anneal_ctx a = { ob, malloc((size_t)3 * nsel * sizeof(double)) };
	double t0 = glint_now();

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
	if (res->npasses < GLINT_FIT_MAX_PASSES) {
		struct glint_fit_pass *ps = &res->passes[res->npasses++];
		snprintf(ps->name, sizeof(ps->name), "anneal");
		ps->pixels = nsel;
		ps->iterations = ar.accepted;
		ps->evaluations = ar.evals;
		ps->cost0 = ar.cost0;
		ps->cost = ar.cost;
		ps->seconds = glint_now() - t0;
	}
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
	double t0 = glint_now();

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
	glint_lm_default_opts(&lo_opts);
	/* The objective is a Monte Carlo estimate good to ~1e-3: a relative
	 * cost drop below 1e-6 is no progress. */
	lo_opts.ftol = 1e-6;
	lo_opts.se_tol = 0.1;
	lo_opts.max_iter = ob->o->max_iter;
	/* The fine pass polishes a coarse optimum: a few steps do. */
	if (!strcmp(name, "fine") && lo_opts.max_iter > 20)
		lo_opts.max_iter = 20;
	lo_opts.progress = lm_progress;
	lo_opts.progress_ctx = &pc;
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
	if (res->npasses < GLINT_FIT_MAX_PASSES) {
		struct glint_fit_pass *fp = &res->passes[res->npasses++];
		snprintf(fp->name, sizeof(fp->name), "%s", name);
		fp->pixels = nsel;
		fp->iterations = lr->iterations;
		fp->evaluations = ob->evals;
		fp->cost0 = lr->cost0;
		fp->cost = lr->cost;
		fp->seconds = glint_now() - t0;
	}
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
			     const struct fit_data *d)
{
	double se = 0, sy = 0;
	int n = 0;

	for (int i = 0; i < d->n; i++) {
		double bg[3] = { 0, 0, 0 }, l[3];
		for (int s = 0; s < gb->spp; s++) {
			const float *dir =
				gb->hits[(size_t)d->pix[i] * gb->spp + s].d;
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
	return n && sy > 0 ? sqrt(se / n) / (sy / n) : INFINITY;
}

static void finish_stats(struct objective *ob, const int *sel, int nsel,
			 struct glint_fit_result *res)
{
	double se = 0, sy = 0, wcost = 0;
	int n = 0;
	double *lobes = ob->cache ? malloc((size_t)nsel * ob->m->nlobes * 3 *
					   sizeof(double))
				  : NULL;

	if (ob->cache && lobes)
		glint_shade_cache_lobes_sel(ob->cache, ob->p, sel, nsel, lobes);
	else if (!ob->cache)
		render_full(ob, ob->p);
	for (int t = 0; t < nsel; t++) {
		int s = sel[t];
		for (int c = 0; c < 3; c++) {
			if (ob->d->sw[3 * s + c] <= 0)
				continue;
			double v;
			if (lobes)
				v = pixel_value(ob, ob->p, lobes, t, c);
			else
				v = glint_image_px(ob->img, ob->d->xy[2 * s],
						   ob->d->xy[2 * s + 1])[c];
			double e = v - ob->d->y[3 * s + c];
			double we = ob->d->sw[3 * s + c] * e;
			wcost += 0.5 * we * we;
			se += e * e;
			sy += ob->d->y[3 * s + c];
			n++;
		}
	}
	free(lobes);
	res->rmse = n ? sqrt(se / n) : NAN;
	res->wcost = wcost;
	res->rel_rmse = n && sy > 0 ? res->rmse / (sy / n) : NAN;
	res->pixels = nsel;
}

static int fit_or_eval(struct glint_renderer *r,
		       const struct glint_model_ops *model,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, const double *eval_p,
		       struct glint_fit_result *res)
{
	const struct glint_gbuffer *gb = &r->gb;
	struct fit_data d = { 0 };
	struct objective ob;
	int *all = NULL, *coarse = NULL, *spec = NULL, *diff = NULL;
	int freev[GLINT_MAX_PARAMS];
	struct glint_lm_result lr;
	int ret, interior;
	double t0 = glint_now();

	if (model->transparent)
		return glint_fit_dielectric(r, model, photo, weight, o, NULL,
					    eval_p, res);
	memset(res, 0, sizeof(*res));
	memset(&ob, 0, sizeof(ob));
	res->model = model;
	if (model->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "model %s cannot be fitted by LM here "
				       "(no linear lobes)",
				       model->name);
	ret = fit_data_prepare(gb, photo, weight, o, &d, &interior);
	if (ret < 0)
		goto out;
	res->interior = interior;

	ob.r = r;
	ob.m = model;
	ob.d = &d;
	ob.o = o;
	for (int k = 0; k < model->nparams; k++) {
		ob.p[k] = o->start ? o->start[k] : model->params[k].def;
		ob.lobe_of[k] = ob.chan_of[k] = -1;
	}
	for (int j = 0; j < model->nlobes; j++)
		for (int c = 0; c < 3; c++) {
			ob.lobe_of[model->lobe_param[j] + c] = j;
			ob.chan_of[model->lobe_param[j] + c] = c;
		}
	ob.lobes = malloc((size_t)d.n * model->nlobes * 3 * sizeof(double));
	ob.lobes2 = malloc((size_t)d.n * model->nlobes * 3 * sizeof(double));
	all = malloc((size_t)d.n * sizeof(int));
	coarse = malloc((size_t)d.n * sizeof(int));
	spec = malloc((size_t)d.n * sizeof(int));
	diff = malloc((size_t)d.n * sizeof(int));
	if (!ob.lobes || !ob.lobes2 || !all || !coarse || !spec || !diff) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	if (o->faithful) {
		ob.img = glint_image_new(gb->width, gb->height);
		if (!ob.img) {
			ret = -ENOMEM;
			goto out;
		}
	} else {
		struct glint_shade_cache_opts co = {
			.light_samples = o->light_samples,
			.lobe_samples = o->lobe_samples,
			.static_samples = o->static_samples,
			.nthreads = o->nthreads,
		};
		ret = glint_shade_cache_new(gb, d.pix, d.n, r->env, model, &co,
					    &ob.cache);
		if (ret < 0)
			goto out;
	}
	res->setup_seconds = glint_now() - t0;
	if (eval_p) {
		for (int i = 0; i < d.n; i++)
			all[i] = i;
		memcpy(ob.p, eval_p, (size_t)model->nparams * sizeof(double));
		memcpy(res->p, ob.p, sizeof(res->p));
		finish_stats(&ob, all, d.n, res);
		res->seconds = glint_now() - t0;
		ret = 0;
		goto out;
	}

	/*
	 * Selections.  The masks are computed on every fitted pixel; the
	 * coarse set is every 4th row and column plus every specular pixel:
	 * a grid alone can miss a small glint, and the glint is what pins
	 * roughness down (without it the coarse passes drift to any lobe).
	 */
	int nall = d.n, ncoarse = 0, nspec = 0, ndiff = 0;
	unsigned char *is_spec = calloc((size_t)d.n, 1);
	if (!is_spec) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	for (int i = 0; i < d.n; i++)
		all[i] = i;
	/* The white render: the constant lobes at albedo 1 (the faithful
	 * path renders a white Lambertian sphere in full). */
	double *white = malloc((size_t)d.n * 3 * sizeof(double));
	double *ratio = malloc((size_t)d.n * sizeof(double));
	if (!white || !ratio) {
		free(white);
		free(ratio);
		free(is_spec);
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	if (o->faithful) {
		double white_p[GLINT_MAX_PARAMS] = { 1, 1, 1 };
		struct objective wob = ob;
		wob.m = &glint_model_lambert;
		ret = render_full(&wob, white_p);
		for (int s = 0; s < d.n && !ret; s++)
			for (int c = 0; c < 3; c++)
				white[3 * s + c] =
					glint_image_px(ob.img, d.xy[2 * s],
						       d.xy[2 * s + 1])[c];
	} else {
		int nj = model->nlobes;
		double *wl = malloc((size_t)d.n * nj * 3 * sizeof(double));
		ret = wl ? 0 : glint_error_set(ENOMEM, "out of memory");
		if (wl)
			glint_shade_cache_lobes_sel(ob.cache, ob.p, all, d.n,
						    wl);
		for (int s = 0; s < d.n && wl; s++)
			for (int c = 0; c < 3; c++) {
				double w = 0;
				for (int j = 0; j < nj; j++)
					if (!model->lobe_varies[j])
						w += wl[((size_t)s * nj + j) *
								3 +
							c];
				white[3 * s + c] = w;
			}
		free(wl);
	}
	/*
	 * The specular mask.  The paper marks pixels where the photo exceeds
	 * the white render by more than a threshold; but a dark glossy
	 * material's highlights never outshine a white sphere (satin paint:
	 * 0.27 against 1.5), which leaves the mask empty and pass 1 fitting
	 * diffuse albedo on highlights.  A Lambertian surface of unknown
	 * albedo a shows photo = a x white everywhere, so glint marks the
	 * pixels whose ratio photo / white exceeds the median ratio by more
	 * than the threshold; the paper's rule is the case a = 1.
	 */
	int nr = 0;
	for (int s = 0; s < d.n && !ret; s++) {
		double pw = rgb_luminance(d.y[3 * s], d.y[3 * s + 1],
					  d.y[3 * s + 2]);
		double ww = rgb_luminance(white[3 * s], white[3 * s + 1],
					  white[3 * s + 2]);
		ratio[s] = ww > 0 ? pw / ww : 0;
		nr++;
	}
	double med = 0;
	if (!ret && nr) {
		double *tmp = malloc((size_t)nr * sizeof(double));
		if (tmp) {
			memcpy(tmp, ratio, (size_t)nr * sizeof(double));
			med = median_of(tmp, nr);
			free(tmp);
		}
	}
	for (int s = 0; s < d.n && !ret; s++)
		is_spec[s] = ratio[s] > (1 + o->mask_threshold) * med;
	free(white);
	free(ratio);
	if (ret < 0) {
		free(is_spec);
		goto out;
	}
	for (int s = 0; s < d.n; s++) {
		int on_grid = d.xy[2 * s] % (4 * d.stride) == 0 &&
			      d.xy[2 * s + 1] % (4 * d.stride) == 0;
		if (is_spec[s])
			spec[nspec++] = s;
		if (on_grid || is_spec[s])
			coarse[ncoarse++] = s;
	}
	if (!o->coarse_to_fine || ncoarse < 64 || ncoarse > nall / 2) {
		memcpy(coarse, all, (size_t)nall * sizeof(int));
		ncoarse = nall;
	}
	/* The diffuse mask, within the set the passes run on. */
	for (int t = 0; t < ncoarse; t++)
		if (!is_spec[coarse[t]])
			diff[ndiff++] = coarse[t];
	free(is_spec);
	res->specular_pixels = nspec;
	/*
	 * A level sampled every `spacing` pixels cannot tell lobes narrower
	 * than the reflected directions between its samples (about
	 * 2 spacing / R radians on a sphere R pixels in radius, i.e. a
	 * roughness of spacing / R): a mirror's glint can fall between
	 * samples and "mirror" becomes a false minimum.  Coarse passes keep
	 * roughness above that; the fine pass is free.
	 */
	if (ncoarse < nall) {
		double radius_px = sqrt(interior / M_PI);
		ob.rough_lo = 4.0 * d.stride / radius_px;
	}

	if (o->optimizer == GLINT_OPT_ANNEAL && !eval_p) {
		/* Annealing over everything, then LM over everything. */
		ret = anneal_pass(&ob, coarse, ncoarse, res);
		for (int k = 0; k < model->nparams && ret == 0; k++)
			freev[k] = 1;
		if (ret == 0)
			ret = run_pass(&ob, "anneal-polish", coarse, ncoarse,
				       freev, 0, res, &lr);
	} else
		switch (o->method) {
		case GLINT_FIT_THREE_PASS: {
			/* Pass 1: constant lobes only, the others switched off.
			 */
			for (int k = 0; k < model->nparams; k++) {
				int j = ob.lobe_of[k];
				freev[k] = j >= 0 && !model->lobe_varies[j];
				if (j >= 0 && model->lobe_varies[j])
					ob.p[k] = 0;
			}
			if (ndiff < 8) {
				memcpy(diff, coarse,
				       (size_t)ncoarse * sizeof(int));
				ndiff = ncoarse;
			}
			ret = run_pass(&ob, "1 diffuse", diff, ndiff, freev, 0,
				       res, &lr);
			if (ret < 0)
				goto out;
			/* Pass 2: the rest from the paper's values, diffuse
			 * held. */
			int any = 0;
			for (int k = 0; k < model->nparams; k++) {
				int j = ob.lobe_of[k];
				freev[k] = !(j >= 0 && !model->lobe_varies[j]);
				any |= freev[k];
				if (freev[k])
					ob.p[k] =
						o->start ? o->start[k]
							 : model->params[k].def;
			}
			if (any) {
				const int *sel = nspec >= 8 ? spec : coarse;
				int nsel = nspec >= 8 ? nspec : ncoarse;
				ret = scan_start(&ob, sel, nsel);
				if (ret < 0)
					goto out;
				ret = run_pass(&ob, "2 specular", sel, nsel,
					       freev, 0, res, &lr);
				if (ret < 0)
					goto out;
			}
			/* Pass 3: everything, all pixels. */
			for (int k = 0; k < model->nparams; k++)
				freev[k] = 1;
			ret = run_pass(&ob, "3 all", coarse, ncoarse, freev, 0,
				       res, &lr);
			break;
		}
		case GLINT_FIT_NAIVE:
			ret = scan_start(&ob, coarse, ncoarse);
			if (ret < 0)
				goto out;
			for (int k = 0; k < model->nparams; k++)
				freev[k] = 1;
			ret = run_pass(&ob, "all at once", coarse, ncoarse,
				       freev, 0, res, &lr);
			break;
		case GLINT_FIT_VARPRO: {
			if (o->faithful) {
				ret = glint_error_set(
					EINVAL, "variable projection needs the "
						"shade cache (not --faithful)");
				goto out;
			}
			/* Coarse scan of the first nonlinear parameter
			 * (roughness for Torrance-Sparrow), log-spaced, then
			 * LM. */
			int nl = -1;
			for (int k = 0; k < model->nparams; k++) {
				freev[k] = ob.lobe_of[k] < 0;
				if (freev[k] && nl < 0)
					nl = k;
			}
			if (nl >= 0) {
				const struct glint_param *pi =
					&model->params[nl];
				double best = INFINITY, bestv = pi->def;
				double lo = fmax(pi->lo, 1e-3),
				       hi = fmin(pi->hi, 0.6);
				if (nl == model->roughness_param)
					lo = fmax(lo, ob.rough_lo);
				double *scratch = malloc((size_t)3 * ncoarse *
							 sizeof(double));
				if (!scratch) {
					ret = -ENOMEM;
					goto out;
				}
				ob.sel = coarse;
				ob.nsel = ncoarse;
				ob.varpro = 1;
				ob.nfree = 0;
				for (int i = 0; i < 10; i++) {
					double v = lo * pow(hi / lo, i / 9.0);
					ob.p[nl] = v;
					ob.memo_valid = 0;
					obj_residuals(&ob, ob.p, scratch);
					double c = 0;
					for (int k = 0; k < 3 * ncoarse; k++)
						c += scratch[k] * scratch[k];
					if (c < best) {
						best = c;
						bestv = v;
					}
				}
				free(scratch);
				ob.p[nl] = bestv;
				ret = run_pass(&ob, "varpro", coarse, ncoarse,
					       freev, 1, res, &lr);
			}
			break;
		}
		}
	if (ret < 0)
		goto out;
	/* Coarse to fine: polish everything on the full pixel set. */
	ob.rough_lo = 0;
	if (ncoarse < nall && model->roughness_param >= 0) {
		/* The coarse level could not see lobes below its spacing:
		 * before polishing, compare the coarse result with sharper and
		 * rougher lobes at full resolution, albedos solved exactly for
		 * each, and start from the best. */
		/* Below the coarse bound (which the coarse level could not
		 * resolve), log-spaced down to the model's bound. */
		ret = rescan_roughness(
			&ob, all, nall,
			fmax(model->params[model->roughness_param].lo, 1e-3),
			4.0 * d.stride / sqrt(interior / M_PI), 6);
		if (ret < 0)
			goto out;
	}
	if (ncoarse < nall) {
		int vp = o->method == GLINT_FIT_VARPRO;
		for (int k = 0; k < model->nparams; k++)
			freev[k] = vp ? ob.lobe_of[k] < 0 : 1;
		ret = run_pass(&ob, "fine", all, nall, freev, vp, res, &lr);
		if (ret < 0)
			goto out;
	}
	/* Standard errors over every parameter at the optimum: an LM call
	 * that takes no step but computes the Jacobian. */
	{
		struct glint_lm_result fin;
		struct glint_fit_result dummy = { 0 };
		struct glint_fit_opts o0 = *o;
		o0.max_iter = 0;
		ob.o = &o0;
		for (int k = 0; k < model->nparams; k++)
			freev[k] = 1;
		ret = run_pass(&ob, "errors", all, nall, freev, 0, &dummy,
			       &fin);
		ob.o = o;
		if (ret < 0)
			goto out;
		for (int k = 0; k < model->nparams; k++) {
			res->se[k] = fin.se[k];
			res->at_bound[k] = fin.at_bound[k];
		}
		res->cost = fin.cost;
	}
	memcpy(res->p, ob.p, sizeof(res->p));
	finish_stats(&ob, all, nall, res);
	res->backdrop_rel_rmse = backdrop_error(gb, r->env, &d);
	res->seconds = glint_now() - t0;
	if (res->backdrop_rel_rmse < res->rel_rmse) {
		ret = glint_error_set(EINVAL,
				      "the photo shows the backdrop, not a "
				      "sphere, where the scene puts it (the "
				      "bare environment explains it with a "
				      "relative RMSE of %.3f, the fitted "
				      "sphere only %.3f): wrong scene or "
				      "sphere position?",
				      res->backdrop_rel_rmse, res->rel_rmse);
		goto out;
	}
	ret = 0;
out:
	glint_shade_cache_free(ob.cache);
	glint_image_free(ob.img);
	free(ob.lobes);
	free(ob.lobes2);
	free(all);
	free(coarse);
	free(spec);
	free(diff);
	free_data(&d);
	return ret;
}

int glint_fit(struct glint_renderer *r, const struct glint_model_ops *model,
	      const struct glint_image *photo, const struct glint_image *weight,
	      const struct glint_fit_opts *o, struct glint_fit_result *res)
{
	return fit_or_eval(r, model, photo, weight, o, NULL, res);
}

int glint_fit_evaluate(struct glint_renderer *r,
		       const struct glint_model_ops *model,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, const double *p,
		       struct glint_fit_result *res)
{
	return fit_or_eval(r, model, photo, weight, o, p, res);
}
