/* SPDX-License-Identifier: MIT */
#include "core/clock.h"
#include "image.h"

#include "error.h"
#include "formats.h"
#include "log.h"
#include "path.h"
#include "tiff.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Large enough for any real sensor or probe, small enough to be sane. */
#define GLINT_IMAGE_MAX_DIM 65536

struct glint_image *glint_image_new(int width, int height)
{
	struct glint_image *img;

	if (width <= 0 || height <= 0 || width > GLINT_IMAGE_MAX_DIM ||
	    height > GLINT_IMAGE_MAX_DIM) {
		glint_error_set(EINVAL,
				"image size %dx%d: expected 1..%d on each side",
				width, height, GLINT_IMAGE_MAX_DIM);
		return NULL;
	}
	img = calloc(1, sizeof(*img));
	if (!img)
		goto err_oom;
	img->data = calloc((size_t)width * height * 3, sizeof(float));
	if (!img->data)
		goto err_data;
	img->width = width;
	img->height = height;
	return img;

err_data:
	free(img);
err_oom:
	glint_error_set(ENOMEM, "out of memory for a %dx%d image", width,
			height);
	return NULL;
}

static long long env_limit(const char *name, long long fallback, long long unit)
{
	const char *v = getenv(name);
	char *end;
	if (!v || !*v)
		return fallback;
	errno = 0;
	long long n = strtoll(v, &end, 10);
	if (errno || *end || n <= 0 || n > LLONG_MAX / unit) {
		glint_log_warn("%s=%s: expected a positive whole number; "
			       "using %lld",
			       name, v, fallback / unit);
		return fallback;
	}
	return n * unit;
}

long long glint_image_max_pixels(void)
{
	return env_limit("GLINT_MAX_PIXELS", 1LL << 27, 1);
}

long long glint_image_max_bytes(void)
{
	return env_limit("GLINT_MAX_IMAGE_MB", 2048LL << 20, 1LL << 20);
}

long long glint_file_bytes_left(FILE *fp)
{
	struct stat st;
	long pos = ftell(fp);
	if (pos < 0 || fstat(fileno(fp), &st) < 0 || !S_ISREG(st.st_mode))
		return -1;
	return st.st_size > pos ? (long long)st.st_size - pos : 0;
}

long long glint_file_size(const char *path)
{
	struct stat st;
	return stat(path, &st) == 0 && S_ISREG(st.st_mode)
		       ? (long long)st.st_size
		       : -1;
}

int glint_image_size_check(const char *path, const char *field, long long w,
			   long long h, long long have_bytes, double need_bytes)
{
	if (w <= 0 || h <= 0 || w > GLINT_IMAGE_MAX_DIM ||
	    h > GLINT_IMAGE_MAX_DIM)
		return glint_error_set(EINVAL,
				       "%s: %s says %lldx%lld: expected 1..%d "
				       "on each side",
				       path, field, w, h, GLINT_IMAGE_MAX_DIM);
	long long px = w * h, max_px = glint_image_max_pixels();
	long long max_b = glint_image_max_bytes();
	if (px > max_px)
		return glint_error_set(EFBIG,
				       "%s: %s says %lldx%lld = %lld pixels, "
				       "above the limit of %lld "
				       "(GLINT_MAX_PIXELS)",
				       path, field, w, h, px, max_px);
	if (px * 12 > max_b)
		return glint_error_set(EFBIG,
				       "%s: %s says %lldx%lld, %lld MiB as "
				       "floats, above the limit of %lld MiB "
				       "(GLINT_MAX_IMAGE_MB)",
				       path, field, w, h, (px * 12) >> 20,
				       max_b >> 20);
	if (have_bytes >= 0 && (double)have_bytes < need_bytes)
		return glint_error_set(EINVAL,
				       "%s: %s says %lldx%lld, which needs at "
				       "least %.0f bytes of data, but the "
				       "file holds %lld",
				       path, field, w, h, need_bytes,
				       have_bytes);
	return 0;
}

void glint_image_free(struct glint_image *img)
{
	if (!img)
		return;
	free(img->data);
	free(img);
}

struct glint_image *glint_image_dup(const struct glint_image *img)
{
	struct glint_image *r = glint_image_new(img->width, img->height);

	if (r)
		memcpy(r->data, img->data,
		       (size_t)img->width * img->height * 3 * sizeof(float));
	return r;
}

int glint_image_check_finite(const struct glint_image *img, const char *what,
			     int nonneg)
{
	return glint_image_check_finite_at(img, what, nonneg, 0, 0);
}

int glint_image_check_finite_at(const struct glint_image *img, const char *what,
				int nonneg, int x0, int y0)
{
	size_t n = (size_t)img->width * img->height * 3, bad = 0, first = 0;

	for (size_t i = 0; i < n; i++) {
		float v = img->data[i];
		if (!isfinite(v) || (nonneg && v < 0)) {
			if (!bad)
				first = i;
			bad++;
		}
	}
	if (!bad)
		return 0;
	static const char chan[] = "RGB";
	size_t px = first / 3;
	return glint_error_set(
		EINVAL,
		"%s: pixel (%zu, %zu) channel %c is %g: expected a finite%s "
		"value (%zu bad values in all)",
		what, x0 + px % img->width, y0 + px / img->width,
		chan[first % 3], (double)img->data[first],
		nonneg ? ", non-negative" : "", bad);
}

const char *glint_path_ext(const char *path, char *buf, size_t n)
{
	const char *dot = strrchr(path, '.');
	const char *slash = strrchr(path, '/');
	size_t i = 0;

	if (!dot || (slash && dot < slash) || n == 0) {
		if (n)
			buf[0] = '\0';
		return buf;
	}
	for (dot++; *dot && i + 1 < n; dot++)
		buf[i++] = (char)tolower((unsigned char)*dot);
	buf[i] = '\0';
	return buf;
}

static int image_read(const char *path, struct glint_image **out)
{
	char ext[16];

	*out = NULL;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "exr"))
		return glint_exr_read(path, out);
	if (!strcmp(ext, "hdr") || !strcmp(ext, "pic") || !strcmp(ext, "rgbe"))
		return glint_rgbe_read(path, out);
	if (!strcmp(ext, "pfm"))
		return glint_pfm_read(path, out);
	if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		return glint_tiff_read(path, out);
	if (!strcmp(ext, "png") || !strcmp(ext, "tga") || !strcmp(ext, "jpg") ||
	    !strcmp(ext, "jpeg") || !strcmp(ext, "bmp"))
		return glint_ldr_read_image(path, out);
	return glint_error_set(EINVAL,
			       "%s: unknown image extension '.%s': expected "
			       ".exr, .hdr, .pic, .pfm, .tif (HDR) or .png, "
			       ".tga, .jpg, .bmp (8-bit)",
			       path, ext);
}

int glint_image_read(const char *path, struct glint_image **out)
{
	double t0 = glint_clock_monotonic();
	/* the format libraries open the file by name: a FIFO or a device
	 * would block them forever */
	int ret = glint_check_regular(path);

	*out = NULL;
	if (ret == 0)
		ret = image_read(path, out);
	if (ret == 0)
		glint_log_debug("read %s: %dx%d in %.3f s", path, (*out)->width,
				(*out)->height, glint_clock_monotonic() - t0);
	return ret;
}

int glint_image_window_check(const char *path,
			     const struct glint_image_window *win, int w, int h)
{
	if (win->x < 0 || win->y < 0 || win->width < 1 || win->height < 1 ||
	    win->x > w - win->width || win->y > h - win->height)
		return glint_error_set(EINVAL,
				       "%s: window %dx%d at (%d, %d) is not "
				       "inside the %dx%d image",
				       path, win->width, win->height, win->x,
				       win->y, w, h);
	return 0;
}

int glint_image_window_take(const char *path,
			    const struct glint_image_window *win,
			    struct glint_image **img)
{
	int ret = glint_image_window_check(path, win, (*img)->width,
					   (*img)->height);
	struct glint_image *c = ret ? NULL
				    : glint_image_crop(*img, win->x, win->y,
						       win->width, win->height);

	if (!ret && !c)
		ret = glint_error_set(ENOMEM, "out of memory");
	glint_image_free(*img);
	*img = c;
	return ret;
}

int glint_image_read_window(const char *path, int frame_width, int frame_height,
			    const struct glint_image_window *win,
			    struct glint_image **out, int *cropped)
{
	char ext[16];
	int w = 0, h = 0, ret;

	*out = NULL;
	if ((ret = glint_check_regular(path)) < 0)
		return ret;
	*cropped = 0;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "exr")) {
		ret = glint_exr_size(path, &w, &h);
		if (ret == 0 && (w != frame_width || h != frame_height))
			return glint_image_read(path, out);
		if (ret == 0)
			ret = glint_exr_read_window(path, win, out);
		*cropped = ret == 0;
		if (ret == 0)
			glint_log_debug("read %s: its %dx%d window at (%d, %d)",
					path, win->width, win->height, win->x,
					win->y);
		return ret;
	}
	ret = glint_image_read(path, out);
	if (ret < 0 || (*out)->width != frame_width ||
	    (*out)->height != frame_height)
		return ret;
	ret = glint_image_window_take(path, win, out);
	*cropped = ret == 0;
	return ret;
}

int glint_image_write(const char *path, const struct glint_image *img,
		      const struct glint_write_opts *opts)
{
	static const struct glint_write_opts defaults = { .auto_expose = 1 };
	char ext[16];

	if (!opts)
		opts = &defaults;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "exr"))
		return glint_exr_write(path, img, opts);
	if (opts->frame_width)
		return glint_error_set(EINVAL,
				       "%s: a data window inside a larger "
				       "frame needs an .exr file",
				       path);
	if (!strcmp(ext, "hdr") || !strcmp(ext, "pic"))
		return glint_rgbe_write(path, img);
	if (!strcmp(ext, "pfm"))
		return glint_pfm_write(path, img);
	if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		return glint_tiff_write(path, img);
	if (!strcmp(ext, "png"))
		return glint_png_write(
			path, img, opts->auto_expose ? NAN : opts->exposure);
	return glint_error_set(EINVAL,
			       "%s: unknown image extension '.%s': expected "
			       ".exr, .hdr, .pfm, .tif or .png",
			       path, ext);
}

struct glint_image *glint_image_crop(const struct glint_image *src, int x,
				     int y, int w, int h)
{
	struct glint_image *d = glint_image_new(w, h);
	for (int j = 0; d && j < h; j++)
		memcpy(glint_image_px(d, 0, j), glint_image_px(src, x, y + j),
		       (size_t)w * 3 * sizeof(float));
	return d;
}

struct glint_image *glint_image_downsample(const struct glint_image *src, int f)
{
	int w = src->width / f, h = src->height / f;
	struct glint_image *d = glint_image_new(w, h);
	for (int y = 0; d && y < h; y++)
		for (int x = 0; x < w; x++)
			for (int c = 0; c < 3; c++) {
				double s = 0;
				for (int j = 0; j < f; j++)
					for (int i = 0; i < f; i++)
						s += glint_image_px(
							src, f * x + i,
							f * y + j)[c];
				glint_image_px(d, x, y)[c] =
					(float)(s / (f * f));
			}
	return d;
}

int glint_image_encoded(const char *path)
{
	static const char *const ldr[] = { "png", "tga", "jpg", "jpeg", "bmp" };
	char ext[16];

	glint_path_ext(path, ext, sizeof(ext));
	for (int i = 0; i < 5; i++)
		if (!strcmp(ext, ldr[i]))
			return 1;
	return 0;
}

int glint_radiance_check(const char *path, int srgb)
{
	if (srgb || !glint_image_encoded(path))
		return 0;
	return glint_error_set(EINVAL,
			       "%s: an 8-bit image holds camera-encoded "
			       "values, not radiance: merge a bracket to HDR "
			       "(glint hdr), or give --srgb to take it as "
			       "sRGB-encoded (highlights stay clipped)",
			       path);
}

void glint_image_srgb_to_linear(struct glint_image *img)
{
	for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++) {
		float v = img->data[i];
		img->data[i] = v <= 0.04045f
				       ? v / 12.92f
				       : powf((v + 0.055f) / 1.055f, 2.4f);
	}
}

int glint_image_read_radiance(const char *path, int srgb,
			      struct glint_image **out)
{
	int ret = glint_radiance_check(path, srgb);

	*out = NULL;
	if (ret == 0)
		ret = glint_image_read(path, out);
	if (ret == 0 && glint_image_encoded(path))
		glint_image_from_srgb(path, *out);
	return ret;
}

void glint_image_from_srgb(const char *path, struct glint_image *img)
{
	glint_image_srgb_to_linear(img);
	glint_log_warn("%s: 8-bit, taken as sRGB-encoded (--srgb): "
		       "highlights above its white point are clipped, so its "
		       "brightest light or highlight is too dim",
		       path);
}
