/* SPDX-License-Identifier: MIT */
/*
 * The job's result folder: params.json, each view's render and compare
 * image, the exports, written as one atomic folder (job.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "fit/job.h"
#include "fit/job_internal.h"

#include "fit/ladder.h"
#include "fit/misfit.h"
#include "fit/report.h"
#include "fit/select.h"
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

/* Photo k's render and compare image names: render.exr, render-2.exr, ... */
void job_view_file(int k, const char *stem, const char *ext, char *buf,
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
		{ "VIEW ANGLE", "DEG FROM VIEW", GLINT_MISFIT_BANDS, ve,
		  mean[0], se[0], px[0] },
		{ "MIRROR ANGLE", "DEG FROM MIRROR", GLINT_MISFIT_BANDS, me,
		  mean[1], se[1], px[1] },
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
	job_view_file(k, "render", ".exr", name, sizeof(name));
	int ret = glint_image_write(
		glint_atomic_dir_file(ad, name, path, sizeof(path)), vo->img,
		&wo);
	job_view_file(k, "compare", ".png", name, sizeof(name));
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
		"params.json",	 "report.html",	  "render.exr",
		"compare.png",	 "material.gltf", "material.xml",
		"material.pbrt", "material.py",	  "material.mtlx",
	};
	enum { NFIXED = sizeof(fixed) / sizeof(fixed[0]) };
	static char more[2 * (GLINT_FIT_MAX_VIEWS - 1)][32];
	static const char *names[NFIXED + 2 * (GLINT_FIT_MAX_VIEWS - 1) + 1];
	if (names[0])
		return names;
	int n = 0;
	for (int k = 1; k < GLINT_FIT_MAX_VIEWS; k++) {
		job_view_file(k, "render", ".exr", more[2 * k - 2], 32);
		job_view_file(k, "compare", ".png", more[2 * k - 1], 32);
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
int job_write_results(const struct glint_fit_job *job, const char *dir,
		      const json_t *doc, const struct view_out *outs,
		      int nviews, const struct glint_export *exports,
		      const struct glint_model *model)
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
	if (!ret) {
		char *html = glint_fit_report_html(doc, nviews);
		ret = html ? glint_atomic_write_file(
				     glint_atomic_dir_file(&ad, "report.html",
							   path, sizeof(path)),
				     html, strlen(html))
			   : glint_error_set(ENOMEM, "out of memory");
		free(html);
	}
	char name_buf[256];
	for (int k = 0; exports && !ret && k < GLINT_EXPORT_NFORMATS; k++) {
		const struct glint_export *e = &exports[k];
		char file[64];
		if ((int)e->format != k)
			continue;
		snprintf(file, sizeof(file), "material%s",
			 glint_export_extension(e->format));
		char *mtext =
			glint_export_text(e, job_material_name(job, name_buf),
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
json_t *job_refit_exports(const struct glint_fit_job *job,
			  const struct glint_model *model, const double *p,
			  struct glint_export *exports)
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
int job_check_outputs(const struct glint_fit_job *job)
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
	if (!ret && !job->replace && !glint_path_is_empty_dir(job->out_dir))
		ret = glint_error_set(EEXIST,
				      "%s holds a previous result: refusing to "
				      "replace it (--force replaces glint's "
				      "files there)",
				      job->out_dir);

	if (!ret)
		ret = glint_path_fmt(dir, sizeof(dir), "%s.refused",
				     job->out_dir);
	if (!ret)
		ret = glint_atomic_dir_check(dir, output_names(), NULL, inputs,
					     job->force);
	return ret;
}
