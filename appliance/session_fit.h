/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_SESSION_FIT_H
#define GLINT_APPLIANCE_SESSION_FIT_H

/*
 * The fit as one typed call: what `glint fit` runs, and what a queue
 * worker runs in its child for each job.  The inputs are chosen here (a
 * capture session, several sessions fitted jointly, a rig run's samples,
 * or SCENE PHOTO pairs), each session's fit lock is taken for the fit's
 * length, the photos are read and cropped, the fit runs and writes its
 * result folder (fit/job.h), and the outcome comes back as values.
 *
 * Errors: a negative errno with glint_error_msg() set; outcome->usage is
 * 1 when the inputs themselves were wrong (a count, a missing -o), which
 * the command line reports as a usage error.  Threads: one call at a
 * time per process (a joint fit's inputs live in static storage; the
 * fit itself uses job.nthreads threads).  Who frees: the caller
 * json_decref()s outcome->doc (NULL on failure).
 */

#include "fit/job.h"
#include "core/path.h"

#include <jansson.h>

struct glint_fit_request {
	/* The inputs: one SESSION or RUN folder, several SESSION folders,
	 * or SCENE PHOTO pairs (in that order, pairs flattened). */
	char *const *args;
	int nargs;
	/* --weights, once per photo in order, or none (nweights 0: a
	 * session's own merge weights) */
	const char *weights[GLINT_FIT_MAX_VIEWS];
	int nweights;
	/* Wait for another fit of a session to end (else -EBUSY). */
	int wait;
	/* The fit's options, model, exports and output folder (out_dir
	 * NULL: the session's fit folder, the run's, or "fit-out").  Its
	 * inputs (scene_path, photo_path, also) are filled here. */
	struct glint_fit_job job;
};

#define GLINT_OUTCOME_MAX_PARAMS 16

struct glint_fit_param_value {
	char name[32];
	double value, stderr_, lo, hi; /* interval [lo, hi]; NAN if none */
	int determined;
};

struct glint_fit_outcome {
	int usage; /* the failure was in the inputs given */
	char out_dir[GLINT_PATH_MAX];
	char model[48];
	int nphotos;
	int transparent;
	int nparams;
	struct glint_fit_param_value param[GLINT_OUTCOME_MAX_PARAMS];
	double relative_rmse, seconds;
	int pixels;
	/* The whole params.json document (plus "output"); NULL after a
	 * failure.  Not carried across a fork (glint_fit_outcome_plain). */
	json_t *doc;
};

/* Fill req->job with the defaults `glint fit` starts from. */
void glint_fit_request_init(struct glint_fit_request *req);

/* Run the fit the request asks for; *out as above. */
int glint_session_fit(struct glint_fit_request *req,
		      struct glint_fit_outcome *out);

/* The job record's "parameters" from an outcome: [{name, value, stderr,
 * interval, determined}], a new reference. */
json_t *glint_fit_outcome_parameters(const struct glint_fit_outcome *o);

#endif
