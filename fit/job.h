/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_JOB_H
#define GLINT_FIT_JOB_H

/*
 * One fit as `glint fit`, `glint demo` and the queue run it, and the
 * result folder it writes (docs/scene.md, "params.json").
 */

#include "fit.h"

#include <jansson.h>

struct glint_fit_job {
	const char *scene_path; /* for the record and messages */
	const char *photo_path;
	struct glint_scene scene;
	const struct glint_model_ops *model; /* NULL: --model auto */
	struct glint_image *photo;	     /* owned by the caller */
	struct glint_image *weight;	     /* may be NULL */
	/* opts.progress (may be NULL) is called as passes run, and once
	 * with pass NULL when they are done */
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
 * render.exr, compare.png} as one atomic folder.  A fit whose relative
 * RMSE says the photo does not show the scene's sphere is refused
 * (-EINVAL, nothing written).  *result is the params.json document plus
 * "output" (the caller json_decref()s it).
 */
int glint_fit_job_run(const struct glint_fit_job *job, json_t **result);

/* params.json's "parameters" (name, value, stderr, at_bound, bounds) and
 * "passes" arrays for a result; new references. */
json_t *glint_fit_params_json(const struct glint_fit_result *r);
json_t *glint_fit_passes_json(const struct glint_fit_result *r);

#endif
