/* SPDX-License-Identifier: MIT */
/*
 * One fit as `glint fit`, `glint demo` and the queue run it: trace, choose
 * the model (--model auto, --select-model), fit (or run the fidelity
 * ladder), check that the photo shows the scene's sphere, render the
 * result and write the result folder atomically.
 */
#define _POSIX_C_SOURCE 200809L
#include "job.h"
#include "job_internal.h"

#include "ladder.h"
#include "misfit.h"
#include "per_light.h"
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
		      const struct glint_model **out, json_t **why)
{
	const struct glint_model *cand[2] = { &glint_model_torrance_sparrow,
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
			const struct glint_model **model,
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
	/* c: the candidate reported (below) */
	if (sel->has_fit[sel->chosen]) {
		*res = sel->fit[sel->chosen];
	} else if (sel->chosen == GLINT_SEL_LAMBERT) {
		ret = glint_fit_views(views, nv, &glint_model_lambert, o, res);
	} else {
		/* Grey specular: the reduced fit's standard errors are the
		 * textbook ones (no sample sets, no model error, no
		 * discrepancy), so the full model's fit is the result, with
		 * its whole uncertainty: grey nests in it, and its specular
		 * channels' intervals say how grey the material is.  The grey
		 * values stay in model_selection. */
		*res = sel->fit[GLINT_SEL_RGB];
		c = &sel->c[GLINT_SEL_RGB];
		glint_log_info("--select-model: grey specular scores best; "
			       "the full model's fit is reported, with its "
			       "intervals (the grey fit's values are in "
			       "model_selection)");
	}
	*model = c->model;
	res->model = c->model;
	glint_log_info("--select-model: %s", sel->why);
	*why = glint_selection_to_json(sel);
	if (*why && sel->chosen == GLINT_SEL_GREY)
		json_object_set_new(
			*why, "reported",
			json_string("torrance-sparrow: grey specular scores "
				    "best, and the full model's fit is "
				    "reported with its whole uncertainty (a "
				    "grey fit has textbook standard errors "
				    "only)"));
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
		   const struct glint_model **model,
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
	if (job->select && !glint_model_is_transparent(*model))
		return select_model(views, nv, o, 1, model, res, selection);
	if (job->ladder > 0 && !glint_model_is_transparent(*model)) {
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
	if (ret < 0 || job->no_auto_select ||
	    glint_model_is_transparent(*model) || (*model)->bxdf->nlobes < 2 ||
	    !glint_fit_needs_selection(res))
		return ret;
	glint_log_info("the photo%s not determine every parameter of %s: "
		       "choosing the model by BIC (--select-model)",
		       nv > 1 ? "s do" : " does", (*model)->name);
	return select_model(views, nv, o, 0, model, res, selection);
}

/* Several photos: each fitted alone too, and the drift of each
 * parameter with the light's angle as *doc (fit/per_light.h); the
 * verdict logged. */
static int per_light(const struct glint_fit_view *views, int nv,
		     const struct glint_model *model,
		     const struct glint_fit_opts *o,
		     const struct glint_fit_result *joint, json_t **doc)
{
	struct glint_per_light *pl = malloc(sizeof(*pl));
	int ret = pl ? glint_fit_per_light(views, nv, model, o, joint, pl)
		     : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0) {
		*doc = glint_per_light_json(pl, model);
		if (pl->ndrift)
			glint_log_warn("per-light fits: %s", pl->verdict);
		else
			glint_log_info("per-light fits: %s", pl->verdict);
	}
	free(pl);
	return ret;
}

json_t *glint_fit_job_shown_path(const struct glint_fit_job *job,
				 const char *path)
{
	char buf[GLINT_PATH_MAX];
	if (!job->shown_dir || strncmp(path, "./", 2) ||
	    glint_path_join(buf, sizeof(buf), job->shown_dir, path + 2) < 0)
		return json_string(path);
	return json_string(buf);
}

/* params.json for a fit (without the model choice, selection, fidelity
 * and output, which the caller adds); a new reference. */
static json_t *params_doc(const struct glint_fit_job *job,
			  const struct glint_fit_opts *o,
			  const struct glint_fit_result *res)
{
	const struct glint_model *model = res->model;
	struct glint_fit_opts ro = *o; /* the samples it took, if not said */
	glint_fit_resolve_samples(&ro, job->scene.spp);
	json_t *doc = json_pack(
		"{s:s,s:s,s:o,s:o,s:{s:s,s:b,s:b,s:f,s:i,s:i},s:f,s:f,s:f,"
		"s:i,s:i,s:i,s:o,s:f,s:f,s:{s:o,s:o,s:f},s:s}",
		"model", model->name, "conventions", model->conventions,
		"material", glint_material_to_json(model, res->p), "parameters",
		glint_fit_params_json(res), "method", "name",
		glint_fit_method_name(o->method), "coarse_to_fine",
		o->coarse_to_fine, "faithful", o->faithful, "mask_threshold",
		o->mask_threshold, "light_samples",
		res->light_samples ? res->light_samples : ro.light_samples,
		"lobe_samples",
		res->lobe_samples ? res->lobe_samples : ro.lobe_samples, "cost",
		res->cost, "rmse", res->rmse, "relative_rmse", res->rel_rmse,
		"pixels", res->pixels, "interior_pixels", res->interior,
		"specular_pixels", res->specular_pixels, "passes",
		glint_fit_passes_json(res), "seconds", res->seconds,
		"setup_seconds", res->setup_seconds, "inputs", "scene",
		glint_fit_job_shown_path(job, job->scene_path), "photo",
		glint_fit_job_shown_path(job, job->photo_path),
		"sphere_diameter_m", 2 * job->scene.sphere_radius, "weighting",
		job->weight			       ? "weight image"
		: o->weighting == GLINT_WEIGHT_POISSON ? "poisson"
						       : "uniform");
	if (!doc)
		return NULL;
	char name[256];
	json_object_set_new(json_object_get(doc, "material"), "name",
			    json_string(job_material_name(job, name)));
	json_object_set_new(doc, "optimizer",
			    json_string(o->optimizer == GLINT_OPT_LM ? "lm"
					: o->optimizer == GLINT_OPT_ANNEAL
						? "anneal"
						: "auto"));
	json_object_set_new(doc, "uncertainty",
			    glint_fit_uncertainty_json(res));
	/* The fitter's own Monte Carlo noise against the photo's, per
	 * parameter and per value (variance ratios at the last check), and
	 * its sampling lean over the noise's standard error (the samples
	 * are raised above 1, 0.25 and 0.5: docs/fitting.md). */
	if (res->light_samples) {
		json_t *meth = json_object_get(doc, "method");
		json_object_set_new(meth, "sampling_over_noise",
				    json_real(res->mc_over_noise));
		json_object_set_new(meth, "model_noise_over_residual",
				    json_real(res->model_noise));
		json_object_set_new(meth, "lean_over_noise",
				    json_real(res->lean_over_noise));
	}
	return doc;
}

/* The material's name: job->name, else its output folder's (a session's
 * fit: the session's). */
const char *job_material_name(const struct glint_fit_job *job, char buf[256])
{
	if (job->name && *job->name)
		return job->name;
	return glint_export_name_from_path(job->out_dir, buf, 256);
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
		       const struct glint_model *model,
		       const struct glint_fit_result *res, struct view_out *vo)
{
	const struct glint_fit_job *job = vo->job;
	int w = job->scene.cam.width, h = job->scene.cam.height;

	vo->img = glint_image_new(w, h);
	vo->cov = glint_image_new(w, h);
	if (!vo->img || !vo->cov)
		return glint_error_set(ENOMEM, "out of memory");
	int ret = job_render_final(r, job, model, res->p, res->seconds, vo->img,
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
	/* the render's own noise, measured: part of the residual */
	json_t *qn = json_object_get(vo->render_info, "noise");
	double q = json_is_number(qn) ? json_number_value(qn) : NAN;
	vo->have_mf =
		glint_misfit_analyse(&r->gb, r->env, job->photo, vo->img,
				     job->weight, vo->cov, q, &vo->mf) == 0;
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
		job_view_file(k, "render", ".exr", name, sizeof(name));
		job_view_file(k, "compare", ".png", cname, sizeof(cname));
		json_array_append_new(
			photos,
			json_pack(
				"{s:o, s:o, s:i, s:i, s:o, s:o, s:f, s:o, "
				"s:s, s:s, s:o*, s:o*}",
				"scene",
				glint_fit_job_shown_path(job,
							 vo->job->scene_path),
				"photo",
				glint_fit_job_shown_path(job,
							 vo->job->photo_path),
				"pixels", one->pixels, "interior_pixels",
				one->interior, "rmse",
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
	const struct glint_model *model = NULL;
	json_t *fidelity = NULL, *selection = NULL, *why = NULL, *doc = NULL;
	json_t *per = NULL;
	int ret;

	*result = NULL;
	ret = nv > 1 ? joint_check(job) : 0;
	if (ret == 0)
		ret = job_check_outputs(job);
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
	/* the sources' flux terms, each on its own photo's rows
	 * (fit/light_sources.c) */
	struct glint_fit_light_source srcs[GLINT_FIT_MAX_SOURCES];
	o.sources = srcs;
	o.nsources = 0;
	for (int k = 0; k < nv; k++) {
		const struct glint_fit_job *jk = outs[k].job;
		for (int s = 0; s < jk->nsources; s++) {
			if (o.nsources == GLINT_FIT_MAX_SOURCES) {
				glint_log_warn("photo %d's light source %d: "
					       "the intervals carry the "
					       "flux of %d sources at most",
					       k + 1, s + 1,
					       GLINT_FIT_MAX_SOURCES);
				break;
			}
			srcs[o.nsources] = jk->sources[s];
			srcs[o.nsources++].view = k;
		}
	}
	for (int k = 0; k < nv; k++) {
		double pd = outs[k].job->map_pixel_deg;
		if (pd < 0 || o.map_pixel_deg < 0)
			o.map_pixel_deg = -1;
		else
			o.map_pixel_deg = fmax(o.map_pixel_deg, pd);
	}
	for (int k = 0; k < nv; k++)
		for (int c = 0; c < 3; c++)
			o.light_scale_sigma[c] =
				fmax(o.light_scale_sigma[c],
				     outs[k].job->scene.env_scale_sigma[c]);
	struct glint_fit_view views[GLINT_FIT_MAX_VIEWS];
	for (int k = 0; k < nv; k++)
		views[k] = (struct glint_fit_view){ &rs[k], outs[k].job->photo,
						    outs[k].job->weight };
	ret = run_fit(views, nv, job, &o, &model, &res, &why, &selection,
		      &fidelity);
	if (ret == 0 && nv > 1 && !job->no_per_light &&
	    !glint_model_is_transparent(model))
		ret = per_light(views, nv, model, &o, &res, &per);
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
	if (per)
		json_object_set(doc, "per_light", per);
	/* A fit is taken as a measurement by a stated rule; a refused one
	 * leaves its evidence beside the output, which stays as it was. */
	char refused[1024];
	if (!judge(job, &res, outs, nv, doc, refused, sizeof(refused))) {
		char dir[GLINT_PATH_MAX];
		ret = glint_path_fmt(dir, sizeof(dir), "%s.refused",
				     job->out_dir);
		if (!ret)
			ret = job_write_results(job, dir, doc, outs, nv, NULL,
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
		json_object_set_new(
			doc, "exports",
			job_refit_exports(job, model, res.p, exports));
	ret = job_write_results(job, job->out_dir, doc, outs, nv,
				job->exports ? exports : NULL, model);
	if (ret < 0)
		goto out;
	json_object_set_new(doc, "output",
			    glint_fit_job_shown_path(job, job->out_dir));
	*result = doc;
	doc = NULL;
out:
	json_decref(doc);
	json_decref(per);
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
