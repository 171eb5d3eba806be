/* SPDX-License-Identifier: MIT */
/*
 * Monte Carlo sample sets: pixel blocks, more sets of light and lobe samples,
 * the refit on their mean.
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

/* The block of each residual: an 8 x 8 grid over each photo's fitted
 * pixels' bounding box, numbered densely; returns the number of
 * blocks. */
int fit_pixel_blocks(const struct objective *ob, const int *sel, int nsel,
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
		int v = fit_view_of(ob, sel[t]);
		x0[v] = x < x0[v] ? x : x0[v];
		y0[v] = y < y0[v] ? y : y0[v];
		x1[v] = x > x1[v] ? x : x1[v];
		y1[v] = y > y1[v] ? y : y1[v];
	}
	for (int b = 0; b < ob->nviews * G * G; b++)
		ids[b] = -1;
	for (int t = 0; t < nsel; t++) {
		int v = fit_view_of(ob, sel[t]);
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
int fit_sample_sets(struct objective *ob, int more,
		    struct glint_shade_cache **sets, int *nsets)
{
	int ret = 0;

	sets[0] = ob->cache;
	*nsets = 1;
	for (int k = 1; k <= more && !ret; k++) {
		ret = fit_new_cache(ob, (uint32_t)k, &sets[k]);
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

int fit_sets_residuals(void *ctx, const double *q, double *r)
{
	struct sets_objective *so = ctx;
	struct objective *ob = so->ob;
	struct glint_shade_cache *fitted = ob->cache;
	int rows = 3 * ob->nsel, ret = 0;

	so->have_res = 0;
	/* The fitted set last: its lobes stay memoised for the Jacobian. */
	size_t nl = (size_t)ob->nsel * ob->m->bxdf->nlobes * 3 * sizeof(double);
	for (int k = so->nsets - 1; k >= 0 && !ret; k--) {
		/* the memo holds one set's lobes (memo_cache): the fitted
		 * set's from the pass before is used where it is at q */
		ob->cache = so->sets[k];
		ret = fit_obj_residuals(ob, q, so->each + (size_t)k * rows);
		size_t all = (size_t)ob->d->n * ob->m->bxdf->nlobes * 3 *
			     sizeof(double);
		if (!ob->set_lobes[k])
			ob->set_lobes[k] = malloc(all);
		if (!ob->set_dlobes[k] && ob->memo_d)
			ob->set_dlobes[k] = malloc(all);
		if (ret == 0 && ob->set_lobes[k] && ob->memo_valid) {
			memcpy(ob->set_lobes[k], ob->lobes, nl);
			memcpy(ob->set_lobes_p[k], ob->memo_p,
			       sizeof(ob->memo_p));
			ob->set_has_d[k] = ob->memo_d && ob->set_dlobes[k];
			if (ob->set_has_d[k])
				memcpy(ob->set_dlobes[k], ob->dlobes, nl);
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

void fit_set_memo(struct objective *ob, int k, const double *p)
{
	ob->cache = ob->sets[k];
	if (ob->memo_valid && ob->memo_cache == ob->cache &&
	    ob->memo_sel == ob->sel && ob->memo_nsel == ob->nsel &&
	    fit_nonlinear_same(ob, p, ob->memo_p))
		return;
	ob->memo_valid = 0;
	if (!ob->set_lobes[k] || !fit_nonlinear_same(ob, p, ob->set_lobes_p[k]))
		return;
	size_t nl = (size_t)ob->nsel * ob->m->bxdf->nlobes * 3 * sizeof(double);
	memcpy(ob->lobes, ob->set_lobes[k], nl);
	ob->memo_d = ob->set_has_d[k];
	if (ob->memo_d)
		memcpy(ob->dlobes, ob->set_dlobes[k], nl);
	memcpy(ob->memo_p, p, sizeof(ob->memo_p));
	ob->memo_valid = 1;
	ob->memo_cache = ob->cache;
	ob->memo_sel = ob->sel;
	ob->memo_nsel = ob->nsel;
}

/*
 * The Jacobian of the sets' mean: the mean of each set's own (kept in
 * ob->set_jac for the sampling lean, fit/intervals.c).  Each set's lobes
 * at q are its last evaluation's, so a set's Jacobian shades only the
 * columns of the parameters that are neither albedos nor the factor
 * parameter (roughness).  One set's Jacobian does not stand for the
 * mean's: at 8 + 8 samples its roughness column carries that set's
 * Monte Carlo error, and LM creeps toward the mean's optimum in small
 * steps and stops short of it (nylon's dim one-frame photo under the
 * overcast class, sim/light_class.c: roughness 0.0566 for 0.067 with
 * the fitted set's Jacobian after 2 iterations and 0.0606 after 6,
 * where the mean's optimum, which costs less, is at 0.0635).
 */
static int sets_jacobian(void *ctx, const double *q, const double *r,
			 double *jac)
{
	struct sets_objective *so = ctx;
	struct objective *ob = so->ob;
	struct glint_shade_cache *fitted = ob->cache;
	int n = ob->nfree, ret = 0;
	size_t nj = (size_t)n * 3 * ob->nsel;

	(void)r;
	so->have_jac = 0;
	ob->set_jac_n = 0;
	if (ob->set_jac_size < nj * so->nsets) {
		free(ob->set_jac);
		ob->set_jac = malloc(sizeof(double) * nj * so->nsets);
		ob->set_jac_size = ob->set_jac ? nj * so->nsets : 0;
		if (!ob->set_jac)
			return glint_error_set(ENOMEM, "out of memory");
	}
	/* the fitted set first: its lobes at q are the memo's */
	for (int k = 0; k < so->nsets && ret == 0; k++) {
		fit_set_memo(ob, k, q);
		ret = fit_obj_jacobian(ob, q, NULL, ob->set_jac + nj * k);
	}
	ob->cache = fitted;
	if (ret < 0)
		return ret;
	for (size_t i = 0; i < nj; i++) {
		double sum = 0;
		for (int k = 0; k < so->nsets; k++)
			sum += ob->set_jac[nj * k + i];
		jac[i] = sum / so->nsets;
	}
	memcpy(ob->set_jac_p, ob->p, sizeof(ob->set_jac_p));
	for (int k = 0; k < n; k++)
		ob->set_jac_p[ob->free_idx[k]] = q[k];
	ob->set_jac_n = so->nsets;
	if (so->jac_last) {
		memcpy(so->jac_last, jac, sizeof(double) * nj);
		memcpy(so->q_jac, q, sizeof(double) * (size_t)n);
		so->have_jac = 1;
	}
	return 0;
}

/*
 * The final estimate on the average of several independent sample sets.
 * A fit on one fixed set minimises that set's estimate, whose Monte Carlo
 * error grows or shrinks with the parameters, and the optimum leans
 * towards where the error is smallest, the same way for every set: at
 * 192 px and 8 + 8 samples, silver under Venice came out 9 % low in
 * roughness for every seed, a fit at 32 + 32 samples within 1 %.  So
 * from the fitted optimum a short LM polish on the sets' average (their
 * mean residuals and the mean of their Jacobians).  Leaves each set's
 * residuals and their mean at the final ob->p in each and r, the
 * Jacobian in jac.
 */
int fit_refine_on_sets(struct objective *ob,
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
	ob->set_jac_n = 0;
	if (nsets > 1) {
		struct glint_lm_problem pr = {
			n, rows, lo, hi, fit_sets_residuals, sets_jacobian, &so,
		};
		so.jac_last = malloc(sizeof(double) * (size_t)rows * n);
		fit_objective_lm_opts(&lo_opts, ob->o->polish_iter, &pc);
		/* every set's footprint blend at the polish's start: one
		 * form of the estimate for the solve and what follows
		 * (glint_shade_cache_fix_footprint()) */
		for (int k = 0; k < nsets; k++)
			glint_shade_cache_fix_footprint(sets[k], ob->p);
		ret = glint_lm_solve(&pr, &lo_opts, q, &lr);
		if (ret < 0)
			goto out;
		memcpy(ob->p, q, qb);
		char name[32];
		snprintf(name, sizeof(name), "%d sample sets", nsets);
		fit_add_pass(res, name, ob->nsel, lr.iterations, lr.evaluations,
			     lr.cost0, lr.cost, t0);
	}
	/* At the polish's end, usually where it last evaluated both. */
	if (so.have_res && !memcmp(so.q_res, ob->p, qb))
		sets_mean(&so, rows, r);
	else
		ret = fit_sets_residuals(&so, ob->p, r);
	if (ret == 0 && so.have_jac && !memcmp(so.q_jac, ob->p, qb))
		memcpy(jac, so.jac_last, sizeof(double) * (size_t)rows * n);
	else if (ret == 0)
		ret = sets_jacobian(&so, ob->p, r, jac);
out:
	free(so.jac_last);
	return ret;
}
