/* SPDX-License-Identifier: MIT */
/*
 * Covariance and intervals: from sample sets and spatial blocks, more samples
 * where the Monte Carlo term dominates.
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

/* Per block of residuals, the sum over its residuals i and the sample
 * sets s of (r_s,i - r_i) J_s,ik (uncertainty.h's draws_jr), with J_s
 * set s's own Jacobian at ob->p: the polish's (ob->set_jac) where it
 * linearised there last, else shaded here, into jr (nblocks x n). */
static int sets_jr(struct objective *ob, int nsets, const double *each,
		   const double *r, const int *block, int nblocks, double *jr)
{
	struct glint_shade_cache *fitted = ob->cache;
	int n = ob->nfree, rows = 3 * ob->nsel, ret = 0;
	size_t nj = (size_t)rows * n;
	int kept = ob->set_jac_n == nsets &&
		   !memcmp(ob->set_jac_p, ob->p, sizeof(ob->p));
	double *js = kept ? NULL : malloc(sizeof(double) * nj);

	if (!kept && !js)
		return glint_error_set(ENOMEM, "out of memory");
	memset(jr, 0, sizeof(double) * (size_t)nblocks * n);
	for (int s = 0; s < nsets && ret == 0; s++) {
		const double *j = kept ? ob->set_jac + nj * s : js;
		if (!kept) {
			fit_set_memo(ob, s, ob->p);
			ret = fit_obj_jacobian(ob, ob->p, NULL, js);
		}
		for (int i = 0; i < rows && ret == 0; i++) {
			double d = each[(size_t)s * rows + i] - r[i];
			double *x = jr + (size_t)block[i] * n;
			for (int k = 0; k < n; k++)
				x[k] += d * j[(size_t)i * n + k];
		}
	}
	ob->cache = fitted;
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
	const struct glint_model *m = ob->m;
	double sys[GLINT_MAX_PARAMS], shared[GLINT_MAX_PARAMS] = { 0 };

	if (ob->o->no_systematic)
		memset(sys, 0, sizeof(sys));
	else
		fit_systematic(m, ob->p, ob->o->map_pixel_deg,
			       fit_blurred_sphere_px(ob), sys, shared);
	memset(res->discrepancy, 0, sizeof(res->discrepancy));
	if (!ob->o->no_discrepancy)
		fit_discrepancy(m, ob->p, share, res->discrepancy);
	/* The light's scale: the photo is linear in the light and the lobe
	 * albedos together, so a relative error s in the light's channel c
	 * is the same relative error, opposite, in every albedo of c. */
	memcpy(res->light_scale_sigma, ob->o->light_scale_sigma,
	       sizeof(res->light_scale_sigma));
	for (int k = 0; k < m->nparams; k++) {
		int c = ob->chan_of[k];
		res->light_stderr[k] =
			ob->lobe_of[k] >= 0 && c >= 0 && c < 3
				? fabs(ob->p[k]) * ob->o->light_scale_sigma[c]
				: 0;
	}
	/* each compact source's flux (its rows are the selection's) */
	res->nsources = 0;
	if (ob->nsel == sl->nall) {
		int ret = fit_source_terms(ob, jac, res);
		if (ret < 0)
			return ret;
	}
	for (int k = 0; k < m->nparams; k++) {
		double v = sys[k] * sys[k] + ob->lean_var[k] +
			   ob->gain_sys[k] * ob->gain_sys[k] +
			   res->discrepancy[k] * res->discrepancy[k] +
			   res->light_stderr[k] * res->light_stderr[k];
		for (int s = 0; s < res->nsources; s++)
			v += res->source_stderr[s][k] *
			     res->source_stderr[s][k];
		sys[k] = sqrt(v);
	}
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
		.sys_shared = shared,
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
		ret = fit_reweight(ob, d, r);
		if (ret == 0)
			ret = fit_sample_sets(ob, nsets - 1, ob->sets,
					      &ob->nsets);
		if (ret == 0)
			ret = fit_refine_on_sets(ob, ob->sets, nsets, lo, hi,
						 each, r, jac, res);
	} else {
		ret = fit_obj_residuals(ob, ob->p, r);
		if (ret == 0)
			ret = fit_jacobian_fd(ob, ob->p, r, jac);
	}
	if (ret < 0)
		return ret;
	int nblocks = fit_pixel_blocks(ob, sl->all, sl->nall, block);
	if (ob->cache && nsets > 1)
		ret = sets_jr(ob, nsets, each, r, block, nblocks, jr);
	if (ret < 0)
		return ret;
	return covariance(ob, sl, nsets, lo, hi, each, r, jac, block, nblocks,
			  ob->cache && nsets > 1 ? jr : NULL, NULL, 0, 0, res);
}

int fit_samples_factor(double mc_over_noise, double model_noise,
		       double lean_over_noise, int samples, int cap)
{
	if (!(mc_over_noise > 1 || model_noise > 0.25 ||
	      lean_over_noise > FIT_LEAN_OVER_NOISE) ||
	    samples * 2 > cap)
		return 1;
	/* The ratios fall as 1 / samples: one step to the power of two
	 * that brings them under their limits, or to the cap. */
	double need = fmax(fmax(mc_over_noise, model_noise / 0.25),
			   lean_over_noise / FIT_LEAN_OVER_NOISE);
	int f = 2;
	while (f < need && samples * f * 2 <= cap)
		f *= 2;
	return f;
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
 * which the first cannot see.  A third: the sampling lean itself
 * (fit_remove_lean()), where it is measured (beyond twice its standard
 * error), against the noise's standard error.  The lean is taken off to
 * first order, but where it is as large as the noise the first order
 * falls short: aluminium bronze under the overcast class (sim/
 * light_class.c) at 8 + 8 samples had its roughness lean measured at
 * -0.00064 against a noise of 0.00057 and the sets' spread just under
 * the noise (0.97 of it), and came out 0.0196 for 0.023, 15 % low, the
 * interval missing the truth; at 32 + 32 samples, 1.6 % low.  Over 1,
 * over 0.25 (the model's noise above half the residual's), or the lean
 * over FIT_LEAN_OVER_NOISE of the noise, the caches are rebuilt with the
 * samples times the power of two that brings all three under (the first
 * two fall as 1 / samples, the lean's ratio as well), up to max_samples
 * (64 + 64 a hit by default, 16 + 16 at a blurred camera's 16 hits a
 * pixel), and the stage runs again: once where the estimate holds, again
 * where it fell short.  Returns 1 to go again, 0 when done, or a negative
 * errno.
 */
static int more_samples(struct objective *ob, const struct glint_uncertainty *u,
			const double *each, const double *r, int rows)
{
	int n = u->n, base = ob->o->light_samples, nsets = ob->nsets;
	int cap = ob->o->max_samples;
	double worst = 0, vm = 0, vr = 0, lean = 0;

	if (!ob->cache || nsets < 2 || !(u->ndraws > 1))
		return 0;
	for (int k = 0; k < n; k++) {
		double vn = u->cov_blocks[k * n + k], vk = u->cov_mc[k * n + k];
		if (vn > 0 && isfinite(vn) && isfinite(vk))
			worst = fmax(worst, vk / vn);
		double l = fabs(u->lean[k]);
		if (vn > 0 && isfinite(vn) && isfinite(l) &&
		    l > 2 * u->lean_se[k])
			lean = fmax(lean, l / sqrt(vn));
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
	ob->lean_over_noise = lean;
	int f = fit_samples_factor(worst, vals, lean, base * ob->sample_scale,
				   cap);
	if (f == 1)
		return 0;
	glint_log_info(
		"the fit's own sampling noise is %.2f of the residual "
		"per value and %.2f of the noise per parameter "
		"(variances), its lean %.2f of the noise's standard error: "
		"%d + %d samples per hit instead of %d + %d",
		vals, worst, lean, base * ob->sample_scale * f,
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
	int ret = fit_new_cache(ob, 0, &ob->cache);
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
int fit_remove_lean(struct objective *ob, int nsets, const double *lo,
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
int fit_uncertainty(struct objective *ob, struct fit_data *d,
		    const struct selections *sl, struct glint_fit_result *res)
{
	const struct glint_model *m = ob->m;
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
	fit_select_all(ob, sl);
	memset(ob->gain_sys, 0, sizeof(ob->gain_sys));
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
		ret = fit_remove_lean(ob, nsets, lo, hi, each, r, jac,
				      &res->unc);
	if (ret > 0)
		ret = covariance(ob, sl, nsets, lo, hi, each, r, jac, block,
				 fit_pixel_blocks(ob, sl->all, sl->nall, block),
				 jr, NULL, 0, 0, res);
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
			       : fit_misfit_regions(ob, sl, r, region, &share);
	ret = fit_render_gain(ob, jac, r, region, res->render_gain);
	if (ret < 0)
		goto out;
	/* roughness moves with the highlight's shape, not its gain: the
	 * study's roughness coverage does not change with the term
	 * (fit/render_gain.c) */
	for (int k = 0; k < n && !ob->o->no_systematic; k++)
		ob->gain_sys[k] =
			k == m->lobes->roughness_param
				? 0
				: FIT_GAIN_COVER * res->render_gain[k];
	memcpy(res->render_gain_stderr, ob->gain_sys, sizeof(ob->gain_sys));
	int gain = 0;
	for (int k = 0; k < n; k++)
		gain |= ob->gain_sys[k] > 0;
	if (nregions < 3)
		nregions = 0;
	/* The model discrepancy wherever the structure has a share (it may
	 * lie under the noise, where the jackknife has no regions), and the
	 * render's gain term. */
	if (nregions || gain || (share > 0 && !ob->o->no_discrepancy))
		ret = covariance(ob, sl, nsets, lo, hi, each, r, jac, block,
				 fit_pixel_blocks(ob, sl->all, sl->nall, block),
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
	res->lean_over_noise = ob->lean_over_noise;
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
