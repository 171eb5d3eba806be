/* SPDX-License-Identifier: MIT */
/*
 * The scene of a captured sample (docs/scene.md), written into its session
 * so that `glint fit SESSION` needs nothing else: the rig's camera, the
 * sphere where it was found in sample.exr (circle_px; its 3-D position
 * follows through the pinhole model) and the probe session's env.exr.
 */
#define _GNU_SOURCE /* realpath */
#include "scene_file.h"

#include "capture/probe/sphere_detect.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"

#include <dirent.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static int is_file(const char *path)
{
	struct stat st;
	return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* A probe session whose session.json says "complete" and that has an
 * env.exr. */
static int usable_probe(const char *dir)
{
	char path[PATH_MAX + 32];
	json_t *doc;
	int ok;

	snprintf(path, sizeof(path), "%s/env.exr", dir);
	if (!is_file(path))
		return 0;
	snprintf(path, sizeof(path), "%s/session.json", dir);
	doc = glint_json_read_quiet(path);
	ok = doc && json_is_string(json_object_get(doc, "status")) &&
	     !strcmp(json_string_value(json_object_get(doc, "status")),
		     "complete");
	json_decref(doc);
	return ok;
}

int glint_session_latest_probe(const char *root, char *out, size_t n)
{
	DIR *d = opendir(root);
	struct dirent *e;
	char best[256] = "", path[PATH_MAX + 300];

	if (!d)
		return glint_error_set(errno, "%s: cannot list sessions: %s",
				       root, strerror(errno));
	/* Session names end in their UTC start time: the greatest is the
	 * newest. */
	while ((e = readdir(d)) != NULL) {
		if (strncmp(e->d_name, "probe-", 6) != 0 ||
		    strcmp(e->d_name, best) <= 0 ||
		    strlen(e->d_name) >= sizeof(best))
			continue;
		snprintf(path, sizeof(path), "%s/%s", root, e->d_name);
		if (usable_probe(path))
			snprintf(best, sizeof(best), "%s", e->d_name);
	}
	closedir(d);
	if (!best[0])
		return glint_error_set(ENOENT,
				       "%s: no complete probe session with an "
				       "env.exr (capture the probe first, or "
				       "pass --probe)",
				       root);
	snprintf(out, n, "%s/%s", root, best);
	return 0;
}

/* env.exr of probe_dir as the scene in sample_dir should name it: relative
 * when the two sessions are siblings (a moved capture folder keeps
 * working), else absolute. */
static int env_reference(const char *sample_dir, const char *probe_dir,
			 char *out, size_t n)
{
	char a[PATH_MAX], b[PATH_MAX];
	if (!realpath(sample_dir, a) || !realpath(probe_dir, b))
		return glint_error_set(errno, "%s: %s", probe_dir,
				       strerror(errno));
	char *sa = strrchr(a, '/'), *sb = strrchr(b, '/');
	if (sa && sb && sa - a == sb - b && !strncmp(a, b, (size_t)(sa - a)))
		snprintf(out, n, "..%s/env.exr", sb);
	else
		snprintf(out, n, "%s/env.exr", b);
	return 0;
}

/* The relative standard uncertainty of the probe's map per channel, when
 * a gray ball calibrated it (env-calibration.json beside env.exr): 1, or
 * 0 when there is none or it is not whole. */
static int calibration_sigma(const char *probe_dir, double rel[3])
{
	char path[PATH_MAX + 32];
	snprintf(path, sizeof(path), "%s/env-calibration.json", probe_dir);
	json_t *doc = glint_json_read_quiet(path);
	json_t *s = json_object_get(doc, "scale"),
	       *e = json_object_get(doc, "scale_sigma");
	int ok = json_array_size(s) == 3 && json_array_size(e) == 3;
	for (int c = 0; ok && c < 3; c++) {
		double v = json_number_value(json_array_get(s, c)),
		       sg = json_number_value(json_array_get(e, c));
		rel[c] = sg / v;
		ok = v > 0 && sg >= 0 && rel[c] <= 1;
	}
	json_decref(doc);
	return ok;
}

int glint_sample_write_scene(const char *dir, const struct glint_image *sample,
			     const struct glint_scene_optics *o,
			     const char *probe_dir, struct glint_circle *found)
{
	char env[PATH_MAX + 16], path[PATH_MAX + 16];
	struct glint_circle c;
	int ret;

	if (!usable_probe(probe_dir))
		return glint_error_set(ENOENT,
				       "%s: not a complete probe session with "
				       "an env.exr",
				       probe_dir);
	ret = glint_sphere_detect(sample, 0, 0, &c);
	if (ret < 0)
		return glint_error_prefix(ret, "finding the sample sphere");
	ret = env_reference(dir, probe_dir, env, sizeof(env));
	if (ret < 0)
		return ret;
	if (o->principal[0] >= 0 &&
	    (fabs(o->principal[0] - sample->width / 2.0) > 0.5 ||
	     fabs(o->principal[1] - sample->height / 2.0) > 0.5))
		glint_log_warn("optics.principal (%g, %g) is not the "
			       "image centre; scene files assume the centre",
			       o->principal[0], o->principal[1]);
	/* A pinhole needs only focal length / pitch; a real pitch keeps the
	 * file's millimetres true for depth of field. */
	json_t *doc = json_pack(
		"{s:s, s:{s:i, s:i, s:f, s:f}, s:{s:f, s:{s:f, s:f, s:f}}, "
		"s:{s:s}}",
		"units", "metres", "camera", "width", sample->width, "height",
		sample->height, "focal_length_mm",
		o->focal_px * o->pitch_um * 1e-3, "pixel_pitch_um", o->pitch_um,
		"sphere", "diameter_m", o->diameter_m, "circle_px", "cx", c.cx,
		"cy", c.cy, "r", c.r, "environment", "path", env);
	json_t *cam = doc ? json_object_get(doc, "camera") : NULL;
	double rel[3];
	json_t *envo = doc ? json_object_get(doc, "environment") : NULL;
	if (envo && calibration_sigma(probe_dir, rel))
		json_object_set_new(envo, "scale_sigma",
				    glint_json_reals(rel, 3));
	/* the probe's compact sources, named as the map is (beside it) */
	char src[PATH_MAX + 32];
	size_t el = strlen(env);
	snprintf(path, sizeof(path), "%s/env-sources.json", probe_dir);
	if (envo && is_file(path) && el >= 7 &&
	    !strcmp(env + el - 7, "env.exr")) {
		snprintf(src, sizeof(src), "%.*senv-sources.json",
			 (int)(el - 7), env);
		json_object_set_new(envo, "sources", json_string(src));
	}
	if (cam && o->psf_sigma_px > 0)
		json_object_set_new(cam, "psf_sigma_px",
				    json_real(o->psf_sigma_px));
	if (cam && o->olpf)
		json_object_set_new(cam, "olpf", json_true());
	if (cam && o->cfa[0])
		json_object_set_new(cam, "cfa", json_string(o->cfa));
	char *text =
		doc ? json_dumps(doc, JSON_INDENT(2) | JSON_REAL_PRECISION(10))
		    : NULL;
	json_decref(doc);
	if (!text)
		return glint_error_set(ENOMEM, "out of memory");
	snprintf(path, sizeof(path), "%s/scene.json", dir);
	size_t len = strlen(text);
	text[len] = '\n'; /* json_dumps's terminator becomes the newline */
	ret = glint_atomic_write_file(path, text, len + 1);
	free(text);
	if (ret < 0)
		return ret;
	glint_log_info("sample sphere at (%.2f, %.2f), radius %.2f px (%d "
		       "edge points, %.2f px rms); scene.json lit by %s",
		       c.cx, c.cy, c.r, c.points, c.rms_px, env);
	if (found)
		*found = c;
	return 0;
}
