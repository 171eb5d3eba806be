/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_RENDER_JOB_H
#define GLINT_FIT_RENDER_RENDER_JOB_H

/*
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: runs its own worker threads.  Who
 * frees: json_decref() the result document.
 */

#include "fit/brdf/model.h"
#include "fit/scene/scene.h"

#include <jansson.h>

/* One render, as `glint render` and `glint demo` run it. */
struct glint_render_job {
	struct glint_scene scene;
	const struct glint_model *model;
	double params[GLINT_MAX_PARAMS];
	const char *out_exr;	  /* required */
	const char *out_png;	  /* may be NULL */
	const char *out_coverage; /* may be NULL */
	int half;
	int background;
	int nthreads;
	double exposure; /* NaN = auto */
};

/* Render and write the files (each atomically); *result describes what
 * was done (the caller json_decref()s it). */
int glint_render_job_run(const struct glint_render_job *job, json_t **result);

#endif
