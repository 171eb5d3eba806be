/* SPDX-License-Identifier: MIT */
/*
 * Fitting a transparent sphere: transmission RGB and ior against the photo
 * over the pixels wholly on the sphere.  A change of ior re-traces the
 * paths (fit/render/dielectric_paths.h; a few caches are kept, keyed by ior); a
 * change of transmission is a re-sum, and its Jacobian columns are exact.
 * Optimiser: adaptive simulated annealing on a coarse pixel subset, then
 * an LM polish on all of them (the paper's choice for these spheres), or
 * LM alone from the start values.
 */
#include "fit/optim/anneal.h"
#include "fit/render/dielectric_paths.h"
#include "fit.h"
#include "fit_data.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NCACHE 3

struct dcache {
	struct glint_dielectric_cache c;
	int valid;
	unsigned long used;
};

/* Refraction shows the map's sharp detail magnified: at the renderer's
 * usual 4 samples per pixel it aliases into biased transmission (blue
 * quartz under the studio map: transmission.b off by 0.026 at 4, 0.009 at
 * 16; docs/fitting.md), so transparent fits trace at least this many. */
#define DIELECTRIC_MIN_SPP 16

struct dobj {
	struct glint_renderer *r;
	const struct glint_gbuffer *gb;
	const struct fit_data *d;
	const int32_t *pix; /* the pixels of the current pass */
	int n;
	const int *idx; /* their rows in d */
	struct dcache cache[NCACHE];
	unsigned long tick;
	struct glint_dielectric_opts dopt;
	int nthreads;
	double *rgb, *drgb;
	int evals, traces;
	double fd_h; /* ior step for its Jacobian column */
};

static void drop_caches(struct dobj *ob)
{
	for (int i = 0; i < NCACHE; i++) {
		if (ob->cache[i].valid)
			glint_dielectric_cache_free(&ob->cache[i].c);
		ob->cache[i].valid = 0;
	}
}

/* Paths for this ior (the least recently used cache is replaced). */
static int paths_for(struct dobj *ob, double ior,
		     const struct glint_dielectric_cache **out)
{
	int lru = 0;
	for (int i = 0; i < NCACHE; i++) {
		if (ob->cache[i].valid && ob->cache[i].c.ior == ior) {
			ob->cache[i].used = ++ob->tick;
			*out = &ob->cache[i].c;
			return 0;
		}
		if (!ob->cache[i].valid ||
		    ob->cache[i].used < ob->cache[lru].used)
			lru = i;
	}
	struct dcache *dc = &ob->cache[lru];
	if (dc->valid)
		glint_dielectric_cache_free(&dc->c);
	dc->valid = 0;
	const struct glint_scene *sc = &ob->r->scene;
	int ret = glint_dielectric_trace(ob->r->tracer, ob->gb, ob->pix, ob->n,
					 ob->r->env, sc->sphere_centre,
					 sc->sphere_radius, ior, &ob->dopt,
					 ob->nthreads, &dc->c);
	if (ret < 0)
		return ret;
	ob->traces++;
	dc->valid = 1;
	dc->used = ++ob->tick;
	*out = &dc->c;
	return 0;
}

static int residuals(void *ctx, const double *p, double *r)
{
	struct dobj *ob = ctx;
	const struct glint_dielectric_cache *c;
	int ret = paths_for(ob, p[3], &c);
	if (ret < 0)
		return ret;
	glint_dielectric_shade(c, p, ob->rgb);
	for (int t = 0; t < ob->n; t++) {
		int i = ob->idx[t];
		for (int ch = 0; ch < 3; ch++)
			r[3 * t + ch] =
				ob->d->sw[3 * i + ch] *
				(ob->rgb[3 * t + ch] - ob->d->y[3 * i + ch]);
	}
	ob->evals++;
	return 0;
}

static int jacobian(void *ctx, const double *p, const double *r, double *J)
{
	struct dobj *ob = ctx;
	const struct glint_dielectric_cache *c;
	int m = 3 * ob->n, ret = paths_for(ob, p[3], &c);
	if (ret < 0)
		return ret;
	glint_dielectric_dshade(c, p, ob->drgb);
	memset(J, 0, (size_t)m * 4 * sizeof(double));
	for (int t = 0; t < ob->n; t++) {
		int i = ob->idx[t];
		for (int ch = 0; ch < 3; ch++)
			J[(size_t)(3 * t + ch) * 4 + ch] =
				ob->d->sw[3 * i + ch] * ob->drgb[3 * t + ch];
	}
	/* ior: central difference on re-traced paths (one side at the
	 * bounds). */
	double h = ob->fd_h, lo = p[3] - h, hi = p[3] + h;
	const struct glint_model *md = &glint_model_dielectric;
	if (lo < md->params[3].lo)
		lo = p[3];
	if (hi > md->params[3].hi)
		hi = p[3];
	double q[4] = { p[0], p[1], p[2], hi };
	double *r1 = malloc((size_t)m * 2 * sizeof(double));
	if (!r1)
		return -ENOMEM;
	double *r0 = r1 + m;
	ret = residuals(ob, q, r1);
	if (!ret && lo != p[3]) {
		q[3] = lo;
		ret = residuals(ob, q, r0);
	} else if (!ret) {
		memcpy(r0, r, (size_t)m * sizeof(double));
	}
	for (int k = 0; k < m && !ret; k++)
		J[(size_t)k * 4 + 3] = (r1[k] - r0[k]) / (hi - lo);
	free(r1);
	return ret;
}

/* Weighted cost of channel ch under transmission t, from the paths. */
static double channel_cost(struct dobj *ob,
			   const struct glint_dielectric_cache *c, int ch,
			   double t)
{
	double lt = log(fmax(t, 1e-300)), cost = 0;
	for (int k = 0; k < c->n; k++) {
		double v = 0;
		for (int64_t q = c->first[k]; q < c->first[k + 1]; q++) {
			const struct glint_dpath *p = &c->paths[q];
			v += p->w * exp(lt * p->len) * p->rgb[ch];
		}
		int i = ob->idx[k];
		double e = ob->d->sw[3 * i + ch] * (v - ob->d->y[3 * i + ch]);
		cost += 0.5 * e * e;
	}
	return cost;
}

/* For the paths of one ior, the best transmission: the channels are
 * independent and each pixel's value rises with T, so each channel is a
 * one-dimensional search (golden section on [0, 1], to 1e-5; the LM
 * polish refines it). */
static double best_transmission(struct dobj *ob,
				const struct glint_dielectric_cache *c,
				double T[3])
{
	const double g = 0.5 * (sqrt(5) - 1);
	double total = 0;
	for (int ch = 0; ch < 3; ch++) {
		double a = 0, b = 1;
		double x1 = b - g * (b - a), x2 = a + g * (b - a);
		double f1 = channel_cost(ob, c, ch, x1);
		double f2 = channel_cost(ob, c, ch, x2);
		while (b - a > 1e-5) {
			if (f1 < f2) {
				b = x2;
				x2 = x1;
				f2 = f1;
				x1 = b - g * (b - a);
				f1 = channel_cost(ob, c, ch, x1);
			} else {
				a = x1;
				x1 = x2;
				f1 = f2;
				x2 = a + g * (b - a);
				f2 = channel_cost(ob, c, ch, x2);
			}
		}
		T[ch] = f1 < f2 ? x1 : x2;
		total += fmin(f1, f2);
	}
	return total;
}

/* Annealing's cost: a function of ior alone, the transmission at its best
 * for that ior (a re-sum on the traced paths, no re-trace). */
static int ior_cost(void *ctx, const double *x, double *cost)
{
	struct dobj *ob = ctx;
	const struct glint_dielectric_cache *c;
	double T[3];
	int ret = paths_for(ob, x[0], &c);
	if (ret < 0)
		return ret;
	ob->evals++;
	*cost = best_transmission(ob, c, T);
	return 0;
}

static int anneal_cost(void *ctx, const double *p, double *cost)
{
	struct dobj *ob = ctx;
	double *r = malloc((size_t)ob->n * 3 * sizeof(double));
	if (!r)
		return -ENOMEM;
	int ret = residuals(ob, p, r);
	double s = 0;
	for (int k = 0; k < 3 * ob->n; k++)
		s += r[k] * r[k];
	free(r);
	*cost = 0.5 * s;
	return ret;
}

static void set_pixels(struct dobj *ob, const int *idx, int n, int32_t *pix)
{
	for (int t = 0; t < n; t++)
		pix[t] = ob->d->pix[idx[t]];
	drop_caches(ob);
	ob->idx = idx;
	ob->pix = pix;
	ob->n = n;
}

/* The global search on the coarse pixels: annealing over ior, the
 * transmission following from each ior's paths; a pass in res. */
static int anneal_search(struct dobj *ob, const struct glint_fit_opts *o,
			 const double *lo, const double *hi, int *coarse,
			 int ncoarse, int32_t *pix, double *p,
			 struct glint_fit_result *res)
{
	struct glint_anneal_opts ao;
	struct glint_anneal_result ar;
	const struct glint_dielectric_cache *bc;

	glint_anneal_default_opts(&ao);
	ao.seed = o->seed;
	ao.max_evals = o->anneal_evals;
	ao.stall_evals = o->anneal_evals / 3;
	set_pixels(ob, coarse, ncoarse, pix);
	double ts = glint_clock_monotonic();
	int e0 = ob->evals;
	int ret =
		glint_anneal(1, lo + 3, hi + 3, ior_cost, ob, &ao, p + 3, &ar);
	if (ret == 0)
		ret = paths_for(ob, p[3], &bc);
	if (ret < 0)
		return ret;
	best_transmission(ob, bc, p);
	struct glint_fit_pass *ps = &res->passes[res->npasses++];
	snprintf(ps->name, sizeof(ps->name), "anneal");
	ps->pixels = ncoarse;
	ps->iterations = ar.accepted;
	ps->evaluations = ob->evals - e0;
	ps->cost0 = ar.cost0;
	ps->cost = ar.cost;
	ps->seconds = glint_clock_monotonic() - ts;
	glint_log_info("anneal: %d evaluations (%d accepted, %d re-anneals), "
		       "cost %.4g -> %.4g: %s",
		       ar.evals, ar.accepted, ar.reanneals, ar.cost0, ar.cost,
		       ar.reason);
	return 0;
}

/*
 * Shot-noise weights taken from the photo favour pixels that came out dark
 * by chance (sampling noise, aliasing of the map's sharp detail): the fit
 * is pulled low (purple quartz under the studio map: transmission.b 0.09
 * low).  Re-weight by the fitted render at p instead (iteratively
 * re-weighted least squares).
 */
static int reweight_by_render(struct dobj *ob, struct fit_data *d,
			      const double *p)
{
	const struct glint_dielectric_cache *wc;
	int ret = paths_for(ob, p[3], &wc);
	if (ret < 0)
		return ret;
	glint_dielectric_shade(wc, p, ob->rgb);
	double mean = 0;
	int nv = 0;
	for (int i = 0; i < 3 * d->n; i++)
		if (d->sw[i] > 0) {
			mean += fmax(0, ob->rgb[i]);
			nv++;
		}
	mean = nv ? mean / nv : 1;
	for (int i = 0; i < 3 * d->n; i++)
		if (d->sw[i] > 0)
			d->sw[i] = 1 / sqrt(fmax(0, ob->rgb[i]) + 0.1 * mean);
	return 0;
}

/* LM over all four parameters on every pixel (re-weighted twice under
 * Poisson weights), or with eval_p only the cost there; a pass in res. */
static int lm_stage(struct dobj *ob, struct fit_data *d,
		    const struct glint_fit_opts *o,
		    const struct glint_image *weight, double *lo, double *hi,
		    const double *eval_p, double *p, struct glint_lm_result *lr,
		    struct glint_fit_result *res)
{
	struct glint_lm_problem pr = { 4,	  3 * ob->d->n, lo, hi,
				       residuals, jacobian,	ob };
	struct glint_lm_opts lo_;
	int ret;

	glint_lm_default_opts(&lo_);
	lo_.max_iter = o->max_iter;
	if (eval_p) {
		double c = NAN;
		ret = anneal_cost(ob, p, &c);
		lr->cost = lr->cost0 = c;
		for (int k = 0; k < 4; k++)
			lr->se[k] = NAN;
		return ret;
	}
	double ts = glint_clock_monotonic();
	int e0 = ob->evals;
	ret = glint_lm_solve(&pr, &lo_, p, lr);
	for (int it = 0; it < 2 && ret == 0 && !weight &&
			 o->weighting == GLINT_WEIGHT_POISSON;
	     it++) {
		ret = reweight_by_render(ob, d, p);
		if (ret == 0)
			ret = glint_lm_solve(&pr, &lo_, p, lr);
	}
	struct glint_fit_pass *ps = &res->passes[res->npasses++];
	snprintf(ps->name, sizeof(ps->name), "%s",
		 res->npasses > 1 ? "lm-polish" : "lm");
	ps->pixels = ob->d->n;
	ps->iterations = lr->iterations;
	ps->evaluations = ob->evals - e0;
	ps->cost0 = lr->cost0;
	ps->cost = lr->cost;
	ps->seconds = glint_clock_monotonic() - ts;
	return ret;
}

/* The result's parameters and statistics at p. */
static int statistics(struct dobj *ob, const double *p,
		      const struct glint_lm_result *lr,
		      struct glint_fit_result *res)
{
	const struct glint_dielectric_cache *c;
	const struct fit_data *d = ob->d;
	int ret = paths_for(ob, p[3], &c);
	if (ret < 0)
		return ret;
	glint_dielectric_shade(c, p, ob->rgb);
	double se = 0, sy = 0, wc = 0;
	int nv = 0;
	for (int i = 0; i < 3 * d->n; i++) {
		if (d->sw[i] <= 0)
			continue;
		double e = ob->rgb[i] - d->y[i];
		se += e * e;
		wc += 0.5 * e * e * d->sw[i] * d->sw[i];
		sy += d->y[i];
		nv++;
	}
	for (int k = 0; k < 4; k++) {
		res->p[k] = p[k];
		res->se[k] = lr->se[k];
		res->at_bound[k] = lr->at_bound[k];
	}
	res->cost = lr->cost;
	res->wcost = wc;
	res->rmse = nv ? sqrt(se / nv) : NAN;
	res->rel_rmse = nv && sy > 0 ? res->rmse / (sy / nv) : NAN;
	res->pixels = d->n;
	res->backdrop_rel_rmse = NAN;
	fit_data_baselines(d, &res->flat_rel_rmse, &res->noise_rmse);
	glint_log_info("dielectric fit: %d evaluations, %d path traces, "
		       "largest dropped branch weight %.2g",
		       ob->evals, ob->traces, c->dropped);
	return 0;
}

int glint_fit_dielectric(struct glint_renderer *r,
			 const struct glint_model *model,
			 const struct glint_image *photo,
			 const struct glint_image *weight,
			 const struct glint_fit_opts *o, const double *start,
			 const double *eval_p, struct glint_fit_result *res)
{
	struct fit_data d = { 0 };
	struct glint_gbuffer fine = { 0 };
	struct glint_lm_result lr;
	struct dobj ob;
	int interior, ret;
	int *all = NULL, *coarse = NULL;
	int32_t *pix = NULL;
	double lo[4], hi[4], p[4];
	double t0 = glint_clock_monotonic();

	memset(res, 0, sizeof(*res));
	memset(&ob, 0, sizeof(ob));
	memset(&lr, 0, sizeof(lr));
	res->model = model;
	struct glint_gbuffer *gb = &r->gb;
	if (r->gb.spp < DIELECTRIC_MIN_SPP) {
		ret = glint_tracer_primary_sparse(r->tracer, &r->scene.cam,
						  DIELECTRIC_MIN_SPP,
						  o->nthreads, NULL, &fine);
		if (ret < 0)
			return ret;
		gb = &fine;
	}
	ob.gb = gb;
	ret = fit_data_prepare(gb, photo, weight, o, &d, &interior);
	if (ret < 0)
		goto out;
	res->interior = interior;
	ob.r = r;
	ob.d = &d;
	ob.nthreads = o->nthreads;
	ob.fd_h = 1e-3;
	glint_dielectric_default_opts(&ob.dopt);
	all = malloc((size_t)d.n * sizeof(int));
	coarse = malloc((size_t)d.n * sizeof(int));
	pix = malloc((size_t)d.n * sizeof(int32_t));
	ob.rgb = malloc((size_t)d.n * 3 * sizeof(double));
	ob.drgb = malloc((size_t)d.n * 3 * sizeof(double));
	if (!all || !coarse || !pix || !ob.rgb || !ob.drgb) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	int ncoarse = 0;
	for (int i = 0; i < d.n; i++) {
		all[i] = i;
		/* about 1 in 8 for the global search */
		if (i % 8 == 0)
			coarse[ncoarse++] = i;
	}
	for (int k = 0; k < 4; k++) {
		lo[k] = model->params[k].lo;
		hi[k] = model->params[k].hi;
		p[k] = eval_p	  ? eval_p[k]
		       : start	  ? start[k]
		       : o->start ? o->start[k]
				  : model->params[k].def;
	}
	res->setup_seconds = glint_clock_monotonic() - t0;
	if (!eval_p && o->optimizer != GLINT_OPT_LM)
		ret = anneal_search(&ob, o, lo, hi, coarse, ncoarse, pix, p,
				    res);
	if (ret == 0) {
		set_pixels(&ob, all, d.n, pix);
		ret = lm_stage(&ob, &d, o, weight, lo, hi, eval_p, p, &lr, res);
	}
	if (ret == 0)
		ret = statistics(&ob, p, &lr, res);
	res->seconds = glint_clock_monotonic() - t0;
out:
	drop_caches(&ob);
	free(ob.rgb);
	free(ob.drgb);
	free(all);
	free(coarse);
	free(pix);
	free_data(&d);
	glint_gbuffer_free(&fine);
	return ret;
}
