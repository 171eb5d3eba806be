/* SPDX-License-Identifier: MIT */
/*
 * One fit as `glint fit`, `glint demo` and the queue run it: trace, choose
 * the model (--model auto, --select-model), fit (or run the fidelity
 * ladder), check that the photo shows the scene's sphere, render the
 * result and write the result folder atomically.
 */
#define _POSIX_C_SOURCE 200809L
#include "job.h"

#include "ladder.h"
#include "misfit.h"
#include "select.h"
#include "export/export.h"
#include "fit/render/compare.h"
#include "core/clock.h"
#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/path.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * --model auto: quick fits (about 1000 pixels) of an opaque and a
 * transparent sphere; the one whose render explains the photo better (the
 * lower relative RMSE) is chosen, and the numbers say why.
 */
static int pick_model(struct glint_renderer *r, const struct glint_fit_job *job,
		      const struct glint_fit_opts *base,
		      const struct glint_model_ops **out, json_t **why)
{
	const struct glint_model_ops *cand[2] = { &glint_model_torrance_sparrow,
						  &glint_model_dielectric };
	double err[2];
	struct glint_fit_opts o = *base;
	o.max_pixels = 1024;
	o.progress = NULL;
	for (int i = 0; i < 2; i++) {
		struct glint_fit_result fr;
		int ret =
			glint_fit(r, cand[i], job->photo, job->weight, &o, &fr);
		if (ret < 0)
			return glint_error_prefix(
				ret, "--model auto: trying %s", cand[i]->name);
		err[i] = fr.rel_rmse;
	}
	int k = err[1] < err[0];
	*out = cand[k];
	*why = json_pack("{s:s, s:f, s:f}", "chosen", cand[k]->name,
			 "torrance_sparrow_rel_rmse", err[0],
			 "dielectric_rel_rmse", err[1]);
	glint_log_info("--model auto: %s (a quick fit leaves a relative RMSE "
		       "of %.3f as an opaque Torrance-Sparrow sphere, %.3f as "
		       "a transparent dielectric one: %s)",
		       cand[k]->name, err[0], err[1],
		       k ? "the photo shows the map through the sphere"
			 : "the photo does not show the map through the "
			   "sphere");
	return 0;
}

/*
 * --select-model: the opaque candidates scored by BIC (fit/select.h); the
 * chosen one's fit is the result.
 */
static int select_model(const struct glint_fit_view *views, int nv,
			const struct glint_fit_opts *o, int richer,
			const struct glint_model_ops **model,
			struct glint_fit_result *res, json_t **why)
{
	struct glint_selection *sel = calloc(1, sizeof(*sel));
	int ret = sel ? glint_select_model_views(views, nv, o, richer, sel)
		      : -ENOMEM;
	if (ret < 0) {
		free(sel);
		return glint_error_prefix(ret, "--select-model");
	}
	const struct glint_select_candidate *c = &sel->c[sel->chosen];
	if (sel->has_fit[sel->chosen]) {
		*res = sel->fit[sel->chosen];
	} else if (sel->chosen == GLINT_SEL_LAMBERT) {
		ret = glint_fit_views(views, nv, &glint_model_lambert, o, res);
	} else {
		/* Grey: the reduced model's values and standard errors
		 * (select.c); the full fit's intervals and covariance do
		 * not apply to them. */
		*res = sel->fit[GLINT_SEL_RGB];
		memcpy(res->p, c->p, sizeof(res->p));
		memcpy(res->se, c->se, sizeof(res->se));
		res->unc.n = 0;
	}
	*model = c->model;
	res->model = c->model;
	glint_log_info("--select-model: %s", sel->why);
	*why = glint_selection_to_json(sel);
	free(sel);
	return ret;
}

/* The fit as the job asks: the model picked (--model auto) or selected
 * (--select-model), then through the fidelity ladder or plainly, on the
 * job's photo or jointly on several (views[0] is the job's; auto and the
 * ladder take one: joint_check()).  *why, *selection and *fidelity get
 * their JSON (or stay NULL). */
static int run_fit(const struct glint_fit_view *views, int nv,
		   const struct glint_fit_job *job, struct glint_fit_opts *o,
		   const struct glint_model_ops **model,
		   struct glint_fit_result *res, json_t **why,
		   json_t **selection, json_t **fidelity)
{
	struct glint_renderer *r = views[0].r;
	int ret = 0;

	*model = job->model;
	if (!*model) {
		ret = pick_model(r, job, o, model, why);
		if (ret < 0)
			return ret;
	}
	if (job->select && !(*model)->transparent)
		return select_model(views, nv, o, 1, model, res, selection);
	if (job->ladder > 0 && !(*model)->transparent) {
		struct glint_ladder_result *lr = calloc(1, sizeof(*lr));
		ret = lr ? glint_ladder_run(&job->scene, *model, job->photo,
					    job->weight, o, job->ladder,
					    job->ladder_knobs, job->nthreads,
					    lr)
			 : glint_error_set(ENOMEM, "out of memory");
		if (!ret) {
			*res = lr->chosen_fit;
			*fidelity = glint_ladder_to_json(lr);
			if (glint_log_get_mode() == GLINT_LOG_HUMAN)
				glint_ladder_print(lr, stderr);
		}
		free(lr);
		return ret;
	}
	ret = glint_fit_views(views, nv, *model, o, res);
	if (ret < 0 || job->no_auto_select || (*model)->transparent ||
	    (*model)->nlobes < 2 || !glint_fit_needs_selection(res))
		return ret;
	glint_log_info("the photo%s not determine every parameter of %s: "
		       "choosing the model by BIC (--select-model)",
		       nv > 1 ? "s do" : " does", (*model)->name);
	return select_model(views, nv, o, 0, model, res, selection);
}

/* params.json for a fit (without the model choice, selection, fidelity
 * and output, which the caller adds); a new reference. */
static json_t *params_doc(const struct glint_fit_job *job,
			  const struct glint_fit_opts *o,
			  const struct glint_fit_result *res)
{
	const struct glint_model_ops *model = res->model;
	json_t *doc = json_pack(
		"{s:s,s:s,s:o,s:o,s:{s:s,s:b,s:b,s:f,s:i,s:i},s:f,s:f,s:f,"
		"s:i,s:i,s:i,s:o,s:f,s:f,s:{s:s,s:s,s:f},s:s}",
		"model", model->name, "conventions", model->conventions,
		"material", glint_material_to_json(model, res->p), "parameters",
		glint_fit_params_json(res), "method", "name",
		glint_fit_method_name(o->method), "coarse_to_fine",
		o->coarse_to_fine, "faithful", o->faithful, "mask_threshold",
		o->mask_threshold, "light_samples",
		res->light_samples ? res->light_samples : o->light_samples,
		"lobe_samples",
		res->lobe_samples ? res->lobe_samples : o->lobe_samples, "cost",
		res->cost, "rmse", res->rmse, "relative_rmse", res->rel_rmse,
		"pixels", res->pixels, "interior_pixels", res->interior,
		"specular_pixels", res->specular_pixels, "passes",
		glint_fit_passes_json(res), "seconds", res->seconds,
		"setup_seconds", res->setup_seconds, "inputs", "scene",
		job->scene_path, "photo", job->photo_path, "sphere_diameter_m",
		2 * job->scene.sphere_radius, "weighting",
		job->weight			       ? "weight image"
		: o->weighting == GLINT_WEIGHT_POISSON ? "poisson"
						       : "uniform");
	if (!doc)
		return NULL;
	json_object_set_new(doc, "optimizer",
			    json_string(o->optimizer == GLINT_OPT_LM ? "lm"
					: o->optimizer == GLINT_OPT_ANNEAL
						? "anneal"
						: "auto"));
	json_object_set_new(doc, "uncertainty",
			    glint_fit_uncertainty_json(res));
	/* The fitter's own Monte Carlo noise against the photo's, per
	 * parameter and per value (variance ratios at the last check; the
	 * samples are raised above 1 and 0.25: docs/fitting.md). */
	if (res->light_samples) {
		json_t *meth = json_object_get(doc, "method");
		json_object_set_new(meth, "sampling_over_noise",
				    json_real(res->mc_over_noise));
		json_object_set_new(meth, "model_noise_over_residual",
				    json_real(res->model_noise));
	}
	return doc;
}

/* An export's material name: the output folder's last component. */
static const char *material_name(const struct glint_fit_job *job, char buf[256])
{
	size_t n = strlen(job->out_dir);
	while (n > 1 && job->out_dir[n - 1] == '/')
		n--;
	size_t b = n;
	while (b > 0 && job->out_dir[b - 1] != '/')
		b--;
	snprintf(buf, 256, "%.*s", (int)(n - b), job->out_dir + b);
	return strcmp(buf, ".") && strcmp(buf, "..") && *buf ? buf : "material";
}

/*
 * The final render, with its own Monte Carlo noise held below the photo's
 * where the photo has a noise model (a weight image of 1/variance), so
 * that the residual judged in misfit and compare.png is the photo's noise
 * and the model's misfit, not the render's.  Two renders on independent
 * sample sets give the noise of their mean, (a - b)^2 / 4 per value; in
 * the photo's variance units, averaged over the sphere's weighted values,
 * that is q.  At the scene's sample counts q is measured; when it is above
 * RENDER_NOISE_TARGET (the render's noise at most half the photo's, adding
 * at most a quarter to chi^2) one more pair is rendered with the samples
 * that should bring the two together to the target (q falls as 1 /
 * samples), at most RENDER_MAX_FACTOR times the scene's, and the two
 * means are combined by inverse variance.  The second pair also keeps to
 * a time budget, twice the fit's time and at least RENDER_MIN_BUDGET_S,
 * predicted from the first pair's time (a pair's time grows with its
 * samples): a large photo (a 1 MP frame's sphere is 220,000 pixels) would
 * otherwise spend minutes on a preview after a fit of seconds.  What
 * limited the render is said in params.json.  Without a noise model the
 * scene's counts are used as they are.
 */
#define RENDER_NOISE_TARGET 0.25
#define RENDER_MAX_FACTOR   4
#define RENDER_MIN_BUDGET_S 20.0
/* The first pair's pilot: every 16th row, on images of 512 rows or more;
 * its samples are cut at most to an eighth. */
#define RENDER_PILOT_STEP     16
#define RENDER_PILOT_MIN_ROWS 512
#define RENDER_MIN_FACTOR     0.125

double glint_render_first_factor(double q_pilot, double pair_s, double budget_s,
				 const char **limited_by)
{
	double f = 1;

	*limited_by = NULL;
	/* aimed at half the target, so that the pair lands below it */
	if (q_pilot >= 0 && isfinite(q_pilot))
		f = fmin(1, q_pilot / (0.5 * RENDER_NOISE_TARGET));
	if (pair_s > 0 && f * pair_s > budget_s) {
		f = budget_s / pair_s;
		*limited_by = "time: the budget_seconds it may take";
	}
	return fmax(f, RENDER_MIN_FACTOR);
}

int glint_render_factor(double q1, double pair_s, double budget_s,
			const char **limited_by)
{
	*limited_by = NULL;
	if (!(q1 > RENDER_NOISE_TARGET))
		return 0;
	int want = (int)ceil(q1 / RENDER_NOISE_TARGET - 1 - 1e-9);
	int factor = want;
	if (factor > RENDER_MAX_FACTOR) {
		factor = RENDER_MAX_FACTOR;
		*limited_by = "samples: at most 4 times the scene's per pair";
	}
	/* The second pair at `factor` takes about factor * pair_s. */
	int afford = pair_s > 0 ? (int)floor(budget_s / pair_s) : factor;
	if (afford < factor) {
		factor = afford > 0 ? afford : 0;
		*limited_by = "time: the budget_seconds it may take";
	}
	return factor;
}

static double render_noise(const struct glint_image *a,
			   const struct glint_image *b,
			   const struct glint_image *cov,
			   const struct glint_image *w, long *nv)
{
	double sum = 0;
	long n = 0;
	size_t np = (size_t)a->width * a->height;
	for (size_t i = 0; i < np; i++) {
		if (cov->data[3 * i] < 1)
			continue; /* rim or backdrop */
		for (int c = 0; c < 3; c++) {
			double wi = w->data[3 * i + c];
			double d = a->data[3 * i + c] - b->data[3 * i + c];
			if (!(wi > 0) || !isfinite(wi) || !isfinite(d))
				continue;
			sum += d * d / 4 * wi;
			n++;
		}
	}
	*nv = n;
	return n ? sum / n : NAN;
}

/* The scene's count n times factor, at least 1 when n is not 0. */
static int scaled(int n, double factor)
{
	return n ? (int)fmax(1, floor(n * factor + 0.5)) : 0;
}

/* One render at `factor` times the scene's samples, on sample sets
 * `seed`, of every row_step-th row. */
static int shade(struct glint_renderer *r, const struct glint_fit_job *job,
		 const struct glint_model_ops *model, const double *p,
		 double factor, uint32_t seed, int row_step,
		 struct glint_image *out, struct glint_image *cov)
{
	struct glint_shade_opts so = {
		.light_samples = scaled(job->scene.light_samples, factor),
		.brdf_samples = scaled(job->scene.brdf_samples, factor),
		.background = 1,
		.nthreads = job->nthreads,
		.seed = seed,
		.row_step = row_step,
	};
	return glint_renderer_shade(r, model, p, &so, out, cov);
}

/* Into img, the mean of a pair of renders at `factor` times the scene's
 * samples; b receives the second.  *q: the mean's noise. */
static int render_pair(struct glint_renderer *r,
		       const struct glint_fit_job *job,
		       const struct glint_model_ops *model, const double *p,
		       double factor, uint32_t seed, int row_step,
		       struct glint_image *img, struct glint_image *b,
		       struct glint_image *cov, double *q, long *nv)
{
	int ret = shade(r, job, model, p, factor, seed, row_step, img, cov);
	if (ret == 0)
		ret = shade(r, job, model, p, factor, seed + 1, row_step, b,
			    NULL);
	if (ret < 0)
		return ret;
	*q = render_noise(img, b, cov, job->weight, nv);
	for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++)
		img->data[i] = 0.5f * (img->data[i] + b->data[i]);
	return 0;
}

static json_t *render_step(const struct glint_fit_job *job, double factor,
			   double q)
{
	return json_pack("{s:i, s:i, s:o}", "light_samples",
			 2 * scaled(job->scene.light_samples, factor),
			 "brdf_samples",
			 2 * scaled(job->scene.brdf_samples, factor), "noise",
			 glint_json_real_or_null(q));
}

static int render_final(struct glint_renderer *r,
			const struct glint_fit_job *job,
			const struct glint_model_ops *model, const double *p,
			double fit_s, struct glint_image *img,
			struct glint_image *cov, json_t **info)
{
	const struct glint_image *w = job->weight;
	double t0 = glint_clock_monotonic(), q1, q2 = NAN;
	struct glint_image *b = NULL, *more = NULL;
	long nv = 0;
	int ret, factor = 0;

	*info = NULL;
	if (!w || model->transparent || w->width != img->width ||
	    w->height != img->height) {
		ret = shade(r, job, model, p, 1, 0, 1, img, cov);
		if (ret < 0)
			return ret;
		*info = json_pack("{s:i, s:i, s:s}", "light_samples",
				  job->scene.light_samples, "brdf_samples",
				  job->scene.brdf_samples, "noise",
				  "not compared: the photo has no noise model");
		return *info ? 0 : glint_error_set(ENOMEM, "out of memory");
	}
	b = glint_image_new(img->width, img->height);
	if (!b) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	double budget_s = fmax(2 * fit_s, RENDER_MIN_BUDGET_S);
	/* A large image's first pair is sized by a pilot of every 16th row:
	 * fewer samples where the render is already far below the photo's
	 * noise, and within the time budget. */
	double f1 = 1, qp = NAN;
	const char *first_limit = NULL;
	if (img->height >= RENDER_PILOT_MIN_ROWS) {
		double tp = glint_clock_monotonic();
		ret = render_pair(r, job, model, p, 1, 0, RENDER_PILOT_STEP,
				  img, b, cov, &qp, &nv);
		if (ret < 0)
			goto out;
		f1 = glint_render_first_factor(
			qp, (glint_clock_monotonic() - tp) * RENDER_PILOT_STEP,
			budget_s, &first_limit);
	}
	double t1 = glint_clock_monotonic();
	ret = render_pair(r, job, model, p, f1, 0, 1, img, b, cov, &q1, &nv);
	if (ret < 0)
		goto out;
	double q = q1, pair_s = glint_clock_monotonic() - t1;
	const char *limited_by;
	factor = glint_render_factor(q1, pair_s, budget_s, &limited_by);
	if (!factor && first_limit)
		limited_by = first_limit;
	if (factor && !(more = glint_image_new(img->width, img->height))) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	if (factor) {
		ret = render_pair(r, job, model, p, f1 * factor, 2, 1, more, b,
				  cov, &q2, &nv);
		if (ret < 0)
			goto out;
		/* Inverse-variance weights, one for the whole image: the
		 * pixels' variances all fall with the samples alike. */
		double w1 = 1 / q1, w2 = 1 / q2;
		if (!(w2 > 0) || !isfinite(w2))
			w1 = 0, w2 = 1; /* a noiseless second pair */
		for (size_t i = 0; i < (size_t)img->width * img->height * 3;
		     i++)
			img->data[i] = (float)((w1 * img->data[i] +
						w2 * more->data[i]) /
					       (w1 + w2));
		q = 1 / (w1 + w2);
	}
	int total_l =
		2 * scaled(job->scene.light_samples, f1) +
		(factor ? 2 * scaled(job->scene.light_samples, f1 * factor)
			: 0);
	int total_b =
		2 * scaled(job->scene.brdf_samples, f1) +
		(factor ? 2 * scaled(job->scene.brdf_samples, f1 * factor) : 0);
	json_t *steps = json_array();
	if (steps) {
		json_array_append_new(steps, render_step(job, f1, q1));
		if (factor)
			json_array_append_new(
				steps, render_step(job, f1 * factor, q2));
	}
	*info = json_pack(
		"{s:i, s:i, s:o, s:f, s:b, s:I, s:f, s:f, s:s?, "
		"s:o*}",
		"light_samples", total_l, "brdf_samples", total_b, "noise",
		glint_json_real_or_null(q), "noise_target", RENDER_NOISE_TARGET,
		"below_target", q <= RENDER_NOISE_TARGET, "values",
		(json_int_t)nv, "seconds", glint_clock_monotonic() - t0,
		"budget_seconds", budget_s, "limited_by",
		q <= RENDER_NOISE_TARGET ? NULL : limited_by, "steps", steps);
	if (*info && img->height >= RENDER_PILOT_MIN_ROWS)
		json_object_set_new(*info, "pilot",
				    json_pack("{s:i, s:o, s:f}", "row_step",
					      RENDER_PILOT_STEP, "noise",
					      glint_json_real_or_null(qp),
					      "first_pair_factor", f1));
	if (!*info) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	glint_log_info("final render: %d + %d samples, its noise %.2f of the "
		       "photo's variance (target %.2f), %.1f s%s%s",
		       total_l, total_b, q, RENDER_NOISE_TARGET,
		       glint_clock_monotonic() - t0,
		       q > RENDER_NOISE_TARGET && limited_by ? "; limited by "
							     : "",
		       q > RENDER_NOISE_TARGET && limited_by ? limited_by : "");
out:
	glint_image_free(b);
	glint_image_free(more);
	return ret;
}

/* One photo's outputs: its job (inputs), the render of the result in its
 * scene, the render's covariance, its misfit by angle (have_mf), the
 * final render's record. */
struct view_out {
	const struct glint_fit_job *job;
	struct glint_image *img, *cov;
	struct glint_misfit mf;
	int have_mf;
	json_t *render_info;
};

/* Photo k's render and compare image names: render.exr, render-2.exr, ... */
static void view_file(int k, const char *stem, const char *ext, char *buf,
		      size_t n)
{
	if (k == 0)
		snprintf(buf, n, "%s%s", stem, ext);
	else
		snprintf(buf, n, "%s-%d%s", stem, k + 1, ext);
}

/* Photo k's render.exr and compare.png into the atomic folder ad. */
static int write_view(struct glint_atomic_dir *ad, int k,
		      const struct view_out *vo)
{
	const struct glint_misfit *mf = vo->have_mf ? &vo->mf : NULL;
	double ve[GLINT_MISFIT_BANDS + 1], me[GLINT_MISFIT_BANDS + 1];
	double mean[2][GLINT_MISFIT_BANDS], se[2][GLINT_MISFIT_BANDS];
	long px[2][GLINT_MISFIT_BANDS];
	struct glint_compare_plot plots[2] = {
		{ "VIEW ANGLE", GLINT_MISFIT_BANDS, ve, mean[0], se[0], px[0] },
		{ "MIRROR ANGLE", GLINT_MISFIT_BANDS, me, mean[1], se[1],
		  px[1] },
	};
	for (int b = 0; mf && b < GLINT_MISFIT_BANDS; b++) {
		const struct glint_misfit_band *band[2] = { &mf->view[b],
							    &mf->mirror[b] };
		for (int a = 0; a < 2; a++) {
			mean[a][b] = band[a]->mean;
			se[a][b] = band[a]->se;
			px[a][b] = band[a]->n;
		}
		ve[b] = band[0]->lo_deg;
		me[b] = band[1]->lo_deg;
		ve[b + 1] = band[0]->hi_deg;
		me[b + 1] = band[1]->hi_deg;
	}
	const struct glint_fit_job *job = vo->job;
	struct glint_write_opts wo = {
		.window_x = job->window.x,
		.window_y = job->window.y,
		.frame_width = job->window.frame_width,
		.frame_height = job->window.frame_height,
	};
	char name[32], path[GLINT_PATH_MAX];
	view_file(k, "render", ".exr", name, sizeof(name));
	int ret = glint_image_write(
		glint_atomic_dir_file(ad, name, path, sizeof(path)), vo->img,
		&wo);
	view_file(k, "compare", ".png", name, sizeof(name));
	if (!ret)
		ret = glint_compare_png_plots(
			glint_atomic_dir_file(ad, name, path, sizeof(path)),
			job->photo, vo->img, vo->cov, plots, mf ? 2 : 0, NULL);
	return ret;
}

/* The names a fit writes into its folder: NULL-terminated, in static
 * storage (a joint fit's render-N.exr, compare-N.png among them). */
static const char *const *output_names(void)
{
	static const char *const fixed[] = {
		"params.json",	"render.exr",	 "compare.png", "material.gltf",
		"material.xml", "material.pbrt", "material.py", "material.mtlx",
	};
	enum { NFIXED = sizeof(fixed) / sizeof(fixed[0]) };
	static char more[2 * (GLINT_FIT_MAX_VIEWS - 1)][32];
	static const char *names[NFIXED + 2 * (GLINT_FIT_MAX_VIEWS - 1) + 1];
	if (names[0])
		return names;
	int n = 0;
	for (int k = 1; k < GLINT_FIT_MAX_VIEWS; k++) {
		view_file(k, "render", ".exr", more[2 * k - 2], 32);
		view_file(k, "compare", ".png", more[2 * k - 1], 32);
	}
	for (int k = 0; k < NFIXED; k++)
		names[n++] = fixed[k];
	for (int k = 0; k < 2 * (GLINT_FIT_MAX_VIEWS - 1); k++)
		names[n++] = more[k];
	names[n] = NULL;
	return names;
}

/* params.json, and each photo's render.exr and compare.png, into dir as
 * one atomic folder (the old one stays whole on failure). */
static int write_results(const struct glint_fit_job *job, const char *dir,
			 const json_t *doc, const struct view_out *outs,
			 int nviews, const struct glint_export *exports,
			 const struct glint_model_ops *model)
{
	struct glint_atomic_dir ad;
	char path[GLINT_PATH_MAX];
	int ret = glint_atomic_dir_open(&ad, dir);

	if (ret < 0)
		return ret;
	/* What is not glint's there stays (check_outputs let it through
	 * only with --force). */
	ad.names = output_names();
	ad.keep_others = job->force;
	char *text = json_dumps(doc, JSON_INDENT(2) | JSON_REAL_PRECISION(9));
	ret = text ? glint_atomic_write_file(
			     glint_atomic_dir_file(&ad, "params.json", path,
						   sizeof(path)),
			     text, strlen(text))
		   : glint_error_set(ENOMEM, "out of memory");
	free(text);
	for (int k = 0; k < nviews && !ret; k++)
		ret = write_view(&ad, k, &outs[k]);
	char name_buf[256];
	for (int k = 0; exports && !ret && k < GLINT_EXPORT_NFORMATS; k++) {
		const struct glint_export *e = &exports[k];
		char file[64];
		if ((int)e->format != k)
			continue;
		snprintf(file, sizeof(file), "material%s",
			 glint_export_extension(e->format));
		char *mtext = glint_export_text(e, material_name(job, name_buf),
						"params.json", model);
		if (!mtext) {
			ret = glint_error_set(ENOMEM, "out of memory");
			break;
		}
		ret = glint_atomic_write_file(
			glint_atomic_dir_file(&ad, file, path, sizeof(path)),
			mtext, strlen(mtext));
		free(mtext);
	}
	if (!ret)
		ret = glint_atomic_dir_commit(&ad);
	else
		glint_atomic_dir_abort(&ad);
	return ret;
}

/* The accepted material in each format of job->exports, into exports[k]
 * (format k, or GLINT_EXPORT_NFORMATS when it has none); the list for
 * params.json. */
static json_t *refit_exports(const struct glint_fit_job *job,
			     const struct glint_model_ops *model,
			     const double *p, struct glint_export *exports)
{
	json_t *list = json_array();
	for (int k = 0; k < GLINT_EXPORT_NFORMATS; k++) {
		exports[k].format = GLINT_EXPORT_NFORMATS;
		if (!(job->exports & (1u << k)))
			continue;
		const char *fmt = glint_export_format_names[k];
		char file[64];
		snprintf(file, sizeof(file), "material%s",
			 glint_export_extension((enum glint_export_format)k));
		if (glint_export_refit((enum glint_export_format)k, model, p,
				       2 * job->scene.sphere_radius,
				       &exports[k]) < 0) {
			glint_log_warn("no %s export: %s", fmt,
				       glint_error_msg());
			json_array_append_new(
				list, json_pack("{s:s, s:s}", "format", fmt,
						"error", glint_error_msg()));
			glint_error_clear();
			exports[k].format = GLINT_EXPORT_NFORMATS;
			continue;
		}
		json_array_append_new(
			list, json_pack("{s:s, s:s, s:f, s:o}", "format", fmt,
					"file", file, "refit_relative_rms",
					exports[k].residual, "parameters",
					glint_export_params_json(&exports[k])));
	}
	return list;
}

/* The output folder and the refused fit's sibling may take the result
 * (nothing there, or glint's own files; with --force, glint's files are
 * replaced and the others kept): checked before any work.  The run's
 * inputs (scene, photo, weights, map, for every photo) are never
 * replaced, with or without --force. */
static int check_outputs(const struct glint_fit_job *job)
{
	const char *inputs[4 * (GLINT_FIT_MAX_VIEWS + 1) + 1];
	int n = 0;
	for (int k = -1; k < job->nalso && n < 4 * GLINT_FIT_MAX_VIEWS; k++) {
		const struct glint_fit_job *j = k < 0 ? job : &job->also[k];
		const char *p[4] = { j->scene_path, j->photo_path,
				     j->weights_path, j->scene.env_path };
		for (int i = 0; i < 4; i++)
			if (p[i] && p[i][0])
				inputs[n++] = p[i];
	}
	inputs[n] = NULL;
	char dir[GLINT_PATH_MAX];
	int ret = glint_atomic_dir_check(job->out_dir, output_names(), NULL,
					 inputs, job->force);

	if (!ret)
		ret = glint_path_fmt(dir, sizeof(dir), "%s.refused",
				     job->out_dir);
	if (!ret)
		ret = glint_atomic_dir_check(dir, output_names(), NULL, inputs,
					     job->force);
	return ret;
}

#define CROP_MIN_SAVING 0.25

/*
 * The window around the scene sphere's silhouette in the camera's frame:
 * the ellipse's extent plus a margin (lens blur at the sphere's nearest
 * depth, a tenth of the radius for the compare image's context, 8
 * pixels).  Returns 1 when it saves at least CROP_MIN_SAVING of the
 * frame, else 0.
 */
static int sphere_window(const struct glint_fit_job *job,
			 struct glint_image_window *win)
{
	const struct glint_pinhole *cam = &job->scene.cam;
	int fw = cam->width, fh = cam->height;
	struct glint_ellipse e;

	if (job->window.frame_width)
		return 0;
	if (glint_pinhole_sphere_ellipse(cam, job->scene.sphere_centre,
					 job->scene.sphere_radius, &e) < 0) {
		glint_error_clear(); /* the fit reports what is wrong */
		return 0;
	}
	double ca = cos(e.angle), sa = sin(e.angle);
	double hx = sqrt(e.a * e.a * ca * ca + e.b * e.b * sa * sa);
	double hy = sqrt(e.a * e.a * sa * sa + e.b * e.b * ca * ca);
	double z =
		v3_dot(v3_sub(job->scene.sphere_centre, cam->pos), cam->fwd) -
		job->scene.sphere_radius;
	double blur = 0;
	if (cam->aperture_radius > 0 && z > 0 && cam->focus_distance > 0)
		blur = cam->aperture_radius * cam->fpx *
		       fabs(1 / z - 1 / cam->focus_distance);
	double margin = 8 + 0.1 * fmax(e.a, e.b) + blur;
	int x0 = (int)floor(fmax(0, e.cx - hx - margin));
	int y0 = (int)floor(fmax(0, e.cy - hy - margin));
	int x1 = (int)ceil(fmin(fw, e.cx + hx + margin));
	int y1 = (int)ceil(fmin(fh, e.cy + hy + margin));
	if (x1 - x0 < 1 || y1 - y0 < 1 ||
	    (double)(x1 - x0) * (y1 - y0) >
		    (1 - CROP_MIN_SAVING) * (double)fw * fh)
		return 0;
	*win = (struct glint_image_window){ x0, y0, x1 - x0, y1 - y0 };
	return 1;
}

/* The camera shifted to the window, and job->window set. */
static void apply_window(struct glint_fit_job *job,
			 const struct glint_image_window *win)
{
	struct glint_pinhole *cam = &job->scene.cam;
	int fw = cam->width, fh = cam->height;

	cam->width = win->width;
	cam->height = win->height;
	cam->cx -= win->x;
	cam->cy -= win->y;
	cam->frame_x = win->x;
	cam->frame_y = win->y;
	cam->frame_width = fw;
	job->window.x = win->x;
	job->window.y = win->y;
	job->window.frame_width = fw;
	job->window.frame_height = fh;
	glint_log_info("fitting the %dx%d window at (%d, %d) around the "
		       "sphere: %.0f%% of the %dx%d frame",
		       win->width, win->height, win->x, win->y,
		       100.0 * win->width * win->height / ((double)fw * fh), fw,
		       fh);
}

/* The photo and weights read whole. */
static int read_whole(struct glint_fit_job *job, const char *weights_path)
{
	int ret = glint_image_read(job->photo_path, &job->photo);

	if (ret == 0 && weights_path)
		ret = glint_image_read(weights_path, &job->weight);
	return ret;
}

static int read_photo(struct glint_fit_job *job, const char *weights_path);

int glint_fit_job_load(struct glint_fit_job *job, const char *weights_path)
{
	int ret = glint_scene_load(job->scene_path, &job->scene);

	job->weights_path = weights_path;
	job->photo = job->weight = NULL;
	if (ret == 0)
		ret = glint_radiance_check(job->photo_path, job->srgb);
	if (ret < 0)
		return ret;
	ret = read_photo(job, weights_path);
	if (ret == 0 && glint_image_encoded(job->photo_path))
		glint_image_from_srgb(job->photo_path, job->photo);
	return ret;
}

/* The photo (and weights): the sphere's window of a frame-sized one, or
 * whole. */
static int read_photo(struct glint_fit_job *job, const char *weights_path)
{
	struct glint_image_window win;
	int cp = 0, cw = 0, ret;

	if (!sphere_window(job, &win))
		return read_whole(job, weights_path);
	/* Only the window of a frame-sized photo and weights: a 12 MP
	 * frame's EXR is never held whole. */
	int fw = job->scene.cam.width, fh = job->scene.cam.height;
	ret = glint_image_read_window(job->photo_path, fw, fh, &win,
				      &job->photo, &cp);
	if (ret == 0 && weights_path)
		ret = glint_image_read_window(weights_path, fw, fh, &win,
					      &job->weight, &cw);
	if (ret < 0)
		return ret;
	if (cp && (!weights_path || cw)) {
		apply_window(job, &win);
		return 0;
	}
	/* An image of another size: both whole, as the fit expects to say
	 * what is wrong with them. */
	glint_fit_job_unload(job);
	return read_whole(job, weights_path);
}

int glint_fit_job_crop(struct glint_fit_job *job)
{
	const struct glint_pinhole *cam = &job->scene.cam;
	struct glint_image_window win;

	if (!job->photo || job->photo->width != cam->width ||
	    job->photo->height != cam->height ||
	    (job->weight && (job->weight->width != cam->width ||
			     job->weight->height != cam->height)) ||
	    !sphere_window(job, &win))
		return 0;
	struct glint_image *p = glint_image_crop(job->photo, win.x, win.y,
						 win.width, win.height);
	struct glint_image *w =
		job->weight ? glint_image_crop(job->weight, win.x, win.y,
					       win.width, win.height)
			    : NULL;
	if (!p || (job->weight && !w)) {
		glint_image_free(p);
		glint_image_free(w);
		return glint_error_set(ENOMEM, "out of memory");
	}
	glint_image_free(job->photo);
	glint_image_free(job->weight);
	job->photo = p;
	job->weight = w;
	apply_window(job, &win);
	return 0;
}

void glint_fit_job_unload(struct glint_fit_job *job)
{
	glint_image_free(job->photo);
	glint_image_free(job->weight);
	job->photo = job->weight = NULL;
}

/* What a joint fit cannot do (yet): checked before any work. */
static int joint_check(const struct glint_fit_job *job)
{
	if (job->nalso + 1 > GLINT_FIT_MAX_VIEWS)
		return glint_error_set(
			EINVAL, "%d photos: a joint fit takes at most %d",
			job->nalso + 1, GLINT_FIT_MAX_VIEWS);
	if (!job->model)
		return glint_error_set(EINVAL,
				       "--model auto chooses from one photo: "
				       "name the model for a joint fit");
	if (job->ladder > 0)
		return glint_error_set(EINVAL,
				       "the fidelity ladder works on one "
				       "photo: fit the photos one by one with "
				       "it, or jointly without it");
	return 0;
}

/* Trace photo k's scene into r. */
static int trace_view(const struct glint_fit_job *job, int k, int nviews,
		      struct glint_renderer *r)
{
	struct glint_progress prog;
	char what[32];

	snprintf(what, sizeof(what), nviews > 1 ? "trace %d" : "trace", k + 1);
	glint_progress_start(&prog, what, job->scene.cam.height);
	int ret = glint_renderer_init(r, &job->scene, job->nthreads, &prog);
	glint_progress_finish(&prog);
	if (ret < 0 && nviews > 1)
		ret = glint_error_prefix(-ret, "%s", job->scene_path);
	return ret;
}

/* Photo k's final render, its record and its misfit by angle. */
static int render_view(struct glint_renderer *r,
		       const struct glint_model_ops *model,
		       const struct glint_fit_result *res, struct view_out *vo)
{
	const struct glint_fit_job *job = vo->job;
	int w = job->scene.cam.width, h = job->scene.cam.height;

	vo->img = glint_image_new(w, h);
	vo->cov = glint_image_new(w, h);
	if (!vo->img || !vo->cov)
		return glint_error_set(ENOMEM, "out of memory");
	int ret = render_final(r, job, model, res->p, res->seconds, vo->img,
			       vo->cov, &vo->render_info);
	if (ret < 0)
		return ret;
	if (job->window.frame_width)
		json_object_set_new(
			vo->render_info, "window",
			json_pack("{s:i, s:i, s:i, s:i, s:i, s:i}", "x",
				  job->window.x, "y", job->window.y, "width", w,
				  "height", h, "frame_width",
				  job->window.frame_width, "frame_height",
				  job->window.frame_height));
	vo->have_mf = glint_misfit_analyse(&r->gb, r->env, job->photo, vo->img,
					   job->weight, vo->cov, &vo->mf) == 0;
	if (!vo->have_mf)
		glint_error_clear();
	return 0;
}

/*
 * Whether the fit is taken, by the stated rule: over all its pixels and,
 * in a joint fit, on every photo (each gets its entry in "photos").  A
 * refused one's reason goes to *why_refused (the photo it concerns).
 */
static int judge(const struct glint_fit_job *job,
		 const struct glint_fit_result *res,
		 const struct view_out *outs, int nviews, json_t *doc,
		 char *why_refused, size_t n)
{
	struct glint_fit_verdict v;
	int accepted = glint_fit_judge(res, job->accept_rmse, &v);

	snprintf(why_refused, n, "%s: fit refused: %s", job->photo_path,
		 v.verdict);
	json_object_set_new(doc, "accepted", json_boolean(accepted));
	json_object_set_new(doc, "acceptance", glint_fit_verdict_json(res, &v));
	json_t *photos = nviews > 1 ? json_array() : NULL;
	for (int k = 0; photos && k < nviews; k++) {
		struct glint_fit_result *one = malloc(sizeof(*one));
		const struct view_out *vo = &outs[k];
		char name[32], cname[32];
		if (!one)
			continue;
		glint_fit_result_view(res, k, one);
		int ok = glint_fit_judge(one, job->accept_rmse, &v);
		if (!ok && accepted)
			snprintf(why_refused, n,
				 "%s (photo %d of %d): fit refused: %s",
				 vo->job->photo_path, k + 1, nviews, v.verdict);
		accepted &= ok;
		view_file(k, "render", ".exr", name, sizeof(name));
		view_file(k, "compare", ".png", cname, sizeof(cname));
		json_array_append_new(
			photos,
			json_pack(
				"{s:s, s:s, s:i, s:i, s:o, s:o, s:f, s:o, "
				"s:s, s:s, s:o*, s:o*}",
				"scene", vo->job->scene_path, "photo",
				vo->job->photo_path, "pixels", one->pixels,
				"interior_pixels", one->interior, "rmse",
				glint_json_real_or_null(one->rmse),
				"relative_rmse",
				glint_json_real_or_null(one->rel_rmse),
				"weighted_cost", one->wcost, "acceptance",
				glint_fit_verdict_json(one, &v), "render", name,
				"compare", cname, "misfit",
				vo->have_mf ? glint_misfit_json(&vo->mf) : NULL,
				"final_render", json_incref(vo->render_info)));
		free(one);
	}
	if (photos)
		json_object_set_new(doc, "photos", photos);
	json_object_set_new(doc, "accepted", json_boolean(accepted));
	return accepted;
}

int glint_fit_job_run(const struct glint_fit_job *job, json_t **result)
{
	int nv = 1 + (job->nalso > 0 ? job->nalso : 0), traced = 0;
	struct glint_renderer *rs = NULL;
	struct view_out *outs = NULL;
	struct glint_fit_result res;
	const struct glint_model_ops *model = NULL;
	json_t *fidelity = NULL, *selection = NULL, *why = NULL, *doc = NULL;
	int ret;

	*result = NULL;
	ret = nv > 1 ? joint_check(job) : 0;
	if (ret == 0)
		ret = check_outputs(job);
	if (ret < 0)
		return ret;
	rs = calloc((size_t)nv, sizeof(*rs));
	outs = calloc((size_t)nv, sizeof(*outs));
	if (!rs || !outs) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	for (int k = 0; k < nv; k++)
		outs[k].job = k ? &job->also[k - 1] : job;
	for (; traced < nv && ret == 0; traced++)
		ret = trace_view(outs[traced].job, traced, nv, &rs[traced]);
	if (ret < 0) {
		traced--; /* the failed one released itself */
		goto out;
	}
	struct glint_fit_opts o = job->opts;
	o.nthreads = job->nthreads;
	struct glint_fit_view views[GLINT_FIT_MAX_VIEWS];
	for (int k = 0; k < nv; k++)
		views[k] = (struct glint_fit_view){ &rs[k], outs[k].job->photo,
						    outs[k].job->weight };
	ret = run_fit(views, nv, job, &o, &model, &res, &why, &selection,
		      &fidelity);
	if (o.progress)
		o.progress(o.progress_ctx, NULL, 0,
			   0); /* the passes are done */
	/* The result rendered in full in each photo's scene (MIS, the
	 * scene's sample counts). */
	for (int k = 0; k < nv && ret == 0; k++)
		ret = render_view(&rs[k], model, &res, &outs[k]);
	if (ret < 0)
		goto out;
	doc = params_doc(job, &o, &res);
	if (!doc) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	json_object_set(doc, "render", outs[0].render_info);
	if (why)
		json_object_set(doc, "model_choice", why);
	if (fidelity)
		json_object_set(doc, "fidelity", fidelity);
	if (selection)
		json_object_set(doc, "model_selection", selection);
	if (outs[0].have_mf)
		json_object_set_new(doc, "misfit",
				    glint_misfit_json(&outs[0].mf));
	/* A fit is taken as a measurement by a stated rule; a refused one
	 * leaves its evidence beside the output, which stays as it was. */
	char refused[1024];
	if (!judge(job, &res, outs, nv, doc, refused, sizeof(refused))) {
		char dir[GLINT_PATH_MAX];
		ret = glint_path_fmt(dir, sizeof(dir), "%s.refused",
				     job->out_dir);
		if (!ret)
			ret = write_results(job, dir, doc, outs, nv, NULL,
					    model);
		if (!ret)
			ret = glint_error_set(EINVAL,
					      "%s (the fit's diagnostics are "
					      "in %s)",
					      refused, dir);
		goto out;
	}
	struct glint_export exports[GLINT_EXPORT_NFORMATS];
	if (job->exports)
		json_object_set_new(doc, "exports",
				    refit_exports(job, model, res.p, exports));
	ret = write_results(job, job->out_dir, doc, outs, nv,
			    job->exports ? exports : NULL, model);
	if (ret < 0)
		goto out;
	json_object_set_new(doc, "output", json_string(job->out_dir));
	*result = doc;
	doc = NULL;
out:
	json_decref(doc);
	json_decref(why);
	json_decref(fidelity);
	json_decref(selection);
	for (int k = 0; outs && k < nv; k++) {
		glint_image_free(outs[k].img);
		glint_image_free(outs[k].cov);
		json_decref(outs[k].render_info);
	}
	for (int k = 0; k < traced; k++)
		glint_renderer_release(&rs[k]);
	free(rs);
	free(outs);
	return ret;
}
