/* SPDX-License-Identifier: MIT */
/*
 * One capture as `glint capture` and the rig daemon run it: a bracket into
 * a session, merged; a probe unwrapped to env.exr, a sample given its
 * scene.json.
 */
#define _POSIX_C_SOURCE 200809L
#include "capture_run.h"
#include "capture_scene.h"
#include "cmd.h"

#include "capture/hdr_linear.h"
#include "capture/probe.h"
#include "capture/session.h"
#include "capture/sphere_detect.h"
#include "core/error.h"
#include "core/log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The merged probe -> env.exr (+ env-mask.png, env-density.exr): the ball
 * found in it, unwrapped with the rig's focal length. */
static int unwrap_probe(const char *dir, const struct glint_rig *rig,
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
			const struct glint_rig *rig,
			const struct glint_image *rad, char *scene_path,
			size_t n)
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
int capture_run(const struct glint_rig *rig_in, const char *kind,
		const char *out, const char *probe, volatile int *cancel,
		struct capture_result *res)
{
	struct glint_camera *cam = NULL;
	struct glint_camera_info info;
	struct glint_session *session = NULL;
	char *session_dir = res->session;
	struct glint_bracket b;
	struct frame_ctx fc;

	struct glint_rig rig = *rig_in;
	int ret;

	memset(res, 0, sizeof(*res));
	ret = glint_camera_open(rig.backend, rig.device, NULL, &cam);
	if (ret < 0)
		goto done;
	glint_camera_describe(cam, &info);
	ret = glint_session_create(out, kind, rig.text, &info, &session);
	if (ret < 0)
		goto done;
	snprintf(session_dir, sizeof(res->session), "%s",
		 glint_session_dir(session));
	glint_log_info("capturing the %s with %s (%s) into %s", kind, info.name,
		       info.backend, glint_session_dir(session));
	memset(&fc, 0, sizeof(fc));
	fc.session = session;
	rig.bracket.on_frame = save_frame;
	rig.bracket.ctx = &fc;
	rig.bracket.cancel = cancel;
	glint_progress_start(&fc.progress, "frames", rig.bracket.max_frames);
	ret = glint_bracket_capture(cam, &rig.roi[strcmp(kind, "probe") != 0],
				    &rig.bracket, &glint_clock_real, &b);
	glint_progress_finish(&fc.progress);
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
					   res->scene, sizeof(res->scene));
		glint_image_free(rad);
	}
	if (ret == 0) {
		res->summary = json_pack(
			"{s:s, s:s, s:s, s:s*, s:i, s:f, s:f, s:f, s:b, s:b, "
			"s:b, s:b, s:f}",
			"status", "complete", "kind", kind, "session",
			session_dir, "scene", res->scene[0] ? res->scene : NULL,
			"frames", b.n, "shortest_s", b.frames[0].exposure_s,
			"longest_s", b.frames[b.n - 1].exposure_s, "max_gain",
			b.frames[b.n - 1].gain, "covered_low", b.covered_low,
			"covered_high", b.covered_high, "used_gain",
			b.used_gain, "truncated", b.truncated, "seconds",
			b.seconds);
		glint_log_info("%d frames, %.4g s .. %.4g s (gain up to %.3g) "
			       "in %.1f s%s%s",
			       b.n, b.frames[0].exposure_s,
			       b.frames[b.n - 1].exposure_s,
			       b.frames[b.n - 1].gain, b.seconds,
			       b.covered_low && b.covered_high
				       ? ", range covered"
				       : "",
			       b.truncated ? " (stopped by a cap)" : "");
		glint_bracket_release(&b);
	}
done:
	glint_camera_close(cam);
	return ret;
}
