/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_JOB_INTERNAL_H
#define GLINT_FIT_JOB_INTERNAL_H

/*
 * What the job's parts share (private to fit/job*.c): one job at a time
 * per call, from the calling thread; errors are negative errno values
 * with glint_error_msg() set.
 */

#include "fit/job.h"
#include "core/atomic_dir.h"
#include "fit/misfit.h"
#include "fit/render/render.h"
#include "export/export.h"

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

const char *job_material_name(const struct glint_fit_job *job, char buf[256]);

int job_render_final(struct glint_renderer *r, const struct glint_fit_job *job,
		     const struct glint_model *model, const double *p,
		     double fit_s, struct glint_image *img,
		     struct glint_image *cov, json_t **info);

void job_view_file(int k, const char *stem, const char *ext, char *buf,
		   size_t n);

int job_write_results(const struct glint_fit_job *job, const char *dir,
		      const json_t *doc, const struct view_out *outs,
		      int nviews, const struct glint_export *exports,
		      const struct glint_model *model);

json_t *job_refit_exports(const struct glint_fit_job *job,
			  const struct glint_model *model, const double *p,
			  struct glint_export *exports);

int job_check_outputs(const struct glint_fit_job *job);

#endif
