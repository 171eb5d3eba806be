/* SPDX-License-Identifier: MIT */
/* A fit's result as JSON (the parameters, passes and uncertainty of
 * params.json) and what the photo does not determine. */
#include "job.h"

#include "fit/brdf/microfacet.h"

#include "core/json.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* (fit/job.h) */
int glint_fit_undetermined(const struct glint_fit_result *r, int k)
{
	const struct glint_param *pi = &r->model->params[k];
	if (r->unc.n == 0)
		return 0;
	return !isfinite(r->unc.se[k]) ||
	       r->unc.hi[k] - r->unc.lo[k] >= 0.5 * (pi->hi - pi->lo);
}

static int param_index(const struct glint_model *m, const char *name)
{
	for (int k = 0; k < m->nparams; k++)
		if (!strcmp(m->params[k].name, name))
			return k;
	return -1;
}

/* The roughness a pixel resolves on a sphere R pixels in radius: the
 * normal turns by 1 / R radians from one pixel to the next.  Of a joint
 * fit, the finest photo's (the largest sphere). */
static double footprint(const struct glint_fit_result *r)
{
	int interior = r->interior;

	if (r->nviews > 1) {
		interior = 0;
		for (int v = 0; v < r->nviews; v++)
			if (r->view[v].interior > interior)
				interior = r->view[v].interior;
	}
	return interior > 0 ? 1 / sqrt(interior / M_PI) : 0;
}

double glint_fit_roughness_bound(const struct glint_fit_result *r)
{
	int rk = glint_model_roughness_param(r->model);

	/* An interval that reaches below the footprint is not a value's:
	 * below it the blurred spot of a smoother surface looks the same,
	 * the objective is flat there, and the interval's low end is its
	 * curvature at the optimum, not what the pixels exclude. */
	if (rk < 0 || !r->unc.n || !(r->unc.lo[rk] < footprint(r)))
		return NAN;
	return fmax(r->unc.hi[rk], footprint(r));
}

json_t *glint_fit_params_json(const struct glint_fit_result *r)
{
	const struct glint_model *m = r->model;
	json_t *list = json_array();
	int rk = glint_model_roughness_param(m);

	for (int k = 0; k < m->nparams; k++) {
		const struct glint_param *pi = &m->params[k];
		json_t *o = json_pack(
			"{s:s,s:f,s:o,s:b,s:[f,f]}", "name", pi->name, "value",
			r->p[k], "stderr", glint_json_real_or_null(r->se[k]),
			"at_bound", r->at_bound[k], "bounds", pi->lo, pi->hi);
		if (r->unc.n) {
			json_object_set_new(
				o, "interval",
				json_pack("[f,f]", r->unc.lo[k], r->unc.hi[k]));
			json_object_set_new(
				o, "determined",
				json_boolean(!glint_fit_undetermined(r, k)));
		}
		if (k == rk && isfinite(glint_fit_roughness_bound(r)))
			json_object_set_new(
				o, "upper_bound",
				json_real(glint_fit_roughness_bound(r)));
		json_array_append_new(list, o);
	}
	return list;
}

json_t *glint_fit_passes_json(const struct glint_fit_result *r)
{
	json_t *a = json_array();

	for (int i = 0; i < r->npasses; i++) {
		const struct glint_fit_pass *p = &r->passes[i];
		json_array_append_new(
			a,
			json_pack("{s:s,s:i,s:i,s:i,s:f,s:f,s:f}", "name",
				  p->name, "pixels", p->pixels, "iterations",
				  p->iterations, "evaluations", p->evaluations,
				  "cost_start", p->cost0, "cost_end", p->cost,
				  "seconds", p->seconds));
	}
	return a;
}

static json_t *matrix_json(const double *a, int n)
{
	json_t *rows = json_array();
	for (int i = 0; i < n; i++) {
		json_t *row = json_array();
		for (int j = 0; j < n; j++)
			json_array_append_new(
				row, glint_json_real_or_null(a[i * n + j]));
		json_array_append_new(rows, row);
	}
	return rows;
}

int glint_fit_specular_f0(const struct glint_fit_result *r, double v[3],
			  double se[3], double *corr)
{
	const struct glint_model *m = r->model;
	int ki = param_index(m, "ior"), n = r->unc.n;
	static const char *const ch[3] = { "specular.r", "specular.g",
					   "specular.b" };
	double worst = 0;

	if (ki < 0 || !n)
		return -1;
	for (int c = 0; c < 3; c++) {
		int ks = param_index(m, ch[c]);
		if (ks >= 0)
			worst = fmax(worst, fabs(r->unc.corr[ks * n + ki]));
	}
	*corr = worst;
	double nn = r->p[ki], f0 = glint_fresnel_dielectric(1, nn);
	double df0 = 4 * (nn - 1) / ((nn + 1) * (nn + 1) * (nn + 1));
	for (int c = 0; c < 3; c++) {
		int ks = param_index(m, ch[c]);
		double g[GLINT_UNC_MAX_N] = { 0 };
		if (ks < 0) {
			v[c] = se[c] = NAN;
			continue;
		}
		g[ks] = f0;
		g[ki] = r->p[ks] * df0;
		v[c] = r->p[ks] * f0;
		se[c] = glint_uncertainty_delta(&r->unc, g);
	}
	return worst >= 0.9 || glint_fit_undetermined(r, ki);
}

/*
 * Specular albedo and ior enter a Torrance-Sparrow image mostly as
 * specular x F0(ior): when they correlate strongly the photo determines
 * that product, reported with its delta-method error.
 */
static void specular_fresnel(const struct glint_fit_result *r, json_t *find,
			     json_t *comb)
{
	static const char *const ch[3] = { "specular.r", "specular.g",
					   "specular.b" };
	double v[3], se[3], worst;

	if (glint_fit_specular_f0(r, v, se, &worst) < 1)
		return;
	char msg[512];
	int len = worst >= 0.9
			  ? snprintf(msg, sizeof(msg),
				     "specular and ior trade off along "
				     "specular x F0(ior) (correlation up to "
				     "%.2f):",
				     worst)
			  : snprintf(msg, sizeof(msg),
				     "the photo determines specular x "
				     "F0(ior):");
	for (int c = 0; c < 3; c++) {
		if (!isfinite(v[c]))
			continue;
		char name[48];
		snprintf(name, sizeof(name), "%s x F0(ior)", ch[c]);
		json_array_append_new(
			comb,
			json_pack("{s:s,s:f,s:o}", "name", name, "value", v[c],
				  "stderr", glint_json_real_or_null(se[c])));
		if (len < (int)sizeof(msg))
			len += snprintf(msg + len, sizeof(msg) - (size_t)len,
					" %s%.4f +- %.4f", c ? ", " : "", v[c],
					1.96 * se[c]);
	}
	if (glint_fit_undetermined(r, param_index(r->model, "ior")) &&
	    len < (int)sizeof(msg))
		snprintf(msg + len, sizeof(msg) - (size_t)len,
			 "; ior is not determined by this photo");
	json_array_append_new(find, json_string(msg));
}

int glint_fit_needs_selection(const struct glint_fit_result *r)
{
	const struct glint_model *m = r->model;
	int n = r->unc.n, ki = param_index(m, "ior");

	for (int k = 0; k < n; k++)
		if (glint_fit_undetermined(r, k))
			return 1;
	/* whether the photos tell the two apart, not the small sphere's
	 * term along their ridge (fit/discrepancy.c) */
	for (int k = 0; k < n && ki >= 0; k++)
		if (!strncmp(m->params[k].name, "specular", 8) &&
		    fabs(glint_uncertainty_corr_without_shared(&r->unc, k,
							       ki)) >= 0.95)
			return 1;
	return 0;
}

/* "light source N"; on a joint fit "photo P's light source N", N its
 * number in that photo's map (its env-sources.json). */
static void source_name(const struct glint_fit_result *r, int s, char *buf,
			size_t n)
{
	int k = 1; /* its number in its own photo's map */
	for (int i = 0; i < s; i++)
		k += r->source[i].view == r->source[s].view;
	if (r->nviews > 1)
		snprintf(buf, n, "photo %d's light source %d",
			 r->source[s].view + 1, k);
	else
		snprintf(buf, n, "light source %d", s + 1);
}

/* The light sources' parts of the standard errors (fit/light_sources.c),
 * and findings: a parameter whose error is mostly one source's flux names
 * it; a clipped source's flux, a lower bound, is not in the intervals.
 * NULL without sources. */
static json_t *light_sources(const struct glint_fit_result *r, json_t *find)
{
	const struct glint_model *m = r->model;
	int n = r->unc.n;
	char msg[400];

	if (!r->nsources)
		return NULL;
	json_t *arr = json_array();
	for (int s = 0; s < r->nsources; s++) {
		const struct glint_fit_light_source *src = &r->source[s];
		double el = asin(fmax(-1, fmin(1, src->dir[1]))) * 180 / M_PI;
		double az = atan2(src->dir[0], -src->dir[2]) * 180 / M_PI;
		json_t *o = json_object();
		json_object_set_new(o, "direction",
				    glint_json_reals(src->dir, 3));
		json_object_set_new(o, "flux", glint_json_reals(src->flux, 3));
		json_object_set_new(o, "flux_sigma",
				    glint_json_reals(src->flux_sigma, 3));
		json_object_set_new(o, "saturated",
				    json_boolean(src->saturated));
		if (r->nviews > 1)
			json_object_set_new(o, "photo",
					    json_integer(src->view + 1));
		json_object_set_new(o, "stderr",
				    glint_json_reals(r->source_stderr[s], n));
		json_array_append_new(arr, o);
		if (src->saturated) {
			char name[48];
			source_name(r, s, name, sizeof(name));
			snprintf(msg, sizeof(msg),
				 "%s (azimuth %.0f, elevation "
				 "%.0f degrees in the map) is clipped in the "
				 "probe: its flux is a lower bound, and these "
				 "intervals cannot hold its error (a gray ball "
				 "beside the probe measures it: glint probe "
				 "calibrate)",
				 name, az, el);
			json_array_append_new(find, json_string(msg));
		}
	}
	/* which light limits which parameter: its part over half the
	 * parameter's standard error */
	for (int k = 0; k < n; k++) {
		int best = -1;
		double top = 0;
		for (int s = 0; s < r->nsources; s++)
			if (r->source_stderr[s][k] > top)
				top = r->source_stderr[s][k], best = s;
		if (best < 0 || !(top > 0.5 * r->unc.se[k]))
			continue;
		const struct glint_fit_light_source *src = &r->source[best];
		double f = src->flux[0] + src->flux[1] + src->flux[2];
		double sg = src->flux_sigma[0] + src->flux_sigma[1] +
			    src->flux_sigma[2];
		char name[48];
		source_name(r, best, name, sizeof(name));
		snprintf(msg, sizeof(msg),
			 "%s is limited by the light: %s (flux "
			 "known to %.1f %%) makes %.0f %% of its standard "
			 "error's variance",
			 m->params[k].name, name, f > 0 ? 100 * sg / f : 0,
			 100 * top * top / (r->unc.se[k] * r->unc.se[k]));
		json_array_append_new(find, json_string(msg));
	}
	return arr;
}

json_t *glint_fit_uncertainty_json(const struct glint_fit_result *r)
{
	const struct glint_model *m = r->model;
	const struct glint_uncertainty *u = &r->unc;
	int n = u->n;
	json_t *find, *comb, *tb, *sys, *me, *md, *lean;
	char msg[320];

	if (!n)
		return json_null();
	find = json_array();
	comb = json_array();
	tb = json_array();
	sys = json_array();
	me = json_array();
	md = json_array();
	lean = json_array();
	if (u->nregions) {
		snprintf(msg, sizeof(msg),
			 "the residual is structured (the model is too simple "
			 "for this material, or the scene is not the photo's: "
			 "the light probe, the sphere's place): the intervals "
			 "include how far "
			 "the answer moves between %d regions of the sphere "
			 "that see the light differently",
			 u->nregions);
		json_array_append_new(find, json_string(msg));
	}
	/* The term is in every interval with a share; the finding from 1 %,
	 * where a structure stands out of a noisy photo's estimate. */
	if (r->misfit_share >= 0.01) {
		snprintf(msg, sizeof(msg),
			 "the residual's structure is %.1f %% of the photo's "
			 "signal: the answer imitates the material under this "
			 "light (as the probe measured it) and may move under "
			 "another; the intervals "
			 "include a model discrepancy for that, calibrated on "
			 "materials outside the model (bench/misfit)",
			 100 * r->misfit_share);
		json_array_append_new(find, json_string(msg));
	}
	specular_fresnel(r, find, comb);
	if (isfinite(glint_fit_roughness_bound(r))) {
		snprintf(msg, sizeof(msg),
			 "roughness's interval reaches below the pixel "
			 "footprint (%.4f), where a smoother surface looks "
			 "the same: an upper bound, roughness < %.4f, not a "
			 "value",
			 footprint(r), glint_fit_roughness_bound(r));
		json_array_append_new(find, json_string(msg));
	}
	for (int k = 0; k < n; k++) {
		json_array_append_new(
			tb, glint_json_real_or_null(u->se_textbook[k]));
		json_array_append_new(sys, json_real(u->sys[k]));
		json_array_append_new(lean, json_real(r->lean_removed[k]));
		json_array_append_new(
			me,
			json_real(sqrt(fmax(0, u->cov_regions[k * n + k]))));
		json_array_append_new(md, json_real(r->discrepancy[k]));
		if (glint_fit_undetermined(r, k) &&
		    strcmp(m->params[k].name, "ior") != 0) {
			snprintf(msg, sizeof(msg),
				 "%s is not determined by this photo "
				 "(%.0f %% interval %.4g .. %.4g)",
				 m->params[k].name, 100 * u->level, u->lo[k],
				 u->hi[k]);
			json_array_append_new(find, json_string(msg));
		}
		for (int j = k + 1; j < n; j++) {
			double c = u->corr[k * n + j];
			int spec_ior =
				!strcmp(m->params[j].name, "ior") &&
				!strncmp(m->params[k].name, "specular", 8);
			if (fabs(c) < 0.95 || spec_ior)
				continue;
			snprintf(msg, sizeof(msg),
				 "%s and %s trade off (correlation %.3f): the "
				 "photo determines a combination of them "
				 "better than either",
				 m->params[k].name, m->params[j].name, c);
			json_array_append_new(find, json_string(msg));
		}
	}
	json_t *light = json_array(), *gain = json_array();
	for (int k = 0; k < n; k++) {
		json_array_append_new(light, json_real(r->light_stderr[k]));
		json_array_append_new(gain,
				      json_real(r->render_gain_stderr[k]));
	}
	json_t *sources = light_sources(r, find);
	json_t *doc = json_pack(
		"{s:s,s:f,s:f,s:i,s:i,s:i,s:o,s:o,s:o,s:o,s:o,s:f,s:o,s:o,s:o,"
		"s:o,s:f,s:o,s:o}",
		"method",
		"cluster-robust covariance over spatial blocks (not below "
		"chi2/dof-scaled, nor, when the residual is structured, below "
		"a delete-one-region jackknife over regions that see the "
		"light differently) plus the spread over independent sample "
		"sets plus the fast render's systematic accuracy (a fixed "
		"part and a gain error per region of the residual) "
		"plus the "
		"light scale's stated uncertainty plus a model discrepancy in "
		"proportion to the residual structure's "
		"share of the signal, calibrated on materials outside the "
		"model; Student t at "
		"Welch-Satterthwaite degrees of freedom",
		"level", u->level, "chi2_dof", u->chi2_dof, "blocks",
		u->nblocks, "sample_sets", u->ndraws, "model_error_regions",
		u->nregions, "covariance", matrix_json(u->cov, n),
		"correlation", matrix_json(u->corr, n), "textbook_stderr", tb,
		"systematic_stderr", sys, "model_error_stderr", me,
		"misfit_share", r->misfit_share, "model_discrepancy_stderr", md,
		"sampling_lean_removed", lean, "findings", find, "combinations",
		comb, "seconds", r->unc_seconds, "light_scale_sigma",
		glint_json_reals(r->light_scale_sigma, 3), "light_stderr",
		light);
	if (doc && sources)
		json_object_set_new(doc, "light_sources", sources);
	if (doc)
		json_object_set_new(doc, "render_gain_stderr", gain);
	else
		json_decref(gain);
	return doc;
}

void glint_fit_result_view(const struct glint_fit_result *res, int k,
			   struct glint_fit_result *out)
{
	const struct glint_fit_view_stats *st = &res->view[k];

	*out = *res;
	out->pixels = st->pixels;
	out->interior = st->interior;
	out->wcost = st->wcost;
	out->rmse = st->rmse;
	out->rel_rmse = st->rel_rmse;
	out->backdrop_rel_rmse = st->backdrop_rel_rmse;
	out->flat_rel_rmse = st->flat_rel_rmse;
	out->noise_rmse = st->noise_rmse;
	out->nviews = 1;
}

int glint_fit_judge(const struct glint_fit_result *r, double accept_rmse,
		    struct glint_fit_verdict *v)
{
	double back = r->backdrop_rel_rmse, flat = r->flat_rel_rmse;
	int by_back = isfinite(back) && !(back > flat);

	memset(v, 0, sizeof(*v));
	v->ratio = r->rmse / r->noise_rmse;
	if (accept_rmse > 0) {
		v->limit = accept_rmse;
		snprintf(v->rule, sizeof(v->rule),
			 "relative RMSE below --accept-rmse %g", accept_rmse);
	} else {
		v->limit = by_back ? back : flat;
		snprintf(v->rule, sizeof(v->rule),
			 "the fitted sphere explains the photo better than %s",
			 isfinite(back) ? "the bare backdrop and a flat disc "
					  "of the photo's mean colour"
					: "a flat disc of the photo's mean "
					  "colour");
	}
	v->accepted = r->rel_rmse < v->limit;
	if (!v->accepted) {
		if (accept_rmse > 0)
			snprintf(v->verdict, sizeof(v->verdict),
				 "relative RMSE %.3f is above --accept-rmse "
				 "%g",
				 r->rel_rmse, accept_rmse);
		else if (by_back)
			snprintf(v->verdict, sizeof(v->verdict),
				 "the photo shows the backdrop, not a sphere, "
				 "where the scene puts it (the bare "
				 "environment explains it with a relative "
				 "RMSE of %.3f, the fitted sphere only "
				 "%.3f): wrong scene or sphere position?",
				 back, r->rel_rmse);
		else
			snprintf(v->verdict, sizeof(v->verdict),
				 "the photo does not show this scene's "
				 "sphere: a flat disc of its mean colour "
				 "explains it as well (relative RMSE %.3f) "
				 "as the fitted sphere (%.3f): another photo, "
				 "or another scene?",
				 flat, r->rel_rmse);
	} else if (!isfinite(v->ratio)) {
		snprintf(v->verdict, sizeof(v->verdict),
			 "relative RMSE %.3f (a flat disc leaves %.3f); no "
			 "noise model to judge the misfit by (give the "
			 "capture's weights)",
			 r->rel_rmse, flat);
	} else if (v->ratio <= 1.5) {
		snprintf(v->verdict, sizeof(v->verdict),
			 "fits to the noise: the residual is %.2f times what "
			 "noise alone leaves",
			 v->ratio);
	} else {
		snprintf(v->verdict, sizeof(v->verdict),
			 "misfit: the residual is %.1f times what noise alone "
			 "leaves: the model (or the scene) does not explain "
			 "all of the photo; the intervals include the misfit",
			 v->ratio);
	}
	return v->accepted;
}

json_t *glint_fit_verdict_json(const struct glint_fit_result *r,
			       const struct glint_fit_verdict *v)
{
	return json_pack(
		"{s:b,s:s,s:s,s:o,s:o,s:o,s:o,s:o,s:o}", "accepted",
		v->accepted, "rule", v->rule, "verdict", v->verdict,
		"relative_rmse", glint_json_real_or_null(r->rel_rmse), "limit",
		glint_json_real_or_null(v->limit), "backdrop_relative_rmse",
		glint_json_real_or_null(r->backdrop_rel_rmse),
		"flat_relative_rmse", glint_json_real_or_null(r->flat_rel_rmse),
		"noise_rmse", glint_json_real_or_null(r->noise_rmse),
		"residual_over_noise", glint_json_real_or_null(v->ratio));
}
