/* SPDX-License-Identifier: MIT */
/*
 * glint capture probe|sample: a verified exposure bracket of the region of
 * interest into a capture session (capture/session.h); glint cameras: the
 * cameras each backend can open and what they can do.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "capture_scene.h"

#include "capture/hdr_linear.h"
#include "capture/probe.h"
#include "capture/sphere_detect.h"
#include "capture/session.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"

#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cmd_capture_help(void)
{
	printf("usage: glint capture (probe | sample) [options]\n"
	       "\n"
	       "Capture an exposure bracket of the light probe or the sample "
	       "that covers the\nregion of interest's dynamic range: from a "
	       "metered start, shorter exposures\nuntil nothing in the ROI "
	       "saturates, longer ones (then gain) until its darkest\npixels "
	       "clear the noise floor.  Each frame is on disk before the next "
	       "is taken;\nan interrupted or failed capture leaves its session "
	       "marked incomplete with\nevery frame it got.  A complete raw "
	       "bracket is merged into KIND.exr,\nKIND-variance.exr, "
	       "KIND-weights.exr and KIND-mask.png in the session\n(see "
	       "glint hdr).  A probe is also unwrapped to env.exr, and a "
	       "sample "
	       "gets a\nscene.json for glint fit SESSION (the sphere found in "
	       "sample.exr, lit by\nthe probe's env.exr), when the rig gives "
	       "optics.focal_px.\n"
	       "\n"
	       "  --config FILE       rig configuration (default: the "
	       "simulated rig,\n"
	       "                      data/rig-sim.json; see "
	       "docs/capture.md)\n"
	       "  --out DIR           sessions go under DIR (default: the "
	       "config's \"output\")\n"
	       "  --probe SESSION     the probe session that lights a sample "
	       "(default: the\n"
	       "                      newest complete one under DIR)\n"
	       "      --verbose       show camera libraries' own logging\n"
	       "      --json          print a JSON result on stdout, logs as "
	       "JSON lines\n"
	       "  -q, --quiet         no progress or info messages\n"
	       "\nExit status: 0 done, 1 failure (the session says why), "
	       "2 bad command line,\n130 interrupted.\n");
}

void cmd_cameras_help(void)
{
	printf("usage: glint cameras [--backend NAME] [--device DEV] "
	       "[--json]\n"
	       "\n"
	       "List the cameras glint can open and their capabilities "
	       "(formats, bit depth,\nexposure and gain ranges, the controls "
	       "used).  Without --device: the simulated\ncamera, every "
	       "/dev/video* capture device and every libcamera camera.\n"
	       "\n"
	       "  --backend NAME      sim, v4l2 or libcamera (as built)\n"
	       "  --device DEV        describe this device only (e.g. "
	       "/dev/video0)\n"
	       "      --verbose       show camera libraries' own logging\n"
	       "      --json          print JSON on stdout\n");
}

struct rig {
	json_t *doc;
	char *text;
	const char *backend, *device, *output;
	struct glint_bracket_opts bracket;
	struct glint_roi roi;
	double focal_px, principal[2]; /* optics; 0 = not given */
	double pitch_um;	       /* optics.pixel_pitch_um */
	double diameter_m;	       /* sample.diameter_m */
};

static int load_rig(const char *path, const char *kind, struct rig *r)
{
	static const char *const top[] = { "camera", "bracket", "roi",
					   "output", "sensor",	"optics",
					   "sample", NULL };
	static const char *const cam_keys[] = { "backend", "device", NULL };
	static const char *const br_keys[] = { "step_ev",    "max_frames",
					       "max_time_s", "floor_dn",
					       "start_s",    "max_drop",
					       NULL };
	static const char *const roi_keys[] = { "probe", "sample", NULL };
	json_t *cam, *br = NULL, *roi = NULL;
	int ret;

	memset(r, 0, sizeof(*r));
	glint_bracket_default_opts(&r->bracket);
	r->output = "captures";
	ret = glint_json_load(path, &r->doc);
	if (ret < 0)
		return ret;
	ret = glint_json_known_keys(path, "", r->doc, top);
	if (!ret)
		ret = glint_json_object(path, "", r->doc, "camera", 1, &cam);
	if (!ret)
		ret = glint_json_known_keys(path, "camera", cam, cam_keys);
	if (!ret)
		ret = glint_json_string(path, "camera", cam, "backend", 1,
					&r->backend);
	if (!ret)
		ret = glint_json_string(path, "camera", cam, "device", 0,
					&r->device);
	if (!ret)
		ret = glint_json_string(path, "", r->doc, "output", 0,
					&r->output);
	if (!ret)
		ret = glint_json_object(path, "", r->doc, "bracket", 0, &br);
	if (!ret && br) {
		struct glint_bracket_opts *o = &r->bracket;
		ret = glint_json_known_keys(path, "bracket", br, br_keys);
		if (!ret)
			ret = glint_json_number(
				path, "bracket", br, "step_ev", 0,
				(struct glint_range){ 0.25, 4, 0, 0 },
				&o->step_ev);
		if (!ret)
			ret = glint_json_int(path, "bracket", br, "max_frames",
					     0, 1, GLINT_BRACKET_MAX,
					     &o->max_frames);
		if (!ret)
			ret = glint_json_number(
				path, "bracket", br, "max_time_s", 0,
				(struct glint_range){ 0, 3600, 0, 1 },
				&o->max_time_s);
		if (!ret)
			ret = glint_json_number(
				path, "bracket", br, "floor_dn", 0,
				(struct glint_range){ 0, 1e4, 0, 0 },
				&o->floor_dn);
		if (!ret)
			ret = glint_json_number(
				path, "bracket", br, "start_s", 0,
				(struct glint_range){ 0, 60, 0, 0 },
				&o->start_s);
		if (!ret)
			ret = glint_json_int(path, "bracket", br, "max_drop", 0,
					     0, 64, &o->max_drop);
	}
	if (!ret) {
		static const char *const opt_keys[] = { "focal_px", "principal",
							"pixel_pitch_um",
							NULL };
		static const char *const sample_keys[] = { "diameter_m", NULL };
		json_t *opt = NULL, *smp = NULL;
		r->principal[0] = r->principal[1] = -1;
		r->pitch_um = 1;
		r->diameter_m = 0.1;
		ret = glint_json_object(path, "", r->doc, "sample", 0, &smp);
		if (!ret && smp)
			ret = glint_json_known_keys(path, "sample", smp,
						    sample_keys);
		if (!ret && smp)
			ret = glint_json_number(
				path, "sample", smp, "diameter_m", 0,
				(struct glint_range){ 0, 10, 1, 0 },
				&r->diameter_m);
		if (!ret)
			ret = glint_json_object(path, "", r->doc, "optics", 0,
						&opt);
		if (!ret && opt)
			ret = glint_json_known_keys(path, "optics", opt,
						    opt_keys);
		if (!ret && opt)
			ret = glint_json_number(
				path, "optics", opt, "focal_px", 1,
				(struct glint_range){ 1, 1e6, 0, 0 },
				&r->focal_px);
		if (!ret && opt)
			ret = glint_json_numbers(
				path, "optics", opt, "principal", 0, 2,
				(struct glint_range){ 0, 1e5, 0, 0 },
				r->principal);
		if (!ret && opt)
			ret = glint_json_number(
				path, "optics", opt, "pixel_pitch_um", 0,
				(struct glint_range){ 0, 1000, 1, 0 },
				&r->pitch_um);
	}
	if (!ret)
		ret = glint_json_object(path, "", r->doc, "roi", 0, &roi);
	if (!ret && roi)
		ret = glint_json_known_keys(path, "roi", roi, roi_keys);
	if (!ret && roi) {
		double v[4] = { 0, 0, 0, 0 };
		ret = glint_json_numbers(path, "roi", roi, kind, 0, 4,
					 (struct glint_range){ 0, 65536, 0, 0 },
					 v);
		r->roi = (struct glint_roi){ (int)v[0], (int)v[1], (int)v[2],
					     (int)v[3] };
	}
	if (!ret)
		r->text = json_dumps(r->doc, JSON_INDENT(2));
	if (ret < 0)
		json_decref(r->doc);
	return ret;
}

/* The merged probe -> env.exr (+ env-mask.png, env-density.exr): the ball
 * found in it, unwrapped with the rig's focal length. */
static int unwrap_probe(const char *dir, const struct rig *rig,
			const struct glint_image *probe)
{
	char path[4200];
	struct glint_image *env = NULL, *mask = NULL, *dens = NULL;
	struct glint_circle c;
	struct glint_unwrap_opts o;
	int ret = glint_sphere_detect(probe, 0, 0, &c);
	if (ret == 0) {
		glint_unwrap_default_opts(&o);
		o.fpx = rig->focal_px;
		o.cx = rig->principal[0];
		o.cy = rig->principal[1];
		o.ball_cx = c.cx;
		o.ball_cy = c.cy;
		o.ball_r = c.r;
		glint_log_info("probe ball at (%.2f, %.2f), radius %.2f px "
			       "(%d edge points, %.2f px rms)",
			       c.cx, c.cy, c.r, c.points, c.rms_px);
		ret = glint_probe_unwrap(probe, &o, &env, &mask, &dens);
	}
	const char *names[3] = { "env.exr", "env-mask.png", "env-density.exr" };
	struct glint_image *imgs[3] = { env, mask, dens };
	for (int i = 0; i < 3 && ret == 0; i++) {
		struct glint_write_opts wo = { 0, 0, 0 };
		snprintf(path, sizeof(path), "%s/%s", dir, names[i]);
		ret = glint_image_write(path, imgs[i], &wo);
	}
	if (ret < 0)
		glint_error_prefix(ret,
				   "unwrapping the probe (frames and "
				   "probe.exr kept in %s)",
				   dir);
	glint_image_free(env);
	glint_image_free(mask);
	glint_image_free(dens);
	return ret;
}

/* A merged sample -> scene.json lit by the probe session's env.exr.  A
 * missing probe is not the sample's fault: its capture stays complete and
 * the warning says what to do; a given --probe that is wrong is an error. */
static int sample_scene(const char *dir, const char *root, const char *probe,
			const struct rig *rig, const struct glint_image *rad,
			char *scene_path, size_t n)
{
	char found[4200];
	struct capture_optics o = { rig->focal_px,
				    { rig->principal[0], rig->principal[1] },
				    rig->pitch_um,
				    rig->diameter_m };
	int ret = 0;

	if (!probe) {
		ret = capture_latest_probe(root, found, sizeof(found));
		probe = found;
	}
	if (ret == 0)
		ret = capture_write_scene(dir, rad, &o, probe, NULL);
	if (ret == 0) {
		snprintf(scene_path, n, "%s/scene.json", dir);
		return 0;
	}
	if (probe != found)
		return ret;
	glint_log_warn("no scene.json for the sample: %s (session "
		       "%s is complete; glint fit needs a scene)",
		       glint_error_msg(), dir);
	return 0;
}

static volatile sig_atomic_t interrupted;
static volatile int cancel_flag;

static void on_sigint(int sig)
{
	(void)sig;
	interrupted = 1;
	cancel_flag = 1;
}

struct frame_ctx {
	struct glint_session *session;
	struct glint_progress progress;
};

static int save_frame(const struct glint_frame *f, int index, void *ctx)
{
	struct frame_ctx *c = ctx;
	int ret = glint_session_add_frame(c->session, f, index);
	glint_progress_add(&c->progress, 1);
	return ret;
}

int cmd_capture(int argc, char **argv)
{
	enum { O_CONFIG = 256, O_OUT, O_JSON, O_VERBOSE, O_PROBE };
	static const struct option opts[] = {
		{ "config", required_argument, NULL, O_CONFIG },
		{ "probe", required_argument, NULL, O_PROBE },
		{ "out", required_argument, NULL, O_OUT },
		{ "json", no_argument, NULL, O_JSON },
		{ "verbose", no_argument, NULL, O_VERBOSE },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *config = NULL, *out = NULL, *probe = NULL;
	char default_config[4096], scene_path[4200] = "";
	int json = 0, c, ret;

	optind = 1;
	while ((c = getopt_long(argc, argv, "qh", opts, NULL)) != -1) {
		switch (c) {
		case O_CONFIG:
			config = optarg;
			break;
		case O_OUT:
			out = optarg;
			break;
		case O_PROBE:
			probe = optarg;
			break;
		case O_JSON:
			json = 1;
			glint_log_set_mode(GLINT_LOG_JSON);
			break;
		case O_VERBOSE:
			glint_camera_set_verbose(1);
			break;
		case 'q':
			glint_log_set_mode(GLINT_LOG_QUIET);
			break;
		case 'h':
			cmd_capture_help();
			return GLINT_EXIT_OK;
		default:
			return GLINT_EXIT_USAGE;
		}
	}
	if (optind != argc - 1 || (strcmp(argv[optind], "probe") != 0 &&
				   strcmp(argv[optind], "sample") != 0))
		return cmd_usage_error("capture",
				       "expected what to capture: probe or "
				       "sample");
	const char *kind = argv[optind];
	if (!config) {
		snprintf(default_config, sizeof(default_config),
			 "%s/rig-sim.json", glint_data_dir());
		config = default_config;
	}

	struct rig rig;
	ret = load_rig(config, kind, &rig);
	if (ret < 0)
		return cmd_fail("capture");
	if (!out)
		out = rig.output;

	struct glint_camera *cam = NULL;
	struct glint_camera_info info;
	struct glint_session *session = NULL;
	char session_dir[4096] = "";
	struct glint_bracket b;
	struct frame_ctx fc;
	struct sigaction sa, old_int, old_term;

	ret = glint_camera_open(rig.backend, rig.device, NULL, &cam);
	if (ret < 0)
		goto done;
	glint_camera_describe(cam, &info);
	ret = glint_session_create(out, kind, rig.text, &info, &session);
	if (ret < 0)
		goto done;
	snprintf(session_dir, sizeof(session_dir), "%s",
		 glint_session_dir(session));
	glint_log_info("capturing the %s with %s (%s) into %s", kind, info.name,
		       info.backend, glint_session_dir(session));
	memset(&fc, 0, sizeof(fc));
	fc.session = session;
	rig.bracket.on_frame = save_frame;
	rig.bracket.ctx = &fc;
	rig.bracket.cancel = &cancel_flag;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_sigint;
	sigaction(SIGINT, &sa, &old_int);
	sigaction(SIGTERM, &sa, &old_term);
	glint_progress_start(&fc.progress, "frames", rig.bracket.max_frames);
	ret = glint_bracket_capture(cam, &rig.roi, &rig.bracket,
				    &glint_clock_real, &b);
	glint_progress_finish(&fc.progress);
	sigaction(SIGINT, &old_int, NULL);
	sigaction(SIGTERM, &old_term, NULL);
	{
		/* The session records the outcome either way. */
		char err[512], dir[4096];
		snprintf(err, sizeof(err), "%s", glint_error_msg());
		snprintf(dir, sizeof(dir), "%s", glint_session_dir(session));
		int r2 =
			glint_session_finish(session, &b, ret < 0 ? err : NULL);
		if (ret < 0)
			glint_error_set(-ret,
					"%s (session %s kept, incomplete)", err,
					dir);
		session = NULL;
		if (ret == 0 && r2 < 0)
			ret = r2;
	}
	/* The merged HDR image of a raw bracket, beside its frames:
	 * KIND.exr, KIND-variance.exr, KIND-weights.exr, KIND-mask.png. */
	long valid_px = 0;
	if (ret == 0 && b.n > 0 && b.frames[0].linear &&
	    b.frames[0].channels == 1) {
		char names[5][64];
		const char *np[5];
		static const char *const suffix[5] = { ".exr", "-variance.exr",
						       "-weights.exr",
						       "-mask.png", ".png" };
		for (int i = 0; i < 5; i++) {
			snprintf(names[i], sizeof(names[i]), "%s%s", kind,
				 suffix[i]);
			np[i] = names[i];
		}
		struct glint_noise_model nm;
		struct glint_hdr_report rep;
		struct glint_image *rad = NULL;
		int w, h;
		glint_noise_default(&nm);
		ret = cmd_session_noise(session_dir, &nm);
		if (ret == 0)
			ret = cmd_hdr_merge_write(b.frames, b.n, &nm,
						  session_dir, np, &rep, &w, &h,
						  &valid_px, &rad);
		if (ret == 0 && rep.moved)
			glint_log_warn("the bracket's frames disagree "
				       "(moved rig or scene?); run glint hdr "
				       "on the session for details");
		if (ret < 0)
			glint_error_prefix(ret,
					   "merging the bracket (frames "
					   "kept in %s)",
					   session_dir);
		if (ret == 0 && !strcmp(kind, "probe") && rig.focal_px > 0)
			ret = unwrap_probe(session_dir, &rig, rad);
		if (ret == 0 && !strcmp(kind, "sample") && rig.focal_px > 0)
			ret = sample_scene(session_dir, out, probe, &rig, rad,
					   scene_path, sizeof(scene_path));
		glint_image_free(rad);
	}
	if (ret == 0) {
		if (json) {
			cmd_print_json(json_pack(
				"{s:s, s:s, s:s, s:s*, s:i, s:f, s:f, s:f, "
				"s:b, "
				"s:b, s:b, s:b, s:f}",
				"status", "complete", "kind", kind, "session",
				session_dir, "scene",
				scene_path[0] ? scene_path : NULL, "frames",
				b.n, "shortest_s", b.frames[0].exposure_s,
				"longest_s", b.frames[b.n - 1].exposure_s,
				"max_gain", b.frames[b.n - 1].gain,
				"covered_low", b.covered_low, "covered_high",
				b.covered_high, "used_gain", b.used_gain,
				"truncated", b.truncated, "seconds",
				b.seconds));
		} else {
			glint_log_info("%d frames, %.4g s .. %.4g s (gain up "
				       "to %.3g) in %.1f s%s%s",
				       b.n, b.frames[0].exposure_s,
				       b.frames[b.n - 1].exposure_s,
				       b.frames[b.n - 1].gain, b.seconds,
				       b.covered_low && b.covered_high
					       ? ", range covered"
					       : "",
				       b.truncated ? " (stopped by a cap)"
						   : "");
		}
		glint_bracket_release(&b);
	}
done:
	glint_camera_close(cam);
	free(rig.text);
	json_decref(rig.doc);
	if (ret < 0) {
		cmd_fail("capture");
		return interrupted ? 130 : GLINT_EXIT_FAIL;
	}
	return GLINT_EXIT_OK;
}

struct listing {
	json_t *arr;
	const char *backend;
	int json;
};

static void describe_one(const char *backend, const char *device,
			 struct listing *l)
{
	struct glint_camera *cam;
	struct glint_camera_info in;
	int ret = glint_camera_open(backend, device, NULL, &cam);
	if (ret < 0) {
		if (l->json)
			json_array_append_new(
				l->arr,
				json_pack("{s:s, s:s, s:s}", "backend", backend,
					  "device", device ? device : "",
					  "error", glint_error_msg()));
		else
			printf("%s %s: %s\n", backend, device ? device : "",
			       glint_error_msg());
		return;
	}
	glint_camera_describe(cam, &in);
	glint_camera_close(cam);
	if (l->json) {
		json_t *f = json_array();
		for (int i = 0; i < in.nformats; i++)
			json_array_append_new(f, json_string(in.formats[i]));
		json_array_append_new(
			l->arr,
			json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:o, s:i, "
				  "s:b, s:[f,f], s:[f,f], s:s, s:s, s:f}",
				  "backend", backend, "device",
				  device ? device : "", "name", in.name,
				  "detail", in.detail, "width", in.width,
				  "height", in.height, "formats", f,
				  "bit_depth", in.bit_depth, "manual_exposure",
				  in.manual_exposure, "exposure_range_s",
				  in.exposure_min_s, in.exposure_max_s,
				  "gain_range", in.gain_min, in.gain_max,
				  "exposure_control", in.exposure_control,
				  "gain_control", in.gain_control,
				  "frame_period_min_s", in.frame_period_min_s));
		return;
	}
	printf("%s %s: %s%s%s\n", backend, device ? device : "", in.name,
	       in.detail[0] ? " — " : "", in.detail);
	printf("  %dx%d, %d-bit, formats:", in.width, in.height, in.bit_depth);
	for (int i = 0; i < in.nformats; i++)
		printf(" %s", in.formats[i]);
	printf("\n  exposure %s: %g .. %g s (%s); gain %g .. %g (%s)\n",
	       in.manual_exposure ? "manual" : "NOT manual (cannot bracket)",
	       in.exposure_min_s, in.exposure_max_s, in.exposure_control,
	       in.gain_min, in.gain_max, in.gain_control);
}

static void found_device(const char *device, void *ctx)
{
	struct listing *l = ctx;
	describe_one(l->backend, device, l);
}

int cmd_cameras(int argc, char **argv)
{
	enum { O_BACKEND = 256, O_DEVICE, O_JSON, O_VERBOSE };
	static const struct option opts[] = {
		{ "backend", required_argument, NULL, O_BACKEND },
		{ "device", required_argument, NULL, O_DEVICE },
		{ "json", no_argument, NULL, O_JSON },
		{ "verbose", no_argument, NULL, O_VERBOSE },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *backend = NULL, *device = NULL;
	struct listing l = { NULL, NULL, 0 };
	int c;

	optind = 1;
	while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
		switch (c) {
		case O_BACKEND:
			backend = optarg;
			break;
		case O_DEVICE:
			device = optarg;
			break;
		case O_JSON:
			l.json = 1;
			break;
		case O_VERBOSE:
			glint_camera_set_verbose(1);
			break;
		case 'h':
			cmd_cameras_help();
			return GLINT_EXIT_OK;
		default:
			return GLINT_EXIT_USAGE;
		}
	}
	if (optind != argc)
		return cmd_usage_error("cameras", "unexpected argument '%s'",
				       argv[optind]);
	if (device && !backend)
		backend = device[0] == '/'	       ? "v4l2"
			  : !strncmp(device, "sim", 3) ? "sim"
						       : "libcamera";
	l.arr = json_array();
	int found = 0;
	for (int i = 0; glint_camera_backends[i]; i++) {
		const struct glint_camera_ops *ops = glint_camera_backends[i];
		if (backend && strcmp(backend, ops->name) != 0)
			continue;
		found = 1;
		l.backend = ops->name;
		if (device || !ops->enumerate) {
			describe_one(ops->name, device ? device : ops->name,
				     &l);
			continue;
		}
		int n = ops->enumerate(found_device, &l);
		if (n == 0 && !l.json)
			printf("%s: no cameras found\n", ops->name);
		else if (n < 0 && !l.json)
			printf("%s: %s\n", ops->name, glint_error_msg());
	}
	if (!found) {
		json_decref(l.arr);
		return cmd_usage_error("cameras",
				       "--backend %s: not built into this "
				       "glint",
				       backend);
	}
	if (l.json)
		cmd_print_json(json_pack("{s:o}", "cameras", l.arr));
	else
		json_decref(l.arr);
	return GLINT_EXIT_OK;
}
