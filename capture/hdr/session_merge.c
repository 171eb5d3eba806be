/* SPDX-License-Identifier: MIT */
/*
 * A session's raw bracket merged and written beside its frames (glint
 * hdr SESSION and every capture): radiance, variance, fit weights, a
 * validity mask and a preview.
 */
#define _POSIX_C_SOURCE 200809L
#include "capture/hdr/session_merge.h"

#include "capture/hdr/frame_file.h"
#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/path.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The rig's "sensor" section, if the session has one. */
int glint_session_noise(const char *dir, struct glint_noise_model *m)
{
	static const char *const keys[] = { "dn_per_electron", "read_noise_e",
					    "saturation_dn", NULL };
	char path[GLINT_PATH_MAX];
	json_t *rig, *s = NULL;
	struct stat st;
	int ret;

	ret = glint_path_join(path, sizeof(path), dir, "rig.json");
	if (ret < 0)
		return ret;
	if (stat(path, &st) != 0)
		return 0;
	ret = glint_json_load(path, &rig);
	if (ret < 0)
		return ret;
	ret = glint_json_object(path, "", rig, "sensor", 0, &s);
	if (!ret && s)
		ret = glint_json_known_keys(path, "sensor", s, keys);
	if (!ret && s)
		ret = glint_json_number(path, "sensor", s, "dn_per_electron", 0,
					(struct glint_range){ 0, 1e6, 1, 0 },
					&m->dn_per_electron);
	if (!ret && s)
		ret = glint_json_number(path, "sensor", s, "read_noise_e", 0,
					(struct glint_range){ 0, 1e6, 0, 0 },
					&m->read_noise_e);
	if (!ret && s)
		ret = glint_json_number(path, "sensor", s, "saturation_dn", 0,
					(struct glint_range){ 0, 65535, 0, 0 },
					&m->saturation_dn);
	json_decref(rig);
	return ret;
}

/*
 * Read frame `name` of a session and check it is the frame the session
 * recorded there: its own metadata gives the index in its name and the
 * exposure the session lists, its sequence number follows the previous
 * frame's, and its pixels match their checksum, both its own and the
 * one session.json recorded.  A frame copied over another, swapped,
 * edited or taken from another session is an error naming it.
 */
static int frame_in_place(const char *path, const char *name,
			  const json_t *listed, struct glint_frame *f,
			  const struct glint_frame *prev)
{
	int index, named;
	uint32_t pixels_crc = 0;
	int ret = glint_frame_read_crc(path, f, &index, &pixels_crc);
	if (ret < 0)
		return ret;
	double t = json_number_value(json_object_get(listed, "exposure_s"));
	if (sscanf(name, "frame-%d.", &named) == 1 && index >= 0 &&
	    index != named)
		return glint_error_set(EINVAL,
				       "%s: holds frame %d of the bracket, "
				       "not frame %d: a frame was copied or "
				       "swapped",
				       path, index, named);
	if (t > 0 && fabs(f->exposure_s - t) > 1e-6 * t)
		return glint_error_set(EINVAL,
				       "%s: exposed %g s, but the session "
				       "lists %g s for it: a frame was copied "
				       "or swapped",
				       path, f->exposure_s, t);
	/* the checksum session.json recorded as the frame was taken: a
	 * frame of another session (same index, exposure and place in the
	 * camera's sequence) has other pixels */
	const json_t *crc = json_object_get(listed, "pixels_crc32");
	if (json_is_integer(crc) &&
	    (json_int_t)pixels_crc != json_integer_value(crc))
		return glint_error_set(
			EINVAL,
			"%s: its pixels (CRC-32 %08x) are not "
			"the ones this session recorded for "
			"%s (%08llx): a frame from another "
			"session was copied in",
			path, pixels_crc, name,
			(unsigned long long)json_integer_value(crc));
	if (prev && f->sequence && prev->sequence &&
	    f->sequence <= prev->sequence)
		return glint_error_set(EINVAL,
				       "%s: camera sequence %llu after %llu: "
				       "frames out of order",
				       path, (unsigned long long)f->sequence,
				       (unsigned long long)prev->sequence);
	return 0;
}

/* Each frame session.json lists, read and checked in order, to fn (which
 * owns it); fn's error or the first bad frame stops it. */
typedef int (*frame_fn)(struct glint_frame *f, int i, int n, void *ctx);

static int each_frame(const char *dir, frame_fn fn, void *ctx)
{
	char path[GLINT_PATH_MAX];
	struct glint_frame prev = { 0 };
	json_t *doc, *list;
	int ret;

	ret = glint_path_join(path, sizeof(path), dir, "session.json");
	if (ret < 0)
		return ret;
	ret = glint_json_load(path, &doc);
	if (ret < 0)
		return ret;
	list = json_object_get(doc, "frames");
	if (!json_is_array(list) || json_array_size(list) == 0) {
		json_decref(doc);
		return glint_error_set(EINVAL, "%s: no frames listed", path);
	}
	int n = (int)json_array_size(list);
	for (int i = 0; i < n && ret == 0; i++) {
		struct glint_frame f = { 0 };
		const char *name = json_string_value(json_object_get(
			json_array_get(list, (size_t)i), "file"));
		if (!name || strchr(name, '/')) {
			ret = glint_error_set(EINVAL,
					      "%s: frames[%d].file: expected a "
					      "file name in the session",
					      path, i);
			break;
		}
		ret = glint_path_join(path, sizeof(path), dir, name);
		if (!ret)
			ret = frame_in_place(path, name,
					     json_array_get(list, (size_t)i),
					     &f, i ? &prev : NULL);
		if (ret < 0) {
			glint_frame_release(&f);
			break;
		}
		prev = f;
		prev.data = NULL;
		ret = fn(&f, i, n, ctx);
	}
	json_decref(doc);
	return ret;
}

struct load_ctx {
	struct glint_frame *frames;
	int n;
};

static int load_one(struct glint_frame *f, int i, int n, void *ctx)
{
	struct load_ctx *c = ctx;
	if (!c->frames && !(c->frames = calloc((size_t)n, sizeof(*f)))) {
		glint_frame_release(f);
		return glint_error_set(ENOMEM, "out of memory");
	}
	c->frames[i] = *f;
	c->n = i + 1;
	return 0;
}

int glint_session_load_frames(const char *dir, struct glint_frame **frames,
			      int *n)
{
	struct load_ctx c = { NULL, 0 };
	int ret = each_frame(dir, load_one, &c);
	*frames = c.frames;
	*n = c.n;
	return ret;
}

void glint_frames_free(struct glint_frame *f, int n)
{
	for (int i = 0; f && i < n; i++)
		glint_frame_release(&f[i]);
	free(f);
}

/* Camera RGB to the output's RGB by the 3 x 3 matrix m (row-major): the
 * radiance, and the variance as of a sum of independent terms (each
 * channel's variance weighted by the square of its coefficient). */
static void to_rgb(struct glint_image *rad, struct glint_image *var,
		   const double m[9])
{
	size_t np = (size_t)rad->width * rad->height;
	for (size_t p = 0; p < np; p++) {
		float *x = rad->data + 3 * p, *v = var->data + 3 * p;
		double y[3], w[3];
		int ok = v[0] > 0 && v[1] > 0 && v[2] > 0;
		for (int i = 0; i < 3; i++) {
			y[i] = w[i] = 0;
			for (int j = 0; j < 3; j++) {
				y[i] += m[3 * i + j] * x[j];
				w[i] += m[3 * i + j] * m[3 * i + j] * v[j];
			}
		}
		for (int i = 0; i < 3; i++) {
			x[i] = (float)y[i];
			v[i] = ok ? (float)w[i] : 0;
		}
	}
}

static int write_merge(struct glint_raw_hdr *raw, const double *rgb_cam,
		       const char *out, const char *const names[5], int *width,
		       int *height, long *valid_px,
		       struct glint_image **radiance)
{
	struct glint_image *rad = NULL, *var = NULL, *valid = NULL;
	char path[GLINT_PATH_MAX];
	int ret = glint_hdr_demosaic(raw, &rad, &var, &valid);

	glint_raw_hdr_release(raw);
	if (ret == 0 && rgb_cam)
		to_rgb(rad, var, rgb_cam);
	if (ret == 0 && mkdir(out, 0777) < 0 && errno != EEXIST)
		ret = glint_error_set(errno, "%s: %s", out, strerror(errno));
	*valid_px = 0;
	if (ret == 0) {
		size_t np = (size_t)rad->width * rad->height * 3;
		for (size_t i = 0; i < np; i += 3)
			*valid_px += valid->data[i] > 0;
		*width = rad->width;
		*height = rad->height;
	}
	/* In order, each image freed once written; the weights are the
	 * variance image turned into 1 / variance (0 where invalid) in
	 * place. */
	struct glint_image *imgs[] = { rad, var, var, valid, rad };
	for (int i = 0; i < 5 && ret == 0; i++) {
		struct glint_write_opts wo = { .auto_expose = i == 4 };
		if (i == 2) {
			size_t np = (size_t)var->width * var->height * 3;
			for (size_t k = 0; k < np; k++)
				var->data[k] =
					var->data[k] > 0 ? 1 / var->data[k] : 0;
		}
		ret = glint_path_join(path, sizeof(path), out, names[i]);
		if (!ret)
			ret = glint_image_write(path, imgs[i], &wo);
		if (i == 2) {
			glint_image_free(var);
			var = NULL;
		} else if (i == 3) {
			glint_image_free(valid);
			valid = NULL;
		}
	}
	if (radiance && ret == 0)
		*radiance = rad;
	else
		glint_image_free(rad);
	glint_image_free(var);
	glint_image_free(valid);
	return ret;
}

int glint_hdr_write(struct glint_raw_hdr *raw, const char *out,
		    const char *const names[5], int *width, int *height,
		    long *valid_px, struct glint_image **radiance)
{
	return write_merge(raw, NULL, out, names, width, height, valid_px,
			   radiance);
}

int glint_hdr_merge_write(struct glint_frame *frames, int n,
			  const struct glint_noise_model *nm,
			  const double *rgb_cam, const char *out,
			  const char *const names[5],
			  struct glint_hdr_report *rep, int *width, int *height,
			  long *valid_px, struct glint_image **radiance)
{
	struct glint_hdr_stream *st;
	struct glint_raw_hdr raw;
	int ret = glint_hdr_stream_new(nm, &st);

	if (n < 1 && ret == 0)
		ret = glint_error_set(EINVAL, "HDR merge: no frames");
	for (int i = 0; i < n; i++) {
		if (ret == 0)
			ret = glint_hdr_stream_add(st, &frames[i]);
		glint_frame_release(&frames[i]);
	}
	if (ret == 0)
		ret = glint_hdr_stream_finish(st, &raw, rep);
	glint_hdr_stream_free(st);
	if (ret < 0)
		return ret;
	return write_merge(&raw, rgb_cam, out, names, width, height, valid_px,
			   radiance);
}

static int fold_one(struct glint_frame *f, int i, int n, void *ctx)
{
	(void)i;
	(void)n;
	int ret = glint_hdr_stream_add(ctx, f);
	glint_frame_release(f);
	return ret;
}

int glint_session_merge_write(const char *dir,
			      const struct glint_noise_model *nm,
			      const char *out, const char *const names[5],
			      struct glint_hdr_report *rep, int *width,
			      int *height, long *valid_px)
{
	struct glint_hdr_stream *st;
	struct glint_raw_hdr raw;
	int ret = glint_hdr_stream_new(nm, &st);

	if (ret == 0)
		ret = each_frame(dir, fold_one, st);
	if (ret == 0)
		ret = glint_hdr_stream_finish(st, &raw, rep);
	glint_hdr_stream_free(st);
	if (ret < 0)
		return ret;
	return glint_hdr_write(&raw, out, names, width, height, valid_px, NULL);
}

int glint_session_fit_inputs(const char *dir,
			     struct glint_session_fit_files *fs)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	json_t *doc;
	int ret;

	if (stat(dir, &st) < 0 || !S_ISDIR(st.st_mode))
		return glint_error_set(ENOENT,
				       "%s: not a capture session folder "
				       "(give SCENE.json and PHOTO, or a "
				       "session)",
				       dir);
	ret = glint_path_join(path, sizeof(path), dir, GLINT_SESSION_JSON);
	if (!ret)
		ret = glint_json_load(path, &doc);
	if (ret < 0)
		return ret;
	const char *status = json_string_value(json_object_get(doc, "status"));
	const char *kind = json_string_value(json_object_get(doc, "kind"));
	const char *stage = json_string_value(json_object_get(doc, "stage"));
	const char *why = json_string_value(json_object_get(doc, "error"));
	if (!status || strcmp(status, "complete") != 0 || !kind ||
	    strcmp(kind, "sample") != 0) {
		ret = glint_error_set(
			EINVAL,
			"%s: a %s %s session%s%s%s%s%s: expected a "
			"complete sample session%s",
			dir, status ? status : "(no status)",
			kind ? kind : "(no kind)",
			stage ? " (stopped at its " : "", stage ? stage : "",
			stage && why ? " stage: " : "", stage && why ? why : "",
			stage ? ")" : "",
			kind && !strcmp(kind, "probe")
				? " (a probe session is the "
				  "light of a sample's scene; "
				  "fit the sample captured "
				  "after it)"
				: "");
		json_decref(doc);
		return ret;
	}
	json_decref(doc);
	ret = glint_path_join(fs->scene, sizeof(fs->scene), dir,
			      GLINT_SESSION_SCENE);
	if (!ret)
		ret = glint_path_join(fs->photo, sizeof(fs->photo), dir,
				      GLINT_SESSION_SAMPLE);
	if (!ret)
		ret = glint_path_join(fs->weights, sizeof(fs->weights), dir,
				      GLINT_SESSION_SAMPLE_WEIGHTS);
	if (!ret)
		ret = glint_path_join(fs->out, sizeof(fs->out), dir,
				      GLINT_SESSION_FIT);
	if (ret < 0)
		return ret;
	if (stat(fs->scene, &st) < 0)
		return glint_error_set(ENOENT,
				       "%s: no scene.json (the sample was "
				       "captured without a probe or optics; "
				       "capture the probe, then the sample, "
				       "or write a scene, docs/scene.md)",
				       dir);
	if (stat(fs->photo, &st) < 0)
		return glint_error_set(ENOENT,
				       "%s: no %s (the bracket was not merged)",
				       dir, GLINT_SESSION_SAMPLE);
	if (stat(fs->weights, &st) < 0)
		fs->weights[0] = '\0';
	return 0;
}
