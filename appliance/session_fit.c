/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "appliance/session_fit.h"

#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/json.h"
#include "core/lockfile.h"
#include "core/log.h"
#include "core/path.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* The photos a request names, and the session locks held for the fit. */
struct inputs {
	int n;
	const char *scene[GLINT_FIT_MAX_VIEWS], *photo[GLINT_FIT_MAX_VIEWS];
	const char *weights[GLINT_FIT_MAX_VIEWS];
	struct glint_session_fit_files fs[GLINT_FIT_MAX_VIEWS];
	int lock[GLINT_FIT_MAX_VIEWS];
	int fitted_meanwhile; /* one session, fitted by the fit waited for */
	struct glint_run_samples rs;
};

static int is_dir(const char *path)
{
	struct stat st;

	return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* A failure in the inputs given: the command line's usage error. */
#define USAGE(out, ...) ((out)->usage = 1, glint_error_set(EINVAL, __VA_ARGS__))

/* Sessions: each one's scene, sample and merge weights, locked. */
static int session_inputs(char *const *dirs, int n,
			  const struct glint_fit_request *req,
			  struct inputs *in)
{
	for (int k = 0; k < n; k++) {
		struct glint_session_fit_files *fs = &in->fs[k];
		int ret = glint_session_fit_open(dirs[k], req->wait, fs,
						 &in->lock[k]);
		if (ret < 0)
			return ret;
		in->fitted_meanwhile = n == 1 && ret == 1;
		in->n = k + 1;
		in->scene[k] = fs->scene;
		in->photo[k] = fs->photo;
		in->weights[k] = req->nweights	  ? req->weights[k]
				 : fs->weights[0] ? fs->weights
						  : NULL;
	}
	return 0;
}

/*
 * One SESSION, several SESSIONs (a joint fit of their samples, an output
 * folder required), a RUN, or SCENE PHOTO pairs; weights once per photo.
 * *out_dir defaults to the session's fit folder, the run's, or fit-out.
 */
static int choose_inputs(const struct glint_fit_request *req, struct inputs *in,
			 const char **out_dir, struct glint_fit_outcome *out)
{
	int sessions = req->nargs >= 1, n;
	int nw = req->nweights;

	in->n = 0;
	for (int k = 0; k < req->nargs; k++)
		sessions &= is_dir(req->args[k]);
	/* one argument can only be a session: its own error says what is
	 * wrong with it */
	sessions |= req->nargs == 1;
	if (!sessions && (req->nargs < 2 || req->nargs % 2))
		return USAGE(out, "expected SCENE.json and PHOTO (or several "
				  "such pairs), or capture SESSIONs");
	n = sessions ? req->nargs : req->nargs / 2;
	_Static_assert(GLINT_RUN_MAX_SAMPLES <= GLINT_FIT_MAX_VIEWS,
		       "a run's samples fit jointly");
	int run = req->nargs == 1 ? glint_run_read(req->args[0], &in->rs) : 0;
	if (run < 0)
		return run;
	if (run) {
		char *dirs[GLINT_RUN_MAX_SAMPLES];
		n = in->rs.n;
		for (int k = 0; k < n; k++) {
			/* a run's samples are folders in it: a link there
			 * could lead a worker's fit anywhere */
			struct stat st;
			if (lstat(in->rs.session[k], &st) < 0 ||
			    !S_ISDIR(st.st_mode))
				return glint_error_set(
					EINVAL,
					"run %s: sample %s is not a folder in "
					"the run",
					req->args[0], in->rs.session[k]);
			dirs[k] = in->rs.session[k];
		}
		if (nw && nw != n)
			return USAGE(out,
				     "--weights given %d times for a run of "
				     "%d samples",
				     nw, n);
		int ret = session_inputs(dirs, n, req, in);
		if (ret == 0 && !*out_dir)
			*out_dir = in->rs.out;
		return ret;
	}
	if (n > GLINT_FIT_MAX_VIEWS)
		return USAGE(out, "%d photos: a joint fit takes at most %d", n,
			     GLINT_FIT_MAX_VIEWS);
	if (nw && nw != n)
		return USAGE(out,
			     "--weights given %d times for %d photo%s: once "
			     "per photo, in their order, or not at all",
			     nw, n, n > 1 ? "s" : "");
	if (sessions && n > 1 && !*out_dir)
		return USAGE(out,
			     "a joint fit of %d sessions writes into no "
			     "session's folder: give -o DIR",
			     n);
	if (sessions) {
		int ret = session_inputs(req->args, n, req, in);
		if (ret == 0 && !*out_dir)
			*out_dir = in->fs[0].out;
		return ret;
	}
	for (int k = 0; k < n; k++) {
		in->scene[k] = req->args[2 * k];
		in->photo[k] = req->args[2 * k + 1];
		in->weights[k] = nw ? req->weights[k] : NULL;
	}
	in->n = n;
	if (!*out_dir)
		*out_dir = "fit-out";
	return 0;
}

/* The photos loaded: the first into job, the others into also[]. */
static int load_inputs(struct glint_fit_job *job, struct glint_fit_job *also,
		       const struct inputs *in)
{
	job->scene_path = in->scene[0];
	job->photo_path = in->photo[0];
	int ret = glint_fit_job_load(job, in->weights[0]);
	if (ret == 0)
		ret = glint_fit_job_crop(job);
	job->also = also;
	job->nalso = 0;
	for (int k = 1; k < in->n && ret == 0; k++) {
		struct glint_fit_job *a = &also[k - 1];
		memset(a, 0, sizeof(*a));
		a->scene_path = in->scene[k];
		a->photo_path = in->photo[k];
		a->srgb = job->srgb;
		a->nthreads = job->nthreads;
		a->render_budget_s = job->render_budget_s;
		job->nalso = k;
		ret = glint_fit_job_load(a, in->weights[k]);
		if (ret == 0)
			ret = glint_fit_job_crop(a);
	}
	return ret;
}

static double num(const json_t *o, const char *key)
{
	const json_t *v = json_object_get(o, key);
	return json_is_number(v) ? json_number_value(v) : NAN;
}

/* The outcome's values from the result document. */
static void outcome_from(const json_t *doc, struct glint_fit_outcome *o)
{
	const char *model = json_string_value(json_object_get(doc, "model"));
	const struct glint_model *m = model ? glint_model_find(model) : 0;
	snprintf(o->model, sizeof(o->model), "%s", model ? model : "");
	o->transparent = m && glint_model_is_transparent(m);
	o->relative_rmse = num(doc, "relative_rmse");
	o->seconds = num(doc, "seconds");
	o->pixels = (int)json_integer_value(json_object_get(doc, "pixels"));
	size_t k;
	json_t *e;
	json_array_foreach(json_object_get(doc, "parameters"), k, e)
	{
		if (k >= GLINT_OUTCOME_MAX_PARAMS)
			break;
		struct glint_fit_param_value *p = &o->param[k];
		const json_t *iv = json_object_get(e, "interval");
		snprintf(p->name, sizeof(p->name), "%s",
			 json_string_value(json_object_get(e, "name")));
		p->value = num(e, "value");
		p->stderr_ = num(e, "stderr");
		p->lo = json_is_number(json_array_get(iv, 0))
				? json_number_value(json_array_get(iv, 0))
				: NAN;
		p->hi = json_is_number(json_array_get(iv, 1))
				? json_number_value(json_array_get(iv, 1))
				: NAN;
		p->determined =
			json_is_true(json_object_get(e, "determined")) ||
			!json_object_get(e, "determined");
		o->nparams = (int)k + 1;
	}
}

void glint_fit_request_init(struct glint_fit_request *req)
{
	memset(req, 0, sizeof(*req));
	req->job.model = &glint_model_torrance_sparrow;
	glint_fit_default_opts(&req->job.opts);
}

int glint_session_fit(struct glint_fit_request *req,
		      struct glint_fit_outcome *out)
{
	static struct glint_fit_job also[GLINT_FIT_MAX_VIEWS - 1];
	static struct inputs in;
	struct glint_fit_job *job = &req->job;

	memset(out, 0, sizeof(*out));
	memset(&in, 0, sizeof(in));
	for (int k = 0; k < GLINT_FIT_MAX_VIEWS; k++)
		in.lock[k] = -1;
	int ret = choose_inputs(req, &in, &job->out_dir, out);
	json_t *doc = NULL;
	/* A session's (or run's) own fit folder holds its latest fit: a
	 * fit of it replaces the previous one; a folder named with -o
	 * follows the one overwrite rule (--force). */
	if (ret == 0 &&
	    (job->out_dir == in.rs.out || job->out_dir == in.fs[0].out))
		job->replace = 1;
	/* --wait on a session whose running fit then wrote its result into
	 * the same folder: that result is the answer, not a second fit */
	int taken = ret == 0 && in.fitted_meanwhile && job->out_dir &&
		    !strcmp(job->out_dir, in.fs[0].out);
	if (taken) {
		char path[GLINT_PATH_MAX];
		ret = glint_path_join(path, sizeof(path), job->out_dir,
				      "params.json");
		if (ret == 0)
			ret = glint_json_load(path, &doc);
		if (ret == 0) {
			json_object_set_new(
				doc, "output",
				glint_fit_job_shown_path(job, job->out_dir));
			glint_log_info("%s was fitted by the fit waited for: "
				       "its result is the answer (run glint "
				       "fit again without --wait to fit anew)",
				       in.fs[0].out);
		}
	}
	if (ret == 0 && !taken)
		ret = load_inputs(job, also, &in);
	if (ret == 0 && !taken)
		ret = glint_fit_job_run(job, &doc);
	glint_fit_job_unload(job);
	for (int k = 0; k < job->nalso; k++)
		glint_fit_job_unload(&also[k]);
	job->also = NULL;
	job->nalso = 0;
	for (int k = 0; k < GLINT_FIT_MAX_VIEWS; k++)
		glint_lockfile_release(in.lock[k]);
	out->nphotos = in.n;
	if (job->out_dir)
		snprintf(out->out_dir, sizeof(out->out_dir), "%s",
			 job->out_dir);
	if (ret < 0) {
		json_decref(doc);
		return ret;
	}
	outcome_from(doc, out);
	out->doc = doc;
	return 0;
}

json_t *glint_fit_outcome_parameters(const struct glint_fit_outcome *o)
{
	json_t *a = json_array();
	for (int k = 0; a && k < o->nparams; k++) {
		const struct glint_fit_param_value *p = &o->param[k];
		json_t *iv = isfinite(p->lo) && isfinite(p->hi)
				     ? json_pack("[f, f]", p->lo, p->hi)
				     : json_null();
		json_array_append_new(
			a,
			json_pack("{s:s, s:f, s:o, s:o, s:b}", "name", p->name,
				  "value", p->value, "stderr",
				  isfinite(p->stderr_) ? json_real(p->stderr_)
						       : json_null(),
				  "interval", iv, "determined", p->determined));
	}
	return a;
}
