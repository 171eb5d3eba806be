/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "capture/session.h"
#include "fit/job.h"

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
	       "in params.json);\n"
	       "                        also done when the fit leaves a "
	       "parameter\n"
	       "                        undetermined, or specular and ior "
	       "trading off\n"
	       "  --no-select-model     never choose the model that way\n"
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
	       "  --sample-sets K       final polish and Monte Carlo error on "
	       "the mean of K\n"
	       "                        independent sample sets (default 3; "
	       "1: neither,\n"
	       "                        faster; docs/fitting.md, "
	       "\"Uncertainty\")\n"
	       "  --level P             of the reported intervals (default "
	       "0.95)\n"
	       "  --accept-rmse X       take the fit when its relative RMSE "
	       "is below X, instead\n"
	       "                        of the rule (better than the bare "
	       "backdrop and than\n"
	       "                        a flat disc of the photo's mean "
	       "colour); a refused\n"
	       "                        fit's diagnostics go to OUT.refused\n"
	       "  --force               replace OUT even when it holds files "
	       "glint did not write\n"
	       "                        (without it such a folder is refused "
	       "before any work)\n"
	       "  --max-iter N          LM iterations per pass (default 60)\n"
	       "  --threads N           worker threads (default: all CPUs)\n"
	       "  --wait                SESSION: wait for a running fit of "
	       "it to end\n"
	       "  --json                print params.json on stdout; logs as "
	       "JSON lines\n"
	       "  -q, --quiet           no progress or info messages\n"
	       "\nExit status: 0 fitted, 1 bad input, failure (nothing "
	       "written) or a refused\nfit (its diagnostics in OUT.refused, "
	       "OUT untouched), 2 bad command line.\n");
}

void cmd_fit_progress(void *ctx, const char *pass, int iter, double cost)
{
	(void)ctx;
	if (glint_log_get_mode() != GLINT_LOG_HUMAN || !isatty(2))
		return;
	if (pass)
		fprintf(stderr, "\rfit: pass %-12s iteration %3d  cost %.6g   ",
			pass, iter, cost);
	else
		fprintf(stderr, "\r%*s\r", 70, "");
}

void cmd_print_params(const json_t *doc, const double *truth)
{
	json_t *ps = json_object_get(doc, "parameters"), *p;
	json_t *unc = json_object_get(doc, "uncertainty");
	size_t i;
	double level = json_real_value(json_object_get(unc, "level"));

	int w = 11; /* the longest name */
	json_array_foreach(ps, i, p)
	{
		const char *nm = json_string_value(json_object_get(p, "name"));
		if (nm && (int)strlen(nm) > w)
			w = (int)strlen(nm);
	}
	printf("  %-*s %10s %10s %21s%s\n", w, "parameter", "value", "std.err",
	       json_is_object(unc) ? "interval" : "",
	       truth ? "       true      error" : "");
	json_array_foreach(ps, i, p)
	{
		json_t *se = json_object_get(p, "stderr");
		json_t *iv = json_object_get(p, "interval");
		double v = json_real_value(json_object_get(p, "value"));
		printf("  %-*s %10.4f ", w,
		       json_string_value(json_object_get(p, "name")), v);
		if (json_is_real(se))
			printf("%10.4f", json_real_value(se));
		else
			printf("%10s", "n/a");
		if (json_is_array(iv))
			printf("  [%8.4f, %8.4f]",
			       json_real_value(json_array_get(iv, 0)),
			       json_real_value(json_array_get(iv, 1)));
		if (json_is_false(json_object_get(p, "determined")))
			printf(" not determined");
		else if (json_is_true(json_object_get(p, "at_bound")))
			printf(" (at bound)");
		if (truth)
			printf(" %10.4f %+10.4f", truth[i], v - truth[i]);
		printf("\n");
	}
	if (!json_is_object(unc))
		return;
	printf("  intervals: %.0f %%: noise over %d blocks of pixels "
	       "(chi2/dof %.3g), %d sample sets,\n  and the render's "
	       "systematic accuracy (docs/fitting.md, \"Uncertainty\")\n",
	       100 * level,
	       (int)json_integer_value(json_object_get(unc, "blocks")),
	       json_real_value(json_object_get(unc, "chi2_dof")),
	       (int)json_integer_value(json_object_get(unc, "sample_sets")));
	json_array_foreach(json_object_get(unc, "findings"), i, p)
		printf("  note: %s\n", json_string_value(p));
}

/* A sample's capture session, as glint fit SESSION uses it. */
static int fit_session_open(const char *dir, int wait,
			    struct glint_session_fit *fs, int *lock)
{
	char path[GLINT_PATH_MAX];
	int ret = glint_session_fit_inputs(dir, fs);

	if (ret < 0)
		return ret;
	ret = glint_path_join(path, sizeof(path), dir, GLINT_SESSION_FIT_LOCK);
	if (ret < 0)
		return ret;
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
		O_LADDER_KNOBS,
		O_SETS,
		O_LEVEL,
		O_NOSELECT,
		O_ACCEPT,
		O_FORCE
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
		{ "sample-sets", required_argument, NULL, O_SETS },
		{ "level", required_argument, NULL, O_LEVEL },
		{ "accept-rmse", required_argument, NULL, O_ACCEPT },
		{ "force", no_argument, NULL, O_FORCE },
		{ "max-iter", required_argument, NULL, O_MAXITER },
		{ "threads", required_argument, NULL, O_THREADS },
		{ "json", no_argument, NULL, O_JSON },
		{ "wait", no_argument, NULL, O_WAIT },
		{ "optimizer", required_argument, NULL, O_OPTIMIZER },
		{ "seed", required_argument, NULL, O_SEED },
		{ "anneal-evals", required_argument, NULL, O_ANNEAL_EVALS },
		{ "ladder", no_argument, NULL, O_LADDER },
		{ "select-model", no_argument, NULL, O_SELECT },
		{ "no-select-model", no_argument, NULL, O_NOSELECT },
		{ "ladder-knobs", required_argument, NULL, O_LADDER_KNOBS },
		{ "ladder-limit", required_argument, NULL, O_LADDER_LIMIT },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	struct glint_fit_job job = { .model = &glint_model_torrance_sparrow };
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
		case O_NOSELECT:
			job.no_auto_select = 1;
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
		case O_SETS:
			if (cmd_parse_int("fit", "--sample-sets", optarg, 1, 16,
					  &n) < 0)
				return GLINT_EXIT_USAGE;
			job.opts.mc_draws = n - 1;
			break;
		case O_LEVEL: {
			char *end;
			job.opts.level = strtod(optarg, &end);
			if (*end || !(job.opts.level > 0.5) ||
			    !(job.opts.level < 1))
				return cmd_usage_error("fit",
						       "--level '%s': expected "
						       "a probability in "
						       "(0.5, 1), e.g. 0.95",
						       optarg);
			break;
		}
		case O_FORCE:
			job.force = 1;
			break;
		case O_ACCEPT: {
			char *end;
			job.accept_rmse = strtod(optarg, &end);
			if (*end || !(job.accept_rmse > 0) ||
			    !isfinite(job.accept_rmse))
				return cmd_usage_error("fit",
						       "--accept-rmse '%s': "
						       "expected a relative "
						       "RMSE > 0, e.g. 0.5",
						       optarg);
			break;
		}
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
	struct glint_session_fit fs;
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
	job.opts.progress = cmd_fit_progress;
	if (!ret)
		ret = glint_fit_job_run(&job, &doc);
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
	printf("  verdict: %s\n",
	       json_string_value(json_object_get(
		       json_object_get(doc, "acceptance"), "verdict")));
	printf("results: %s/params.json, render.exr, compare.png\n",
	       job.out_dir);
	json_decref(doc);
	return GLINT_EXIT_OK;
}
