/* SPDX-License-Identifier: MIT */
/*
 * One capture as `glint capture` and the rig daemon run it: a bracket into
 * a session, merged; a probe unwrapped to env.exr, a sample given its
 * scene.json.
 */
#define _POSIX_C_SOURCE 200809L
#include "run.h"

#include "capture/probe/probe.h"
#include "capture/probe/probe_calibrate.h"
#include "capture/probe/probe_sources.h"
#include "scene_file.h"
#include "capture/hdr/session.h"
#include "capture/hdr/session_merge.h"
#include "capture/probe/sphere_detect.h"
#include "core/error.h"
#include "core/log.h"

#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The sphere in img, looked for inside roi when it is given (a frame
 * that holds a gray/chrome pair holds two). */
static int detect_in(const struct glint_image *img, const struct glint_roi *roi,
		     struct glint_circle *c)
{
	int x0 = roi->x0, y0 = roi->y0, x1 = roi->x1, y1 = roi->y1;
	if (x1 > img->width)
		x1 = img->width;
	if (y1 > img->height)
		y1 = img->height;
	if (!(x1 > x0 && y1 > y0))
		return glint_sphere_detect(img, 0, 0, c);
	struct glint_image *crop =
		glint_image_crop(img, x0, y0, x1 - x0, y1 - y0);
	if (!crop)
		return glint_error_set(ENOMEM, "out of memory");
	int ret = glint_sphere_detect(crop, 0, 0, c);
	glint_image_free(crop);
	if (ret < 0)
		return glint_error_prefix(ret, "in [%d, %d, %d, %d]", x0, y0,
					  x1, y1);
	c->cx += x0;
	c->cy += y0;
	return 0;
}

/* The probe session `from`'s env.exr and its sources calibrated by the
 * gray ball in `photo` (inside setup.reference's roi when given) and
 * written with env-calibration.json into `dir`: `from` itself for a gray
 * ball beside the chrome one, the reference session for a gray ball
 * photographed at its own position.  geom: the camera's optics (and the
 * photo's merge weights) as the unwrap used them. */
static int calibrate_into(const char *from, const char *dir,
			  const struct glint_capture_setup *s,
			  const struct glint_image *photo,
			  const char *photo_name,
			  const struct glint_unwrap_opts *geom)
{
	char env_in[GLINT_PATH_MAX], src_in[GLINT_PATH_MAX];
	char env_path[GLINT_PATH_MAX], src_path[GLINT_PATH_MAX],
		cal_path[GLINT_PATH_MAX];
	struct glint_unwrap_opts g = *geom;
	struct glint_calibrate_opts co;
	struct glint_calibration cal;
	struct glint_light_sources src;
	struct glint_image *env = NULL;
	struct glint_circle c;
	int ret = detect_in(photo, &s->ref_roi, &c);

	if (ret < 0)
		return glint_error_prefix(ret, "%s/%s: the gray ball", dir,
					  photo_name);
	g.ball_cx = c.cx;
	g.ball_cy = c.cy;
	g.ball_r = c.r;
	glint_calibrate_default_opts(&co);
	for (int k = 0; k < 3; k++) {
		co.albedo[k] = s->ref_albedo;
		co.albedo_sigma[k] = s->ref_albedo_sigma;
	}
	co.weights = geom->weights;
	ret = glint_path_join(env_in, sizeof(env_in), from, GLINT_SESSION_ENV);
	if (ret == 0)
		ret = glint_path_sibling(src_in, sizeof(src_in), env_in,
					 "-sources.json");
	if (ret == 0)
		ret = glint_path_join(env_path, sizeof(env_path), dir,
				      GLINT_SESSION_ENV);
	if (ret == 0)
		ret = glint_path_sibling(src_path, sizeof(src_path), env_path,
					 "-sources.json");
	if (ret == 0)
		ret = glint_path_sibling(cal_path, sizeof(cal_path), env_path,
					 "-calibration.json");
	if (ret == 0)
		ret = glint_image_read(env_in, &env);
	int have_src = 0;
	if (ret == 0) {
		ret = glint_probe_sources_read(src_in, &src);
		have_src = ret == 0;
		if (ret == -ENOENT) { /* no compact source: the scale alone */
			glint_error_clear();
			ret = 0;
		}
	}
	if (ret == 0)
		ret = glint_probe_calibrate(env, have_src ? &src : NULL, photo,
					    &g, &co, &cal);
	if (ret == 0) {
		glint_probe_calibration_apply(&cal, env,
					      have_src ? &src : NULL);
		ret = glint_image_write(env_path, env, NULL);
	}
	if (ret == 0 && have_src)
		ret = glint_probe_sources_write(src_path, "probe.exr", &src);
	if (ret == 0)
		ret = glint_probe_calibration_write(cal_path, GLINT_SESSION_ENV,
						    photo_name, &cal);
	if (ret == 0)
		glint_log_info("gray ball at (%.2f, %.2f), radius %.2f px: the "
			       "map x %.3f %.3f %.3f (+- %.3f), %d source%s "
			       "measured by it",
			       c.cx, c.cy, c.r, cal.scale[0], cal.scale[1],
			       cal.scale[2], cal.scale_sigma[1], cal.nsources,
			       cal.nsources == 1 ? "" : "s");
	glint_image_free(env);
	return ret < 0 ? glint_error_prefix(ret, "calibration") : 0;
}

/* The unwrap's optics from the rig (the ball's place left to the
 * caller). */
static void optics_opts(const struct glint_capture_setup *s,
			struct glint_unwrap_opts *o)
{
	glint_unwrap_default_opts(o);
	o->fpx = s->focal_px;
	o->cx = s->principal[0];
	o->cy = s->principal[1];
	o->psf_sigma_px = s->psf_sigma_px;
	o->olpf = s->olpf;
}

/* A merged photo of the gray ball at its own turntable position: the
 * probe session `probe`'s map calibrated into this session (env.exr,
 * env-sources.json, env-calibration.json), so that a sample captured
 * after it is lit by this session's map. */
static int calibrate_reference(const char *dir, const char *probe,
			       const struct glint_capture_setup *s,
			       const struct glint_image *photo)
{
	char path[GLINT_PATH_MAX];
	struct glint_unwrap_opts o;
	struct glint_image *wt = NULL;

	if (!probe || !probe[0])
		return glint_error_set(EINVAL,
				       "%s: a reference photo calibrates a "
				       "probe: capture the probe first (or "
				       "name its session)",
				       dir);
	optics_opts(s, &o);
	int ret = glint_path_join(path, sizeof(path), dir,
				  "reference-weights.exr");
	if (ret == 0)
		ret = glint_image_read(path, &wt);
	o.weights = wt;
	if (ret == 0)
		ret = calibrate_into(probe, dir, s, photo, "reference.exr", &o);
	glint_image_free(wt);
	return ret;
}

/* The merged probe -> env.exr (+ env-mask.png, env-density.exr): the ball
 * found in it (inside roi.probe when given), unwrapped with the rig's
 * focal length, and the map checked as light before it is written
 * (glint_probe_unwrap_write); with a gray ball beside it, calibrated. */
static int unwrap_probe(const char *dir, const struct glint_capture_setup *s,
			const struct glint_image *probe)
{
	char path[GLINT_PATH_MAX];
	struct glint_unwrap_opts o;
	struct glint_circle c;
	int ret = detect_in(probe, &s->roi[0], &c);

	if (ret < 0)
		return glint_error_prefix(ret, "%s/probe.exr", dir);
	optics_opts(s, &o);
	o.ball_cx = c.cx;
	o.ball_cy = c.cy;
	o.ball_r = c.r;
	glint_log_info("probe ball at (%.2f, %.2f), radius %.2f px "
		       "(%d edge points, %.2f px rms)",
		       c.cx, c.cy, c.r, c.points, c.rms_px);
	/* the merge's variance and weights, just written beside it: the
	 * compact sources' noise and clipping */
	struct glint_image *var = NULL, *wt = NULL;
	ret = glint_path_join(path, sizeof(path), dir, "probe-variance.exr");
	if (ret == 0)
		ret = glint_image_read(path, &var);
	if (ret == 0)
		ret = glint_path_join(path, sizeof(path), dir,
				      "probe-weights.exr");
	if (ret == 0)
		ret = glint_image_read(path, &wt);
	o.variance = var;
	o.weights = wt;
	if (ret == 0)
		ret = glint_path_join(path, sizeof(path), dir,
				      GLINT_SESSION_ENV);
	if (ret == 0)
		ret = glint_probe_unwrap_write(probe, &o, path, NULL, NULL);
	if (ret == 0 && s->ref_albedo > 0 && !s->ref_own)
		ret = calibrate_into(dir, dir, s, probe, "probe.exr", &o);
	glint_image_free(var);
	glint_image_free(wt);
	return ret;
}

/* A merged sample -> scene.json lit by the probe session's env.exr.  A
 * missing probe is not the sample's fault: its capture stays complete and
 * the warning says what to do; a given probe that is wrong is an error. */
static int sample_scene(const char *dir, const char *root, const char *probe,
			const struct glint_capture_setup *s,
			const struct glint_image *rad, const char *format,
			char *scene_path, size_t n)
{
	static const char *const bayer[] = { "RGGB16", "GRBG16", "GBRG16",
					     "BGGR16" };
	char found[GLINT_PATH_MAX];
	struct glint_scene_optics o = { s->focal_px,
					{ s->principal[0], s->principal[1] },
					s->pitch_um,
					s->diameter_m,
					s->psf_sigma_px,
					s->olpf,
					"" };
	int ret = 0;

	/* a Bayer layout (RGGB16 ...): its colours; MONO16 and RGB16 none */
	for (size_t k = 0; k < sizeof(bayer) / sizeof(bayer[0]); k++)
		if (!strcmp(format, bayer[k]))
			snprintf(o.cfa, sizeof(o.cfa), "%.4s", bayer[k]);

	if (!probe) {
		ret = glint_session_latest_probe(root, found, sizeof(found));
		probe = found;
	}
	if (ret == 0)
		ret = glint_sample_write_scene(dir, rad, &o, probe, NULL);
	if (ret == 0)
		return glint_path_join(scene_path, n, dir, GLINT_SESSION_SCENE);
	if (probe != found)
		return ret;
	glint_log_warn("no scene.json for the sample: %s (session "
		       "%s is complete; glint fit needs a scene)",
		       glint_error_msg(), dir);
	return 0;
}

struct frame_ctx {
	struct glint_session *session;
	struct glint_hdr_stream *hdr; /* raw frames: the merge, as they come */
	struct glint_progress progress;
};

/* Each frame to disk, then folded into the merge (a raw bracket): the
 * merged image is ready moments after the last frame, and no more than
 * one frame is held (a 12 MP bracket is 540 MB). */
static int save_frame(const struct glint_frame *f, int index, void *ctx)
{
	struct frame_ctx *c = ctx;
	int ret = glint_session_add_frame(c->session, f, index);
	if (ret == 0 && index == 0 && f->linear && f->channels == 1) {
		struct glint_noise_model nm;
		glint_noise_default(&nm);
		ret = glint_session_noise(glint_session_dir(c->session), &nm);
		if (ret == 0)
			ret = glint_hdr_stream_new(&nm, &c->hdr);
	}
	if (ret == 0 && c->hdr)
		ret = glint_hdr_stream_add(c->hdr, f);
	glint_progress_add(&c->progress, 1);
	return ret;
}

/* The bracket into the session (which is finished by the caller, once
 * every stage after it has run). */
static int bracket_into(struct glint_camera *cam,
			const struct glint_capture_setup *s, const char *kind,
			struct glint_session *session, atomic_int *cancel,
			struct glint_bracket *b, struct glint_hdr_stream **hdr)
{
	struct glint_bracket_opts opts = s->bracket;
	struct frame_ctx fc = { .session = session };

	opts.on_frame = save_frame;
	opts.ctx = &fc;
	opts.cancel = cancel;
	opts.release_pixels = 1;
	/* The camera's preparation (the simulator renders its views) before
	 * the progress bar and the bracket's clock start. */
	int ret = glint_camera_start(cam);
	if (ret < 0)
		return ret;
	glint_progress_start(&fc.progress, "frames", opts.max_frames);
	const struct glint_roi *roi =
		!strcmp(kind, "reference")
			? &s->ref_roi
			: &s->roi[strcmp(kind, "probe") != 0];
	ret = glint_bracket_capture(cam, roi, &opts, &glint_clock_real, b);
	glint_progress_finish(&fc.progress);
	*hdr = fc.hdr;
	if (ret == 0)
		ret = glint_bracket_verdict(b, &opts);
	return ret;
}

/* How far below zero, in its standard deviations, a dark site of an
 * n-site merge may lie by chance: the depth one photo in
 * GLINT_NEGATIVE_FALSE_ALARM_PHOTOS reaches somewhere (n times the
 * normal tail), and at least 5.  A fixed depth would refuse good photos
 * as they grow: -5 sigma happens once in 3.5 million sites, about three
 * times in a 12 MP frame. */
#define GLINT_NEGATIVE_FALSE_ALARM_PHOTOS 1e4

double glint_negative_sigma_limit(size_t n)
{
	if (n < 1)
		n = 1;
	return fmax(5, gsl_cdf_ugaussian_Qinv(
			       1 / (GLINT_NEGATIVE_FALSE_ALARM_PHOTOS * n)));
}

/* A merged bracket is radiance before it is written: finite, not
 * negative beyond its noise (a merge's dark sites scatter about zero by
 * their noise: glint_negative_sigma_limit), brighter than its noise
 * somewhere, and for a probe, its brightest sites measured in some frame
 * (a light clipped in every frame is a light of unknown strength). */
static int check_raw(const struct glint_raw_hdr *raw, const char *kind,
		     const char *file)
{
	size_t n = (size_t)raw->width * raw->height;
	size_t bright = 0, clipped = 0, first_clip = 0;
	double limit = glint_negative_sigma_limit(n);

	for (size_t i = 0; i < n; i++) {
		double x = raw->x[i], v = raw->var[i];
		if (!raw->valid[i]) {
			if (!clipped++)
				first_clip = i;
			continue;
		}
		if (!isfinite(x) || !isfinite(v) || v < 0)
			return glint_error_set(
				ERANGE,
				"%s: site (%zu, %zu) has radiance %g, variance "
				"%g: expected finite values",
				file, i % (size_t)raw->width,
				i / (size_t)raw->width, x, v);
		if (x < -limit * sqrt(v))
			return glint_error_set(
				ERANGE,
				"%s: site (%zu, %zu) has radiance %g, %.1f "
				"standard deviations below zero: expected >= "
				"0 within its noise (no deeper than %.1f among "
				"%zu sites by chance; a wrong black level or "
				"noise model?)",
				file, i % (size_t)raw->width,
				i / (size_t)raw->width, x, -x / sqrt(v), limit,
				n);
		bright += x > 3 * sqrt(v);
	}
	if (bright * 100 < n)
		return glint_error_set(
			ERANGE,
			"%s: the photo is darker than its noise: %zu of %zu "
			"sites are 3 standard deviations above zero (at "
			"least 1 %% expected): lights off, lens capped, or "
			"a bracket too short",
			file, bright, n);
	if (!strcmp(kind, "probe") && clipped)
		return glint_error_set(
			ERANGE,
			"%s: %zu sites are clipped in every frame, the "
			"first at (%zu, %zu): the brightest light's strength "
			"is unknown, so the probe cannot say how the sample "
			"was lit (the shortest exposure was not short enough: "
			"an ND filter, or a smaller aperture)",
			file, clipped, first_clip % (size_t)raw->width,
			first_clip / (size_t)raw->width);
	return 0;
}

/* The merged HDR image of a raw bracket, beside its frames: KIND.exr,
 * KIND-variance.exr, KIND-weights.exr, KIND-mask.png, KIND.png; then the
 * probe's unwrap or the sample's scene.  *stage says which step failed;
 * files[] gets the outputs promised (names inside the session). */
static int merge_session(const struct glint_capture_setup *s, const char *kind,
			 const char *out, const char *probe,
			 struct glint_hdr_stream *hdr,
			 struct glint_capture_result *res, const char **stage,
			 char files[][64], int *nfiles)
{
	static const char *const suffix[5] = { ".exr", "-variance.exr",
					       "-weights.exr", "-mask.png",
					       ".png" };
	const char *dir = res->session;
	char names[5][64], file[GLINT_PATH_MAX];
	const char *np[5];
	struct glint_hdr_report rep;
	struct glint_raw_hdr raw;
	struct glint_image *rad = NULL;
	char format[sizeof(raw.format)] = "";
	long valid_px;
	int w, h, ret;

	*stage = "merge";
	for (int i = 0; i < 5; i++) {
		snprintf(names[i], sizeof(names[i]), "%s%s", kind, suffix[i]);
		np[i] = names[i];
	}
	ret = glint_path_join(file, sizeof(file), dir, names[0]);
	if (ret == 0)
		ret = glint_hdr_stream_finish(hdr, &raw, &rep);
	if (ret == 0 && (ret = check_raw(&raw, kind, file)) < 0)
		glint_raw_hdr_release(&raw);
	if (ret == 0) {
		snprintf(format, sizeof(format), "%s", raw.format);
		ret = glint_hdr_write(&raw, dir, np, &w, &h, &valid_px, &rad);
	}
	for (int i = 0; ret == 0 && i < 5; i++)
		snprintf(files[(*nfiles)++], 64, "%s", names[i]);
	if (ret == 0 && !strcmp(kind, "probe") && s->focal_px > 0) {
		*stage = "unwrap";
		ret = unwrap_probe(dir, s, rad);
		if (ret == 0) {
			snprintf(files[(*nfiles)++], 64, "%s",
				 GLINT_SESSION_ENV);
			snprintf(files[(*nfiles)++], 64, "env-mask.png");
			snprintf(files[(*nfiles)++], 64, "env-density.exr");
			snprintf(files[(*nfiles)++], 64, "env-sources.json");
			snprintf(files[(*nfiles)++], 64, "env-preview.png");
			if (s->ref_albedo > 0 && !s->ref_own)
				snprintf(files[(*nfiles)++], 64,
					 "env-calibration.json");
		}
	}
	if (ret == 0 && !strcmp(kind, "reference")) {
		*stage = "calibration";
		ret = calibrate_reference(dir, probe, s, rad);
		if (ret == 0) {
			snprintf(files[(*nfiles)++], 64, "%s",
				 GLINT_SESSION_ENV);
			snprintf(files[(*nfiles)++], 64,
				 "env-calibration.json");
		}
	}
	if (ret == 0 && !strcmp(kind, "sample") && s->focal_px > 0) {
		*stage = "scene";
		ret = sample_scene(dir, out, probe, s, rad, format, res->scene,
				   sizeof(res->scene));
		if (ret == 0 && res->scene[0])
			snprintf(files[(*nfiles)++], 64, "%s",
				 GLINT_SESSION_SCENE);
	}
	glint_image_free(rad);
	return ret;
}

/* Every output promised is there, a regular file with something in it. */
static int verify_files(const char *dir, char files[][64], int n)
{
	char path[GLINT_PATH_MAX];
	struct stat st;

	for (int i = 0; i < n; i++) {
		int ret = glint_path_join(path, sizeof(path), dir, files[i]);
		if (ret < 0)
			return ret;
		if (stat(path, &st) < 0 || !S_ISREG(st.st_mode) ||
		    st.st_size == 0)
			return glint_error_set(EIO,
					       "%s: missing or empty after it "
					       "was written",
					       path);
	}
	return 0;
}

static json_t *summary(const char *kind, const struct glint_bracket *b,
		       const struct glint_capture_result *res)
{
	const struct glint_frame *lo = &b->frames[0],
				 *hi = &b->frames[b->n - 1];

	glint_log_info(
		"%d frames, %.4g s .. %.4g s (gain up to %.3g): %.1f s of "
		"exposure and readout, %.1f s here%s%s",
		b->n, lo->exposure_s, hi->exposure_s, hi->gain, b->seconds,
		b->wall_seconds,
		b->covered_low && b->covered_high ? ", range covered" : "",
		b->camera_limit ? " (as far as the camera goes)" : "");
	return json_pack(
		"{s:s, s:s, s:s, s:s*, s:i, s:f, s:f, s:f, s:b, s:b, "
		"s:b, s:b, s:b, s:f, s:f}",
		"status", "complete", "kind", kind, "session", res->session,
		"scene", res->scene[0] ? res->scene : NULL, "frames", b->n,
		"shortest_s", lo->exposure_s, "longest_s", hi->exposure_s,
		"max_gain", hi->gain, "covered_low", b->covered_low,
		"covered_high", b->covered_high, "used_gain", b->used_gain,
		"truncated", b->truncated, "camera_limit", b->camera_limit,
		"seconds", b->seconds, "wall_seconds", b->wall_seconds);
}

int glint_capture_run(const struct glint_capture_setup *s, const char *kind,
		      const char *out, const char *probe, atomic_int *cancel,
		      struct glint_capture_result *res)
{
	struct glint_camera *cam = NULL;
	struct glint_camera_info info;
	struct glint_session *session = NULL;
	struct glint_bracket b = { 0 };
	struct glint_hdr_stream *hdr = NULL;
	const char *stage = "bracket";
	char files[16][64], err[1024];
	int nfiles = 0, ret;

	memset(res, 0, sizeof(*res));
	ret = glint_camera_open(s->backend, s->device, NULL, &cam);
	if (ret < 0)
		goto err_camera;
	glint_camera_describe(cam, &info);
	ret = glint_session_create(out, kind, s->text, &info, &session);
	if (ret < 0)
		goto err_session;
	snprintf(res->session, sizeof(res->session), "%s",
		 glint_session_dir(session));
	glint_log_info("capturing the %s with %s (%s) into %s", kind, info.name,
		       info.backend, res->session);
	ret = bracket_into(cam, s, kind, session, cancel, &b, &hdr);
	if (ret == 0 && hdr)
		ret = merge_session(s, kind, out, probe, hdr, res, &stage,
				    files, &nfiles);
	if (ret == 0) {
		stage = "verify";
		ret = verify_files(res->session, files, nfiles);
	}
	if (ret == 0 && !(res->summary = summary(kind, &b, res)))
		ret = glint_error_set(ENOMEM, "out of memory");
	/* The session says how it ended, whatever ended it. */
	snprintf(err, sizeof(err), "%s", ret < 0 ? glint_error_msg() : "");
	const char *fp[17];
	for (int i = 0; i < nfiles; i++)
		fp[i] = files[i];
	fp[nfiles] = NULL;
	int r2 = glint_session_finish(session, &b, ret < 0 ? stage : NULL,
				      ret < 0 ? err : NULL, fp);
	if (ret < 0) {
		int capture = !strcmp(stage, "bracket");
		glint_error_set(-ret, "the %s's %s: %s (session %s kept, %s)",
				kind, stage, err, res->session,
				capture ? "incomplete" : "failed");
		json_decref(res->summary);
		res->summary = NULL;
	} else {
		ret = r2;
	}
	/* The frames are released on every path (they are on disk). */
	glint_hdr_stream_free(hdr);
	glint_bracket_release(&b);
err_session:
	glint_camera_close(cam);
err_camera:
	return ret;
}
