/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "capture/hdr/hdr_files.h"

#include "capture/hdr/frame_file.h"
#include "capture/hdr/hdr_response.h"
#include "capture/hdr/session_merge.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/exif.h"
#include "core/formats.h"
#include "core/output.h"
#include "core/path.h"
#include "core/plot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* "32", "1/1024", "0.5" */
static int parse_time(const char *s, double *t)
{
	char *end;
	double a = strtod(s, &end);
	if (*end == '/') {
		double b = strtod(end + 1, &end);
		a = b != 0 ? a / b : NAN;
	}
	while (*end == ' ' || *end == '\r' || *end == '\n')
		end++;
	if (*end || !(a > 0) || !isfinite(a))
		return -1;
	*t = a;
	return 0;
}

static int times_from_file(const char *file, int n, double *t, int *k)
{
	char buf[8192];
	FILE *f = glint_fopen_regular(file, "r");
	int ret = 0;

	if (!f)
		return -errno;
	while (ret == 0 && *k <= n && fgets(buf, sizeof(buf), f)) {
		if (buf[0] == '\n' || buf[0] == '#')
			continue;
		if (*k == n || parse_time(buf, &t[*k]) < 0)
			ret = glint_error_set(EINVAL,
					      "%s: line %d: '%.40s': expected "
					      "%d positive times (seconds, "
					      "1/N allowed)",
					      file, *k + 1, buf, n);
		else
			(*k)++;
	}
	fclose(f);
	return ret;
}

static int times_from_list(const char *list, int n, double *t, int *k)
{
	char buf[8192];

	if (strlen(list) >= sizeof(buf))
		return glint_error_set(EINVAL, "--times: too long");
	memcpy(buf, list, strlen(list) + 1);
	for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
	     tok = strtok_r(NULL, ",", &save)) {
		if (*k == n || parse_time(tok, &t[*k]) < 0)
			return glint_error_set(EINVAL,
					       "--times: '%s': expected %d "
					       "positive times",
					       tok, n);
		(*k)++;
	}
	return 0;
}

int glint_exposure_times_read(const char *list, const char *file, int n,
			      double *t)
{
	int k = 0;
	int ret = file ? times_from_file(file, n, t, &k)
		       : times_from_list(list, n, t, &k);

	if (ret == 0 && k != n)
		ret = glint_error_set(EINVAL,
				      "%s: %d exposure times for %d images",
				      file ? file : "--times", k, n);
	return ret;
}

int glint_exposure_times_exif(const char *const *files, int n, double *t)
{
	for (int i = 0; i < n; i++) {
		int ret = glint_exif_exposure_time(files[i], &t[i]);
		if (ret < 0) {
			char why[512];
			snprintf(why, sizeof(why), "%s", glint_error_msg());
			return glint_error_set(-ret,
					       "%s: give the exposure times "
					       "with --times or --times-file",
					       why);
		}
	}
	return 0;
}

static int read_stack(const char *const *files, int n, uint8_t **img, int *w,
		      int *h)
{
	for (int i = 0; i < n; i++) {
		int wi, hi;
		int ret = glint_ldr_read(files[i], &wi, &hi, &img[i]);
		if (ret < 0)
			return ret;
		if (i && (wi != *w || hi != *h))
			return glint_error_set(EINVAL,
					       "%s is %dx%d, %s %dx%d: the "
					       "photos must match",
					       files[i], wi, hi, files[0], *w,
					       *h);
		*w = wi;
		*h = hi;
	}
	return 0;
}

static int write_response(const char *out, const double resp[256][3])
{
	char path[GLINT_PATH_MAX], csv[256 * 64 + 128];
	/* One comment line (numpy's loadtxt and pandas skip it): the marker
	 * of a file glint wrote (core/output.h). */
	size_t k = (size_t)snprintf(csv, sizeof(csv),
				    "# written by glint: camera response "
				    "g(z) for z = 0..255, R,G,B\n");
	int ret = glint_path_join(path, sizeof(path), out, "response.csv");

	for (int z = 0; z < 256; z++)
		k += (size_t)snprintf(csv + k, sizeof(csv) - k,
				      "%.8g,%.8g,%.8g\n", resp[z][0],
				      resp[z][1], resp[z][2]);
	return ret < 0 ? ret : glint_atomic_write_file(path, csv, k);
}

/* The response as a picture (response.png): log2 of the exposure that
 * makes each code value, per channel, relative to code 128's, against
 * the code value; labelled axes, a legend and the method's name. */
static int write_response_png(const char *out, const double resp[256][3],
			      const char *method)
{
	enum { W = 560, H = 380, L = 64, R = 16, T = 36, B = 48 };
	static const uint8_t axis[3] = { 120, 120, 120 };
	static const uint8_t grid[3] = { 225, 225, 225 };
	static const uint8_t rgb[3][3] = { { 200, 30, 30 },
					   { 30, 150, 40 },
					   { 40, 70, 210 } };
	static const char *const names[3] = { "R", "G", "B" };
	double lo = INFINITY, hi = -INFINITY, y[256][3];
	char path[GLINT_PATH_MAX], buf[64];
	struct glint_canvas cv;

	for (int z = 0; z < 256; z++)
		for (int c = 0; c < 3; c++) {
			y[z][c] = resp[z][c] > 0 ? log2(resp[z][c]) : NAN;
			if (isfinite(y[z][c])) {
				lo = fmin(lo, y[z][c]);
				hi = fmax(hi, y[z][c]);
			}
		}
	if (!(hi > lo)) {
		lo = -1;
		hi = 1;
	}
	lo = floor(lo);
	hi = ceil(hi);
	int ret = glint_path_join(path, sizeof(path), out, "response.png");
	if (ret == 0)
		ret = glint_canvas_init(&cv, W, H);
	if (ret < 0)
		return ret;
	int pw = W - L - R, ph = H - T - B;
	/* Grid and ticks: every 32 codes; every stop (or every k stops). */
	int step = (int)ceil((hi - lo) / 12);
	for (int k = (int)lo; k <= (int)hi; k += step) {
		int py = T + ph - (int)lrint((k - lo) / (hi - lo) * ph);
		glint_canvas_fill(&cv, L, py, L + pw, py, grid);
		snprintf(buf, sizeof(buf), "%d", k);
		glint_canvas_text(&cv, L - 6 - (int)strlen(buf) * 6, py - 3, 1,
				  buf);
	}
	for (int z = 0; z <= 256; z += 32) {
		int px = L + (int)lrint(fmin(z, 255) / 255.0 * pw);
		glint_canvas_fill(&cv, px, T, px, T + ph, grid);
		snprintf(buf, sizeof(buf), "%d", z < 256 ? z : 255);
		glint_canvas_text(&cv, px - (int)strlen(buf) * 3, T + ph + 6, 1,
				  buf);
	}
	glint_canvas_fill(&cv, L, T, L, T + ph, axis);
	glint_canvas_fill(&cv, L, T + ph, L + pw, T + ph, axis);
	for (int c = 0; c < 3; c++) {
		int px0 = -1, py0 = -1;
		for (int z = 0; z < 256; z++) {
			if (!isfinite(y[z][c])) {
				px0 = -1;
				continue;
			}
			int px = L + (int)lrint(z / 255.0 * pw);
			int py = T + ph -
				 (int)lrint((y[z][c] - lo) / (hi - lo) * ph);
			if (px0 >= 0)
				glint_canvas_line(&cv, px0, py0, px, py,
						  rgb[c]);
			px0 = px;
			py0 = py;
		}
		/* The legend, top left inside the plot. */
		int lx = L + 10 + 40 * c, ly = T + 8;
		glint_canvas_fill(&cv, lx, ly + 3, lx + 14, ly + 4, rgb[c]);
		glint_canvas_text(&cv, lx + 18, ly, 1, names[c]);
	}
	snprintf(buf, sizeof(buf), "CAMERA RESPONSE (%s)",
		 !strcmp(method, "debevec") ? "DEBEVEC-MALIK" : "ROBERTSON");
	glint_canvas_text(&cv, L, 3, 2, buf);
	glint_canvas_text(&cv, L + pw / 2 - 15 * 6 / 2, H - 18, 1,
			  "PIXEL CODE VALUE");
	glint_canvas_text(&cv, 4, T - 10, 1, "LOG2 EXPOSURE, CODE 128 = 0");
	ret = glint_canvas_write_png(&cv, path);
	glint_canvas_free(&cv);
	return ret;
}

static int write_ldr_result(const char *out, struct glint_image *rad,
			    struct glint_image *valid,
			    const double resp[256][3], const char *method)
{
	static const char *const names[] = { "hdr.exr", "mask.png", "hdr.png" };
	struct glint_image *imgs[] = { rad, valid, rad };
	char path[GLINT_PATH_MAX];

	if (mkdir(out, 0777) < 0 && errno != EEXIST)
		return glint_error_set(errno, "%s: %s", out, strerror(errno));
	for (int i = 0; i < 3; i++) {
		struct glint_write_opts wo = { .auto_expose = i == 2 };
		int ret = glint_path_join(path, sizeof(path), out, names[i]);
		if (ret == 0)
			ret = glint_image_write(path, imgs[i], &wo);
		if (ret < 0)
			return ret;
	}
	int ret = write_response(out, resp);
	return ret < 0 ? ret : write_response_png(out, resp, method);
}

int glint_ldr_merge_files(const char *const *files, int n, const double *t,
			  const char *method, const char *out,
			  struct glint_ldr_merge_info *info)
{
	uint8_t **img = calloc((size_t)n, sizeof(*img));
	double resp[256][3];
	struct glint_image *rad = NULL, *valid = NULL;
	int ret = img ? 0 : glint_error_set(ENOMEM, "out of memory");

	memset(info, 0, sizeof(*info));
	if (ret == 0)
		ret = read_stack(files, n, img, &info->width, &info->height);
	struct glint_ldr_stack s = { n, info->width, info->height,
				     (const uint8_t *const *)img, t };
	if (ret == 0)
		ret = glint_ldr_check_order(&s, files);
	if (ret == 0 && !strcmp(method, "debevec")) {
		struct glint_debevec_opts o;
		glint_debevec_default_opts(&o);
		ret = glint_response_debevec(&s, &o, resp);
	} else if (ret == 0) {
		ret = glint_response_robertson(&s, 30, 0.01, resp,
					       &info->iterations);
	}
	if (ret == 0)
		ret = glint_ldr_merge(&s, resp, NULL, &rad, &valid);
	if (ret == 0)
		ret = write_ldr_result(out, rad, valid, resp, method);
	for (int i = 0; img && i < n; i++)
		free(img[i]);
	free(img);
	glint_image_free(rad);
	glint_image_free(valid);
	return ret;
}

int glint_frames_read(const char *const *files, int n, const double *times,
		      struct glint_frame **frames, struct glint_raw_info *info)
{
	struct glint_raw_info k;
	int ret = 0;

	*frames = calloc((size_t)n, sizeof(**frames));
	if (!*frames)
		return glint_error_set(ENOMEM, "out of memory");
	for (int i = 0; i < n && ret == 0; i++) {
		struct glint_frame *f = &(*frames)[i];
		ret = glint_raw_file_read(files[i], f, i ? &k : info);
		if (ret < 0)
			break;
		if (i == 0)
			k = *info;
		if (times) {
			f->exposure_s = times[i];
		} else if (!k.has_exposure) {
			ret = glint_error_set(EINVAL,
					      "%s: no exposure time in its "
					      "metadata: give the bracket's "
					      "times (--times or --times-file)",
					      files[i]);
			break;
		}
		/* One camera and one colour matrix for the whole bracket. */
		int same = !strcmp(k.camera, info->camera) &&
			   !strcmp(k.reader, info->reader) &&
			   k.has_matrix == info->has_matrix;
		for (int j = 0; same && j < 9; j++)
			same = fabs(k.rgb_cam[j] - info->rgb_cam[j]) <= 1e-6;
		if (!same)
			ret = glint_error_set(EINVAL,
					      "%s: %s (read by %s) where %s "
					      "holds %s (read by %s): a "
					      "bracket's frames come from one "
					      "camera",
					      files[i], k.camera, k.reader,
					      files[0], info->camera,
					      info->reader);
	}
	return ret;
}

int glint_hdr_report_write(const char *out, int frames, int width, int height,
			   long valid_px, const struct glint_hdr_report *rep,
			   const struct glint_noise_model *nm, json_t *input,
			   json_t **doc)
{
	char path[GLINT_PATH_MAX];
	json_t *pairs = json_array();
	int ret;

	for (int i = 0; i < rep->pairs; i++)
		json_array_append_new(
			pairs,
			json_pack("{s:i, s:I, s:f}", "pair", i, "compared",
				  (json_int_t)rep->compared[i],
				  "disagree_fraction", rep->disagree[i]));
	json_t *res =
		json_pack("{s:s, s:s, s:i, s:i, s:i, s:I, s:I, s:I, s:b, s:o, "
			  "s:{s:f, s:f, s:f}}",
			  "generator", GLINT_OUTPUT_SOFTWARE, "output", out,
			  "frames", frames, "width", width, "height", height,
			  "valid_pixels", (json_int_t)valid_px, "clipped_sites",
			  (json_int_t)rep->invalid_sites, "dark_sites",
			  (json_int_t)rep->dark_sites, "moved", rep->moved,
			  "motion", pairs, "noise_model", "dn_per_electron",
			  nm->dn_per_electron, "read_noise_e", nm->read_noise_e,
			  "saturation_dn", nm->saturation_dn);
	if (res && input)
		json_object_set_new(res, "input", input);
	else
		json_decref(input);
	char *text = res ? json_dumps(res, JSON_INDENT(2)) : NULL;
	ret = text ? glint_path_join(path, sizeof(path), out, "hdr.json")
		   : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = glint_atomic_write_file(path, text, strlen(text));
	free(text);
	if (ret == 0 && doc)
		*doc = res;
	else
		json_decref(res);
	return ret;
}

json_t *glint_raw_input_json(const struct glint_raw_info *info,
			     const struct glint_frame *f0,
			     const char *times_from)
{
	json_t *m = json_array();
	for (int i = 0; i < 9 && info->has_matrix; i++)
		json_array_append_new(m, json_real(info->rgb_cam[i]));
	return json_pack(
		"{s:s, s:s, s:s, s:s, s:f, s:f, s:f, s:s, s:o}", "reader",
		info->reader, "camera", info->camera, "format", f0->format,
		"exposure_times_from", times_from, "iso", info->iso,
		"black_level", f0->black_level, "white_level",
		glint_frame_white_dn(f0), "colour",
		info->has_matrix ? "camera RGB to linear sRGB (D65 white) by "
				   "the file's colour matrix"
				 : "as the frames hold it (glint's cameras: "
				   "linear sRGB; a TIFF: its converter's "
				   "output space)",
		"matrix", info->has_matrix ? m : (json_decref(m), json_null()));
}
