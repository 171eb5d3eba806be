/* SPDX-License-Identifier: MIT */
/*
 * glint capture probe|sample: a verified exposure bracket of the region of
 * interest into a capture session (capture/hdr/session.h); glint cameras: the
 * cameras each backend can open and what they can do.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"

#include "appliance/daemon.h"

#include "capture/hdr/hdr_linear.h"
#include "capture/probe/probe.h"
#include "capture/probe/sphere_detect.h"
#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cmd_capture_help(void)
{
	printf("usage: glint capture (probe | reference | sample) "
	       "[options]\n"
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
	       "A reference is the rig's gray ball at its own turntable "
	       "position (the rig's\n\"reference\" section): its photo "
	       "calibrates the probe session's env.exr into\nthe reference "
	       "session (env.exr, env-calibration.json), which then lights "
	       "a\nsample as a probe session does (--probe REFERENCE_SESSION)."
	       "\n"
	       "\n"
	       "  --config FILE       rig configuration (default: the "
	       "installed appliance's\n"
	       "                      /etc/glint/rig.json; run from a "
	       "build folder, the\n"
	       "                      simulated rig data/rig-sim.json; "
	       "docs/capture.md)\n"
	       "  -o, --output DIR    sessions go under DIR (default: the "
	       "config's \"output\")\n"
	       "  --probe SESSION     the probe session that lights a sample "
	       "or that a\n"
	       "                      reference calibrates (default: the "
	       "newest complete\n"
	       "                      probe session under DIR)\n"
	       "  -v, --verbose       show camera libraries' own logging\n"
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
	       "  -v, --verbose       show camera libraries' own logging\n"
	       "      --json          print JSON on stdout\n");
}

static atomic_int interrupted, cancel_flag;

static void on_sigint(int sig)
{
	(void)sig;
	interrupted = 1;
	cancel_flag = 1;
}

int cmd_capture(int argc, char **argv)
{
	static const char *const kinds[] = { "probe", "reference", "sample",
					     NULL };
	const char *config = NULL, *out = NULL, *probe = NULL;
	char default_config[4096];
	int ret;
	const struct cmd_opt opts[] = {
		CMD_STRING("config", 0, &config),
		CMD_STRING("probe", 0, &probe),
		CMD_STRING("output", 'o', &out),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("capture", cmd_capture_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json;
	glint_camera_set_verbose(a.verbose);
	if (a.argc != 1)
		return cmd_usage_error("capture",
				       "expected what to capture: probe, "
				       "reference or sample");
	if (strcmp(a.argv[0], "probe") && strcmp(a.argv[0], "sample") &&
	    strcmp(a.argv[0], "reference")) {
		cmd_choice_error(a.argv[0], kinds);
		return cmd_usage_error("capture", "'%s': %s", a.argv[0],
				       glint_error_msg());
	}
	const char *kind = a.argv[0];
	config = cmd_rig_config(default_config, sizeof(default_config), config);

	struct glint_rig rig;
	ret = glint_rig_load(config, &rig);
	if (ret < 0) {
		glint_rig_free(&rig);
		return cmd_fail("capture");
	}
	if (!out)
		out = rig.output;

	struct glint_capture_result res;
	struct sigaction sa, old_int, old_term;

	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_sigint;
	sigaction(SIGINT, &sa, &old_int);
	sigaction(SIGTERM, &sa, &old_term);
	ret = glint_rig_capture(&rig, kind, out, probe, &cancel_flag, &res);
	sigaction(SIGINT, &old_int, NULL);
	sigaction(SIGTERM, &old_term, NULL);
	glint_rig_free(&rig);
	if (ret < 0) {
		cmd_fail("capture");
		return interrupted ? 130 : GLINT_EXIT_FAIL;
	}
	if (json)
		cmd_print_json(res.summary);
	else
		json_decref(res.summary);
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
	const char *backend = NULL, *device = NULL;
	struct listing l = { NULL, NULL, 0 };
	const struct cmd_opt opts[] = {
		CMD_STRING("backend", 0, &backend),
		CMD_STRING("device", 0, &device),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("cameras", cmd_cameras_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	l.json = a.json;
	glint_camera_set_verbose(a.verbose);
	if (a.argc != 0)
		return cmd_usage_error("cameras", "unexpected argument '%s'",
				       a.argv[0]);
	if (device && !backend)
		backend = device[0] == '/'	       ? "v4l2"
			  : !strncmp(device, "sim", 3) ? "sim"
						       : "libcamera";
	l.arr = json_array();
	int found = 0;
	for (int i = 0; glint_camera_backends()[i]; i++) {
		const struct glint_camera_ops *ops = glint_camera_backends()[i];
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
