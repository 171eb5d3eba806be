/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "fit_job.h"

#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/lockfile.h"
#include "core/log.h"
#include "fit/render/compare.h"
#include "fit/ladder.h"
#include "fit/select.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

void cmd_fit_help(void)
{
	printf("usage: glint fit SCENE.json PHOTO.exr [options]\n"
	       "       glint fit SESSION [options]\n"
	       "\n"
	       "Recover a material's parameters from one HDR image of the "
	       "sphere (PHOTO, the\nscene camera's size, linear radiance) "
	       "seen under the scene's environment map.\nWrites "
	       "DIR/params.json (values, standard errors, conventions, cost, "
	       "RMSE,\niterations and time per pass), DIR/render.exr (the "
	       "fitted material rendered)\nand DIR/compare.png (photo | "
	       "render | signed error with a scale bar).\n"
	       "Given a sample's capture session (glint capture sample), it "
	       "fits SESSION/sample.exr\nwith SESSION/scene.json and the "
	       "merge's weights into SESSION/fit; one fit per\nsession at a "
	       "time (a second one is refused, or waits with --wait).\n"
	       "\n"
	       "  -o, --out DIR         result folder (default fit-out); "
	       "replaced whole,\n"
	       "                        never left half-written\n"
	       "  --model NAME          torrance-sparrow (default), lambert, "
	       "dielectric (a\n"
	       "                        transparent sphere: transmission "
	       "RGB, ior), or auto\n"
	       "                        (tries opaque and transparent, says "
	       "which and why)\n"
	       "  --optimizer O         lm, anneal (adaptive simulated "
	       "annealing, then an LM\n"
	       "                        polish) or auto (default: anneal "
	       "for transparent\n"
	       "                        models, the method's LM passes "
	       "otherwise)\n"
	       "  --seed N              annealing's random stream (default "
	       "1; runs repeat)\n"
	       "  --anneal-evals N      annealing's budget per parameter "
	       "searched (default 150)\n"
	       "  --select-model        fit torrance-sparrow, the same with a "
	       "grey specular,\n"
	       "                        without Fresnel variation, and "
	       "lambert; keep the one\n"
	       "                        with the lowest BIC on the "
	       "weighted residual (all four\n"
	       "                        with AIC, BIC and standard errors "
	       "in params.json)\n"
	       "  --ladder              fidelity ladder: try cheaper "
	       "modelling (no depth of\n"
	       "                        field, fewer samples per pixel, "
	       "smaller image and map,\n"
	       "                        fewer shading samples) and keep "
	       "each that moves no\n"
	       "                        parameter by 0.5 standard errors "
	       "or more; the choices\n"
	       "                        and their measured effects go "
	       "into params.json\n"
	       "                        (\"fidelity\"). A dozen fits: "
	       "minutes at 512 px\n"
	       "  --ladder-limit SE     the ladder's limit (implies "
	       "--ladder; default 0.5)\n"
	       "  --ladder-knobs LIST   only these (implies --ladder): dof, "
	       "spp, resolution,\n"
	       "                        env, samples, comma-separated; the "
	       "others stay as the\n"
	       "                        scene and options have them\n"
	       "  --method M            three-pass (the paper's, default), "
	       "naive, varpro\n"
	       "  --no-coarse           fit on the full pixel set from the "
	       "start\n"
	       "  --faithful            the paper's evaluation: trace and "
	       "render the whole\n"
	       "                        image per evaluation (slow; the "
	       "benchmark baseline)\n"
	       "  --weights W.exr       per-pixel, per-channel weights "
	       "(1/variance; 0 = ignore)\n"
	       "  --weighting W         without --weights: poisson (default: "
	       "variance ~ signal\n"
	       "                        + 10%% of the mean) or uniform (plain "
	       "SSD, the paper)\n"
	       "  --mask-threshold T    specular mask: photo / white render "
	       "above (1+T) x its\n"
	       "                        median (default 0.1; "
	       "docs/fitting.md)\n"
	       "  --max-pixels N        fit on about N pixels (every s-th; "
	       "default 4096)\n"
	       "  --samples N           fixed env and lobe samples per hit "
	       "(default 8 each)\n"
	       "  --max-iter N          LM iterations per pass (default 60)\n"
	       "  --threads N           worker threads (default: all CPUs)\n"
	       "  --wait                SESSION: wait for a running fit of "
	       "it to end\n"
	       "  --json                print params.json on stdout; logs as "
	       "JSON lines\n"
	       "  -q, --quiet           no progress or info messages\n"
	       "\nExit status: 0 fitted, 1 bad input or failure (nothing "
	       "written), 2 bad command\nline.\n");
}

static json_t *param_json(const struct glint_fit_result *r)
{
	const struct glint_model_ops *m = r->model;
	json_t *list = json_array();

	for (int k = 0; k < m->nparams; k++) {
		const struct glint_param *pi = &m->params[k];
		json_array_append_new(
			list, json_pack("{s:s,s:f,s:o,s:b,s:[f,f]}", "name",
					pi->name, "value", r->p[k], "stderr",
					isfinite(r->se[k]) ? json_real(r->se[k])
							   : json_null(),
					"at_bound", r->at_bound[k], "bounds",
					pi->lo, pi->hi));
	}
	return list;
}

static json_t *passes_json(const struct glint_fit_result *r)
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

static void fit_progress(void *ctx, const char *pass, int iter, double cost)
{
	(void)ctx;
	if (glint_log_get_mode() == GLINT_LOG_HUMAN && isatty(2))
		fprintf(stderr, "\rfit: pass %-12s iteration %3d  cost %.6g   ",
			pass, iter, cost);
}

/*
 * --model auto: quick fits (about 1000 pixels) of an opaque and a
 * transparent sphere; the one whose render explains the photo better (the
 * lower relative RMSE) is chosen, and the numbers say why.
 */
static int pick_model(struct glint_renderer *r, const struct fit_job *job,
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
static int select_model(struct glint_renderer *r, const struct fit_job *job,
			const struct glint_fit_opts *o,
			const struct glint_model_ops **model,
			struct glint_fit_result *res, json_t **why)
{
	struct glint_selection *sel = calloc(1, sizeof(*sel));
	int ret = sel ? glint_select_model(r, job->photo, job->weight, o, sel)
		      : -ENOMEM;
	if (ret < 0) {
		free(sel);
		return glint_error_prefix(ret, "--select-model");
	}
	const struct glint_select_candidate *c = &sel->c[sel->chosen];
	switch (sel->chosen) {
	case GLINT_SEL_LAMBERT:
		ret = glint_fit(r, &glint_model_lambert, job->photo,
				job->weight, o, res);
		break;
	case GLINT_SEL_CONST_FRESNEL:
		*res = sel->nf;
		break;
	default:
		*res = sel->full;
		memcpy(res->p, c->p, sizeof(res->p));
		memcpy(res->se, c->se, sizeof(res->se));
	}
	*model = c->model;
	res->model = c->model;
	glint_log_info("--select-model: %s", sel->why);
	*why = glint_selection_to_json(sel);
	free(sel);
	return ret;
}

int fit_job_run(const struct fit_job *job, json_t **result)
{
	struct glint_renderer r;
	struct glint_fit_result res;
	struct glint_progress prog;
	struct glint_atomic_dir ad;
	struct glint_image *img = NULL, *cov = NULL;
	char path[4300];
	json_t *fidelity = NULL, *selection = NULL;
	int ret;

	*result = NULL;
	glint_progress_start(&prog, "trace", job->scene.cam.height);
	ret = glint_renderer_init(&r, &job->scene, job->nthreads, &prog);
	glint_progress_finish(&prog);
	if (ret < 0)
		return ret;
	struct glint_fit_opts o = job->opts;
	o.nthreads = job->nthreads;
	o.progress = fit_progress;
	const struct glint_model_ops *model = job->model;
	json_t *why = NULL;
	if (!model) {
		ret = pick_model(&r, job, &o, &model, &why);
		if (ret < 0)
			goto out;
	}
	if (job->select && !model->transparent) {
		ret = select_model(&r, job, &o, &model, &res, &selection);
		if (ret < 0)
			goto out;
	}
	if (selection)
		; /* fitted already */
	else if (job->ladder > 0 && !model->transparent) {
		struct glint_ladder_result *lr = calloc(1, sizeof(*lr));
		ret = lr ? glint_ladder_run(&job->scene, model, job->photo,
					    job->weight, &o, job->ladder,
					    job->ladder_knobs, job->nthreads,
					    lr)
			 : -ENOMEM;
		if (!ret) {
			res = lr->chosen_fit;
			fidelity = glint_ladder_to_json(lr);
			if (glint_log_get_mode() == GLINT_LOG_HUMAN)
				glint_ladder_print(lr, stderr);
		}
		free(lr);
	} else
		ret = glint_fit(&r, model, job->photo, job->weight, &o, &res);
	if (glint_log_get_mode() == GLINT_LOG_HUMAN && isatty(2))
		fprintf(stderr, "\r%*s\r", 70, "");
	if (ret < 0)
		goto out;
	/* A photo that does not show the sphere where the scene says fits
	 * badly whatever the parameters: say so rather than report them. */
	/* (A transparent sphere's sharp refracted detail aliases: its
	 * relative RMSE runs higher; docs/fitting.md.) */
	if (!(res.rel_rmse < (model->transparent ? 3.0 : 0.5))) {
		ret = glint_error_set(EINVAL,
				      "%s: the fit leaves a relative RMSE of "
				      "%.2f on the sphere: the photo does not "
				      "look like the scene's sphere (wrong "
				      "scene, position or image?)",
				      job->photo_path, res.rel_rmse);
		goto out;
	}
	/* The result rendered in full (MIS, the scene's sample counts). */
	img = glint_image_new(job->scene.cam.width, job->scene.cam.height);
	cov = glint_image_new(job->scene.cam.width, job->scene.cam.height);
	if (!img || !cov) {
		ret = -ENOMEM;
		goto out;
	}
	struct glint_shade_opts so = {
		.light_samples = job->scene.light_samples,
		.brdf_samples = job->scene.brdf_samples,
		.background = 1,
		.nthreads = job->nthreads,
	};
	ret = glint_renderer_shade(&r, model, res.p, &so, img, cov);
	if (ret < 0)
		goto out;
	json_t *doc = json_pack(
		"{s:s,s:s,s:o,s:o,s:{s:s,s:b,s:b,s:f,s:i,s:i},s:f,s:f,s:f,"
		"s:i,s:i,s:i,s:o,s:f,s:f,s:{s:s,s:s},s:s}",
		"model", model->name, "conventions", model->conventions,
		"material", glint_material_to_json(model, res.p), "parameters",
		param_json(&res), "method", "name",
		glint_fit_method_name(o.method), "coarse_to_fine",
		o.coarse_to_fine, "faithful", o.faithful, "mask_threshold",
		o.mask_threshold, "light_samples", o.light_samples,
		"lobe_samples", o.lobe_samples, "cost", res.cost, "rmse",
		res.rmse, "relative_rmse", res.rel_rmse, "pixels", res.pixels,
		"interior_pixels", res.interior, "specular_pixels",
		res.specular_pixels, "passes", passes_json(&res), "seconds",
		res.seconds, "setup_seconds", res.setup_seconds, "inputs",
		"scene", job->scene_path, "photo", job->photo_path, "weighting",
		job->weight			      ? "weight image"
		: o.weighting == GLINT_WEIGHT_POISSON ? "poisson"
						      : "uniform");
	json_object_set_new(doc, "optimizer",
			    json_string(o.optimizer == GLINT_OPT_LM ? "lm"
					: o.optimizer == GLINT_OPT_ANNEAL
						? "anneal"
						: "auto"));
	if (why) {
		json_object_set_new(doc, "model_choice", why);
		why = NULL;
	}
	if (fidelity) {
		json_object_set_new(doc, "fidelity", fidelity);
		fidelity = NULL;
	}
	if (selection) {
		json_object_set_new(doc, "model_selection", selection);
		selection = NULL;
	}
	ret = glint_atomic_dir_open(&ad, job->out_dir);
	if (ret < 0) {
		json_decref(doc);
		goto out;
	}
	char *text = json_dumps(doc, JSON_INDENT(2) | JSON_REAL_PRECISION(9));
	ret = glint_atomic_write_file(
		glint_atomic_dir_file(&ad, "params.json", path, sizeof(path)),
		text, strlen(text));
	free(text);
	if (!ret)
		ret = glint_image_write(glint_atomic_dir_file(&ad, "render.exr",
							      path,
							      sizeof(path)),
					img, NULL);
	if (!ret)
		ret = glint_compare_png(
			glint_atomic_dir_file(&ad, "compare.png", path,
					      sizeof(path)),
			job->photo, img, cov, NULL);
	if (!ret)
		ret = glint_atomic_dir_commit(&ad);
	else
		glint_atomic_dir_abort(&ad);
	if (ret < 0) {
		json_decref(doc);
		goto out;
	}
	json_object_set_new(doc, "output", json_string(job->out_dir));
	*result = doc;
out:
	json_decref(why);
	json_decref(fidelity);
	json_decref(selection);
	glint_image_free(img);
	glint_image_free(cov);
	glint_renderer_release(&r);
	return ret;
}

void cmd_print_params(const json_t *doc, const double *truth)
{
	json_t *ps = json_object_get(doc, "parameters"), *p;
	size_t i;

	int w = 11; /* the longest name */
	json_array_foreach(ps, i, p)
	{
		const char *nm = json_string_value(json_object_get(p, "name"));
		if (nm && (int)strlen(nm) > w)
			w = (int)strlen(nm);
	}
	printf("  %-*s %10s %10s%s\n", w, "parameter", "value", "std.err",
	       truth ? "       true      error" : "");
	json_array_foreach(ps, i, p)
	{
		json_t *se = json_object_get(p, "stderr");
		double v = json_real_value(json_object_get(p, "value"));
		printf("  %-*s %10.4f ", w,
		       json_string_value(json_object_get(p, "name")), v);
		if (json_is_real(se))
			printf("%10.4f", json_real_value(se));
		else
			printf("%10s", "n/a");
		if (json_is_true(json_object_get(p, "at_bound")))
			printf(" (at bound)");
		if (truth)
			printf(" %10.4f %+10.4f", truth[i], v - truth[i]);
		printf("\n");
	}
}

/* A sample's capture session, as glint fit SESSION uses it. */
struct fit_session {
	char scene[4200], photo[4200], weights[4200], out[4200];
};

static int fit_session_open(const char *dir, int wait, struct fit_session *fs,
			    int *lock)
{
	char path[4200];
	struct stat st;
	json_t *doc;
	int ret;

	if (stat(dir, &st) < 0 || !S_ISDIR(st.st_mode))
		return glint_error_set(ENOENT,
				       "%s: not a capture session folder "
				       "(give SCENE.json and PHOTO, or a "
				       "session)",
				       dir);
	snprintf(path, sizeof(path), "%s/session.json", dir);
	ret = glint_json_load(path, &doc);
	if (ret < 0)
		return ret;
	const char *status = json_string_value(json_object_get(doc, "status"));
	const char *kind = json_string_value(json_object_get(doc, "kind"));
	if (!status || strcmp(status, "complete") != 0 || !kind ||
	    strcmp(kind, "sample") != 0) {
		ret = glint_error_set(EINVAL,
				      "%s: a %s %s session: expected a "
				      "complete sample session",
				      dir, status ? status : "(no status)",
				      kind ? kind : "(no kind)");
		json_decref(doc);
		return ret;
	}
	json_decref(doc);
	snprintf(fs->scene, sizeof(fs->scene), "%s/scene.json", dir);
	snprintf(fs->photo, sizeof(fs->photo), "%s/sample.exr", dir);
	snprintf(fs->weights, sizeof(fs->weights), "%s/sample-weights.exr",
		 dir);
	snprintf(fs->out, sizeof(fs->out), "%s/fit", dir);
	if (stat(fs->scene, &st) < 0)
		return glint_error_set(ENOENT,
				       "%s: no scene.json (the sample was "
				       "captured without a probe or optics; "
				       "capture the probe, then the sample, "
				       "or write a scene, docs/scene.md)",
				       dir);
	if (stat(fs->weights, &st) < 0)
		fs->weights[0] = '\0';
	snprintf(path, sizeof(path), "%s/fit.lock", dir);
	if (wait) {
		ret = glint_lockfile_acquire(path, "glint fit", 0, lock);
		if (ret == -EBUSY) {
			glint_log_info("%s", glint_error_msg());
			glint_log_info("waiting for it to finish");
			ret = glint_lockfile_acquire(path, "glint fit", 1,
						     lock);
		}
	} else {
		ret = glint_lockfile_acquire(path, "glint fit", 0, lock);
		if (ret == -EBUSY)
			glint_error_prefix(ret,
					   "%s is being fitted (use --wait to "
					   "wait for it)",
					   dir);
	}
	if (ret < 0)
		return ret;
	/* We hold the lock: what a killed fit left is ours to clean. */
	if (glint_atomic_dir_sweep(fs->out) > 0)
		glint_log_info("%s: cleaned up after an interrupted fit",
			       fs->out);
	return 0;
}

int cmd_fit(int argc, char **argv)
{
	enum {
		O_MODEL = 256,
		O_METHOD,
		O_NOCOARSE,
		O_FAITHFUL,
		O_WEIGHTS,
		O_WEIGHTING,
		O_MASK,
		O_MAXPIX,
		O_SAMPLES,
		O_MAXITER,
		O_THREADS,
		O_JSON,
		O_WAIT,
		O_OPTIMIZER,
		O_SEED,
		O_ANNEAL_EVALS,
		O_LADDER,
		O_LADDER_LIMIT,
		O_SELECT,
		O_LADDER_KNOBS
	};
	static const struct option opts[] = {
		{ "out", required_argument, NULL, 'o' },
		{ "model", required_argument, NULL, O_MODEL },
		{ "method", required_argument, NULL, O_METHOD },
		{ "no-coarse", no_argument, NULL, O_NOCOARSE },
		{ "faithful", no_argument, NULL, O_FAITHFUL },
		{ "weights", required_argument, NULL, O_WEIGHTS },
		{ "weighting", required_argument, NULL, O_WEIGHTING },
		{ "mask-threshold", required_argument, NULL, O_MASK },
		{ "max-pixels", required_argument, NULL, O_MAXPIX },
		{ "samples", required_argument, NULL, O_SAMPLES },
		{ "max-iter", required_argument, NULL, O_MAXITER },
		{ "threads", required_argument, NULL, O_THREADS },
		{ "json", no_argument, NULL, O_JSON },
		{ "wait", no_argument, NULL, O_WAIT },
		{ "optimizer", required_argument, NULL, O_OPTIMIZER },
		{ "seed", required_argument, NULL, O_SEED },
		{ "anneal-evals", required_argument, NULL, O_ANNEAL_EVALS },
		{ "ladder", no_argument, NULL, O_LADDER },
		{ "select-model", no_argument, NULL, O_SELECT },
		{ "ladder-knobs", required_argument, NULL, O_LADDER_KNOBS },
		{ "ladder-limit", required_argument, NULL, O_LADDER_LIMIT },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	struct fit_job job = { .model = &glint_model_torrance_sparrow };
	const char *weights = NULL;
	int json = 0, wait = 0, c, n;

	glint_fit_default_opts(&job.opts);
	optind = 1;
	while ((c = getopt_long(argc, argv, "o:qh", opts, NULL)) != -1) {
		switch (c) {
		case 'o':
			job.out_dir = optarg;
			break;
		case O_OPTIMIZER:
			if (glint_fit_optimizer_parse(optarg,
						      &job.opts.optimizer) < 0)
				return cmd_usage_error("fit", "%s",
						       glint_error_msg());
			break;
		case O_ANNEAL_EVALS:
			if (cmd_parse_int("fit", "--anneal-evals", optarg, 10,
					  1000000, &job.opts.anneal_evals) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_LADDER_KNOBS:
			if (glint_ladder_knobs_parse(optarg,
						     &job.ladder_knobs) < 0)
				return cmd_usage_error("fit",
						       "--ladder-knobs %s",
						       glint_error_msg());
			if (!(job.ladder > 0))
				job.ladder = 0.5;
			break;
		case O_SELECT:
			job.select = 1;
			break;
		case O_LADDER:
			if (!(job.ladder > 0))
				job.ladder = 0.5;
			break;
		case O_LADDER_LIMIT: {
			char *end;
			job.ladder = strtod(optarg, &end);
			if (*end || !(job.ladder > 0 && job.ladder <= 10))
				return cmd_usage_error("fit",
						       "--ladder-limit '%s': "
						       "expected standard "
						       "errors in (0, 10]",
						       optarg);
			break;
		}
		case O_SEED:
			if (cmd_parse_int("fit", "--seed", optarg, 0,
					  2147483647, &n) < 0)
				return GLINT_EXIT_USAGE;
			job.opts.seed = (uint64_t)n;
			break;
		case O_MODEL:
			if (!strcmp(optarg, "auto")) {
				job.model = NULL;
				break;
			}
			job.model = glint_model_find(optarg);
			if (!job.model)
				return cmd_usage_error("fit",
						       "--model '%s': expected "
						       "one of %s, or auto",
						       optarg,
						       glint_model_names());
			break;
		case O_METHOD:
			if (glint_fit_method_parse(optarg, &job.opts.method) <
			    0)
				return cmd_usage_error("fit", "%s",
						       glint_error_msg());
			break;
		case O_NOCOARSE:
			job.opts.coarse_to_fine = 0;
			break;
		case O_FAITHFUL:
			job.opts.faithful = 1;
			break;
		case O_WEIGHTS:
			weights = optarg;
			break;
		case O_WEIGHTING:
			if (!strcmp(optarg, "poisson"))
				job.opts.weighting = GLINT_WEIGHT_POISSON;
			else if (!strcmp(optarg, "uniform"))
				job.opts.weighting = GLINT_WEIGHT_UNIFORM;
			else
				return cmd_usage_error("fit",
						       "--weighting '%s': "
						       "expected poisson or "
						       "uniform",
						       optarg);
			break;
		case O_MASK: {
			char *end;
			job.opts.mask_threshold = strtod(optarg, &end);
			if (*end || !(job.opts.mask_threshold >= 0))
				return cmd_usage_error("fit",
						       "--mask-threshold '%s': "
						       "expected a number >= 0",
						       optarg);
			break;
		}
		case O_MAXPIX:
			if (cmd_parse_int("fit", "--max-pixels", optarg, 64,
					  1 << 24, &job.opts.max_pixels) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_SAMPLES:
			if (cmd_parse_int("fit", "--samples", optarg, 1, 4096,
					  &n) < 0)
				return GLINT_EXIT_USAGE;
			job.opts.light_samples = job.opts.lobe_samples = n;
			break;
		case O_MAXITER:
			if (cmd_parse_int("fit", "--max-iter", optarg, 1, 10000,
					  &job.opts.max_iter) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_THREADS:
			if (cmd_parse_int("fit", "--threads", optarg, 0, 256,
					  &job.nthreads) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_JSON:
			json = 1;
			break;
		case O_WAIT:
			wait = 1;
			break;
		case 'q':
			glint_log_set_mode(GLINT_LOG_QUIET);
			break;
		case 'h':
			cmd_fit_help();
			return GLINT_EXIT_OK;
		default:
			return cmd_usage_error("fit", "unknown option");
		}
	}
	if (json)
		glint_log_set_mode(GLINT_LOG_JSON);
	struct fit_session fs;
	int lock = -1, ret;
	if (optind == argc - 1) {
		ret = fit_session_open(argv[optind], wait, &fs, &lock);
		if (ret < 0)
			return cmd_fail("fit");
		job.scene_path = fs.scene;
		job.photo_path = fs.photo;
		if (!weights && fs.weights[0])
			weights = fs.weights;
		if (!job.out_dir)
			job.out_dir = fs.out;
	} else if (optind == argc - 2) {
		job.scene_path = argv[optind];
		job.photo_path = argv[optind + 1];
	} else {
		return cmd_usage_error("fit",
				       "expected SCENE.json and PHOTO, or a "
				       "capture SESSION");
	}
	if (!job.out_dir)
		job.out_dir = "fit-out";
	json_t *doc = NULL;
	ret = glint_scene_load(job.scene_path, &job.scene);
	if (!ret)
		ret = glint_image_read(job.photo_path, &job.photo);
	if (!ret && weights)
		ret = glint_image_read(weights, &job.weight);
	if (!ret)
		ret = fit_job_run(&job, &doc);
	glint_image_free(job.photo);
	glint_image_free(job.weight);
	glint_lockfile_release(lock);
	if (ret < 0)
		return cmd_fail("fit");
	if (json) {
		cmd_print_json(doc);
		return GLINT_EXIT_OK;
	}
	const struct glint_model_ops *fm = glint_model_find(
		json_string_value(json_object_get(doc, "model")));
	printf("fit: %s, %s%s, %.2f s, relative RMSE %.4f on %d pixels\n",
	       fm->name,
	       !fm->transparent ? glint_fit_method_name(job.opts.method)
	       : job.opts.optimizer == GLINT_OPT_LM ? "LM"
						    : "annealing + LM polish",
	       !fm->transparent && job.opts.coarse_to_fine ? " coarse-to-fine"
							   : "",
	       json_real_value(json_object_get(doc, "seconds")),
	       json_real_value(json_object_get(doc, "relative_rmse")),
	       (int)json_integer_value(json_object_get(doc, "pixels")));
	cmd_print_params(doc, NULL);
	printf("results: %s/params.json, render.exr, compare.png\n",
	       job.out_dir);
	json_decref(doc);
	return GLINT_EXIT_OK;
}
