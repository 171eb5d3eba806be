/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_FIT_JOB_H
#define GLINT_CMD_FIT_JOB_H

#include "fit/fit.h"

#include <jansson.h>

/* One fit as `glint fit` and `glint demo` run it. */
struct fit_job {
	const char *scene_path;
	const char *photo_path;
	struct glint_scene scene;
	const struct glint_model_ops *model;
	struct glint_image *photo;  /* owned by the caller */
	struct glint_image *weight; /* may be NULL */
	struct glint_fit_opts opts;
	const char *out_dir;
	int nthreads;
	/* > 0: run the fidelity ladder (fit/ladder.h) with this limit in
	 * standard errors and report its fit */
	double ladder;
	unsigned ladder_knobs; /* 0: all */
	/* choose among the opaque models by BIC (fit/select.h) */
	int select;
};

/*
 * Trace, fit, render the result and write out_dir/{params.json,
 * render.exr, compare.png} as one atomic folder.  *result is the
 * params.json document (caller json_decref()s).
 */
int fit_job_run(const struct fit_job *job, json_t **result);

#endif
