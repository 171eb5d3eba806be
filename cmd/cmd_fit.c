/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"
#include "appliance/session_fit.h"
#include "capture/hdr/session.h"
#include "fit/job.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/lockfile.h"
#include "core/log.h"
#include "fit/render/compare.h"
#include "fit/ladder.h"
#include "fit/select.h"
#include "fit/brdf/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void fit_help_intro(void)
{
	printf("usage: glint fit SCENE.json PHOTO.exr [SCENE2.json PHOTO2.exr "
	       "...] [options]\n"
	       "       glint fit SESSION [SESSION2 ...] [options]\n"
	       "       glint fit RUN [options]\n"
	       "\n"
	       "Recover a material's parameters from one HDR image of the "
	       "sphere (PHOTO, the\nscene camera's size, linear radiance) "
	       "seen under the scene's environment map.\nWrites "
	       "DIR/params.json (values, standard errors, conventions, cost, "
	       "RMSE,\niterations and time per pass), DIR/render.exr (the "
	       "fitted material rendered;\nwith --weights, with samples "
	       "enough to keep its own noise below a quarter of\nthe photo's "
	       "variance) and DIR/compare.png (photo | render | signed "
	       "error\nwith a scale bar).  When the sphere covers less than "
	       "three quarters of the\nframe, the fit, the render and "
	       "compare.png cover its window (the sphere\nand a margin); "
	       "render.exr keeps the frame as its display window.\n"
	       "Given a sample's capture session (glint capture sample), it "
	       "fits\n"
	       "SESSION/sample.exr with SESSION/scene.json and the merge's "
	       "weights "
	       "into\n"
	       "SESSION/fit; one fit per session at a time (a second one is "
	       "refused, or waits\n"
	       "with --wait and takes the result of the fit it waited for).\n"
	       "Given several SCENE PHOTO pairs (one sphere under different "
	       "lights, probes or\n"
	       "turntable positions, each photo with its own scene), it fits "
	       "one material to\n"
	       "all of them at once: what pins ior apart from specular where "
	       "one light cannot.\n"
	       "params.json's \"photos\" says how the result fits each; "
	       "render-N.exr "
	       "and\n"
	       "compare-N.png show it.  --weights is then given once per "
	       "photo, "
	       "in order; a\n"
	       "joint fit takes a named --model (or --select-model: every "
	       "candidate "
	       "fitted to\n"
	       "every photo), not auto or --ladder.\n"
	       "Several SESSIONs (the sample captured under each light, each "
	       "with its probe)\n"
	       "are fitted the same way, with their merges' weights, into -o "
	       "DIR.  A rig RUN\n"
	       "folder whose sequence captured the sample under each lamp (its "
	       "run.json names\n"
	       "them) is fitted that way into RUN/fit.\n"
	       "\n");
}

void cmd_fit_help(void)
{
	fit_help_intro();
	printf("  -o, --output DIR      result folder (default fit-out); "
	       "replaced whole,\n"
	       "                        never left half-written\n"
	       "  --model NAME          torrance-sparrow (default), lambert, "
	       "ggx (GGX lobe),\n"
	       "                        oren-nayar (rough diffuse), two-lobe "
	       "(a second,\n"
	       "                        broad lobe), "
	       "torrance-sparrow-constant-fresnel,\n"
	       "                        dielectric (a transparent sphere: "
	       "transmission RGB,\n"
	       "                        ior), or auto (tries opaque and "
	       "transparent, says\n"
	       "                        which and why); each model's "
	       "conventions go into\n"
	       "                        params.json\n"
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
	       "                        without Fresnel variation, lambert, "
	       "ggx, oren-nayar\n"
	       "                        and two-lobe; keep the one with the "
	       "lowest BIC on the\n"
	       "                        weighted residual (all with AIC, BIC "
	       "and standard\n"
	       "                        errors in params.json). The first "
	       "four alone are tried\n"
	       "                        when the fit leaves a parameter "
	       "undetermined, or\n"
	       "                        specular and ior trading off\n"
	       "  --no-select-model     never choose the model that way\n"
	       "  --no-per-light        with several photos, do not also fit "
	       "each alone (by\n"
	       "                        default each is, and params.json's "
	       "per_light says\n"
	       "                        whether a parameter drifts with the "
	       "light's angle)\n"
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
	       "(1/variance; 0 = ignore);\n"
	       "                        once per photo of a joint fit\n"
	       "  --weighting W         without --weights: poisson (default: "
	       "variance ~ signal\n"
	       "                        + 10%% of the mean) or uniform (plain "
	       "SSD, the paper)\n"
	       "  --mask-threshold T    specular mask: photo / white render "
	       "above (1+T) x its\n"
	       "                        median (default 0.1; "
	       "docs/fitting.md)\n"
	       "  --max-pixels N        fit on about N pixels of each photo "
	       "(every s-th;\n"
	       "                        default 4096)\n"
	       "  --samples N           fixed env and lobe samples per hit "
	       "(default 8 each,\n"
	       "                        32 a pixel over more than 4 hits: "
	       "2 at 16)\n"
	       "  --max-samples N       where its own sampling noise limits "
	       "the "
	       "answer, the fit\n"
	       "                        raises --samples up to N (default 64, "
	       "16 at 16 hits;\n"
	       "                        docs/fitting.md)\n"
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
	       "  --force               replace a previous result in OUT "
	       "(refused without it;\n"
	       "                        a session's own fit folder is "
	       "replaced by its next fit),\n"
	       "                        and write into OUT even when it "
	       "holds files glint did not\n"
	       "                        write: glint's own (its "
	       "glint-outputs.txt) are replaced,\n"
	       "                        the others kept; never an input of "
	       "this fit (without\n"
	       "                        --force such a folder is refused "
	       "before any work)\n"
	       "  --srgb                take an 8-bit photo (.png, .jpg, ...) "
	       "as sRGB-encoded and\n"
	       "                        linearise it (without it an 8-bit "
	       "photo is refused: it\n"
	       "                        holds camera-encoded values, not "
	       "radiance)\n"
	       "  --export F[,F...]     also write the material for a "
	       "renderer into OUT:\n"
	       "                        material.gltf (gltf), material.xml "
	       "(mitsuba),\n"
	       "                        material.pbrt (pbrt), material.py "
	       "(blender),\n"
	       "                        material.mtlx (materialx);\n"
	       "                        refitted as by glint export, "
	       "residuals in\n"
	       "                        params.json's \"exports\"\n"
	       "  --name N              the material's name in params.json "
	       "and the exports\n"
	       "                        (default: the session's, or OUT's "
	       "folder name)\n"
	       "  --max-iter N          LM iterations per pass (default 60)\n"
	       "  --threads N           worker threads (default: all CPUs)\n"
	       "  --render-seconds S    the final render's time budget "
	       "(default: half the\n"
	       "                        fit's time, at least 1 s); within "
	       "it, its samples\n"
	       "                        depend on the machine's speed; "
	       "1e9 makes them\n"
	       "                        depend on the photo alone\n"
	       "  --wait                SESSION: wait for a running fit of "
	       "it to end; its result,\n"
	       "                        when it leaves one, is the answer\n"
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

/* "  label: text", the text wrapped at 78 columns at spaces, each further
 * line indented under the text's start. */
static void print_wrapped(const char *label, const char *text)
{
	int indent = 2 + (int)strlen(label) + 2, col = indent - 1;
	if (!text)
		return;
	printf("  %s:", label);
	while (*text) {
		size_t n = strcspn(text, " ");
		if (col > indent && col + 1 + (int)n > 78) {
			printf("\n%*s", indent, "");
			col = indent;
		} else {
			putchar(' ');
			col++;
		}
		printf("%.*s", (int)n, text);
		col += (int)n;
		text += n;
		text += strspn(text, " ");
	}
	putchar('\n');
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
	int regions = (int)json_integer_value(
		json_object_get(unc, "model_error_regions"));
	printf("  intervals: %.0f %%: noise over %d blocks of pixels "
	       "(chi2/dof %.3g), %d sample sets,\n",
	       100 * level,
	       (int)json_integer_value(json_object_get(unc, "blocks")),
	       json_real_value(json_object_get(unc, "chi2_dof")),
	       (int)json_integer_value(json_object_get(unc, "sample_sets")));
	if (regions)
		printf("  the model error over %d regions of the sphere,\n",
		       regions);
	double share = json_real_value(json_object_get(unc, "misfit_share"));
	if (share > 0)
		printf("  a model discrepancy (the residual's structure: "
		       "%.1f %% of the signal),\n",
		       100 * share);
	json_t *ls = json_object_get(unc, "light_scale_sigma");
	double l[3];
	for (int c = 0; c < 3; c++)
		l[c] = json_real_value(json_array_get(ls, c));
	if (l[0] > 0 || l[1] > 0 || l[2] > 0)
		printf("  the light's scale (%.1f / %.1f / %.1f %% per "
		       "channel, as the scene states it),\n",
		       100 * l[0], 100 * l[1], 100 * l[2]);
	printf("  and the render's systematic accuracy (docs/fitting.md, "
	       "\"Uncertainty\")\n");
	json_array_foreach(json_object_get(unc, "findings"), i, p)
		print_wrapped("note", json_string_value(p));
}

void cmd_print_verdicts(const json_t *doc)
{
	const char *av = json_string_value(
		json_object_get(json_object_get(doc, "acceptance"), "verdict"));
	const char *mv = json_string_value(
		json_object_get(json_object_get(doc, "misfit"), "verdict"));

	if (av)
		print_wrapped("verdict", av);
	if (mv)
		print_wrapped("residual", mv);
}

static int parse_model(const char *arg, void *dest)
{
	const struct glint_model **m = dest;
	if (!strcmp(arg, "auto")) {
		*m = NULL;
		return 0;
	}
	*m = glint_model_find(arg);
	if (*m)
		return 0;
	const char *const *names = glint_model_list();
	const char *all[16] = { "auto" };
	for (int i = 0; names[i] && i < 14; i++)
		all[i + 1] = names[i];
	return cmd_choice_error(arg, all);
}

static int parse_exports(const char *arg, void *dest)
{
	return glint_export_formats_parse(arg, dest);
}

static int parse_knobs(const char *arg, void *dest)
{
	return glint_ladder_knobs_parse(arg, dest);
}

/* --weights, once per photo. */
struct weights_list {
	const char *path[GLINT_FIT_MAX_VIEWS];
	int n;
};

static int add_weights(const char *arg, void *dest)
{
	struct weights_list *w = dest;

	if (w->n == GLINT_FIT_MAX_VIEWS)
		return glint_error_set(EINVAL,
				       "given more than %d times (once per "
				       "photo, at most %d photos)",
				       GLINT_FIT_MAX_VIEWS,
				       GLINT_FIT_MAX_VIEWS);
	w->path[w->n++] = arg;
	return 0;
}

/* What to fit: scene, photo and weights of each photo, from SCENE PHOTO
 * pairs or capture sessions (their fit locks held). */
/* The joint fit's photos, one line each. */
static void print_photos(const json_t *doc)
{
	size_t k;
	json_t *e;

	json_array_foreach(json_object_get(doc, "photos"), k, e)
	{
		json_t *acc = json_object_get(e, "acceptance");
		printf("photo %zu: %s: relative RMSE %.4f on %d pixels "
		       "(%s, %s); %s\n",
		       k + 1, json_string_value(json_object_get(e, "photo")),
		       json_real_value(json_object_get(e, "relative_rmse")),
		       (int)json_integer_value(json_object_get(e, "pixels")),
		       json_string_value(json_object_get(e, "render")),
		       json_string_value(json_object_get(e, "compare")),
		       json_string_value(json_object_get(acc, "verdict")));
	}
}

int cmd_fit(int argc, char **argv)
{
	static const char *const weightings[] = { "poisson", "uniform", NULL };
	static struct glint_fit_request req;
	struct glint_fit_job *job = &req.job;
	struct weights_list wl = { .n = 0 };
	int samples = 0, sets = 0, seed = -1, ladder = 0;
	int method = -1, optimizer = -1, weighting = -1, nocoarse = 0;

	glint_fit_request_init(&req);
	const struct cmd_opt opts[] = {
		CMD_STRING("output", 'o', &job->out_dir),
		CMD_CALL("model", &job->model, parse_model),
		CMD_CHOICE("method", &method, glint_fit_method_names),
		CMD_CHOICE("optimizer", &optimizer, glint_fit_optimizer_names),
		CMD_FLAG("no-coarse", 0, &nocoarse),
		CMD_FLAG("faithful", 0, &job->opts.faithful),
		CMD_CALL("weights", &wl, add_weights),
		CMD_CHOICE("weighting", &weighting, weightings),
		CMD_REAL("mask-threshold", &job->opts.mask_threshold, 0, 1e6),
		CMD_INT("max-pixels", &job->opts.max_pixels, 64, 1 << 24),
		CMD_INT("samples", &samples, 1, 4096),
		CMD_INT("max-samples", &job->opts.max_samples, 1, 4096),
		CMD_INT("sample-sets", &sets, 1, 16),
		CMD_REAL("level", &job->opts.level, 0.51, 0.999),
		CMD_REAL("accept-rmse", &job->accept_rmse, 1e-9, 1e9),
		CMD_FLAG("force", 0, &job->force),
		CMD_STRING("name", 0, &job->name),
		CMD_FLAG("srgb", 0, &job->srgb),
		CMD_CALL("export", &job->exports, parse_exports),
		CMD_INT("max-iter", &job->opts.max_iter, 1, 10000),
		CMD_INT("threads", &job->nthreads, 0, 256),
		CMD_REAL("render-seconds", &job->render_budget_s, 0.01, 1e9),
		CMD_FLAG("wait", 0, &req.wait),
		CMD_INT("seed", &seed, 0, 2147483647),
		CMD_INT("anneal-evals", &job->opts.anneal_evals, 10, 1000000),
		CMD_FLAG("ladder", 0, &ladder),
		CMD_REAL("ladder-limit", &job->ladder, 1e-6, 10),
		CMD_CALL("ladder-knobs", &job->ladder_knobs, parse_knobs),
		CMD_FLAG("select-model", 0, &job->select),
		CMD_FLAG("no-select-model", 0, &job->no_auto_select),
		CMD_FLAG("no-per-light", 0, &job->no_per_light),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("fit", cmd_fit_help, opts, argc, argv, &a);
	if (r)
		return cmd_options_exit(r);
	if (method >= 0)
		job->opts.method = (enum glint_fit_method)method;
	if (optimizer >= 0)
		job->opts.optimizer = (enum glint_fit_optimizer)optimizer;
	if (weighting >= 0)
		job->opts.weighting =
			weighting ? GLINT_WEIGHT_UNIFORM : GLINT_WEIGHT_POISSON;
	if (nocoarse)
		job->opts.coarse_to_fine = 0;
	if (samples)
		job->opts.light_samples = job->opts.lobe_samples = samples;
	if (sets)
		job->opts.mc_draws = sets - 1;
	if (seed >= 0)
		job->opts.seed = (uint64_t)seed;
	if ((ladder || job->ladder_knobs) && !(job->ladder > 0))
		job->ladder = 0.5;
	job->opts.progress = cmd_fit_progress;
	job->replace = job->force;
	req.args = a.argv;
	req.nargs = a.argc;
	for (int k = 0; k < wl.n; k++)
		req.weights[k] = wl.path[k];
	req.nweights = wl.n;

	struct glint_fit_outcome o;
	if (glint_session_fit(&req, &o) < 0)
		return o.usage ? cmd_usage_error("fit", "%s", glint_error_msg())
			       : cmd_fail("fit");
	json_t *doc = o.doc;
	if (a.json) {
		cmd_print_json(doc);
		return GLINT_EXIT_OK;
	}
	printf("fit: %s, %s%s, %.2f s, relative RMSE %.4f on %d pixels\n",
	       o.model,
	       !o.transparent ? glint_fit_method_name(job->opts.method)
	       : job->opts.optimizer == GLINT_OPT_LM ? "LM"
						     : "annealing + LM polish",
	       !o.transparent && job->opts.coarse_to_fine ? " coarse-to-fine"
							  : "",
	       o.seconds, o.relative_rmse, o.pixels);
	cmd_print_params(doc, NULL);
	cmd_print_verdicts(doc);
	print_photos(doc);
	printf("results: %s/report.html (open it in a browser), params.json, "
	       "render%s.exr, compare%s.png\n",
	       o.out_dir, o.nphotos > 1 ? "[-N]" : "",
	       o.nphotos > 1 ? "[-N]" : "");
	size_t k;
	json_t *e;
	json_array_foreach(json_object_get(doc, "exports"), k, e)
	{
		const char *file =
			json_string_value(json_object_get(e, "file"));
		if (file)
			printf("export: %s/%s (%s), refit relative RMS "
			       "%.4f\n",
			       o.out_dir, file,
			       json_string_value(json_object_get(e, "format")),
			       json_real_value(json_object_get(
				       e, "refit_relative_rms")));
		else
			printf("export: no %s: %s\n",
			       json_string_value(json_object_get(e, "format")),
			       json_string_value(json_object_get(e, "error")));
	}
	json_decref(doc);
	return GLINT_EXIT_OK;
}
