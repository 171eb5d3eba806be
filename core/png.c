/* SPDX-License-Identifier: MIT */
/* 8-bit sRGB PNG previews through libpng; tone map stated in formats.h. */
#include "atomic_file.h"
#include "error.h"
#include "path.h"
#include "formats.h"
#include "output.h"
#include "vec.h"

#include <png.h>

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int cmp_float(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

double glint_png_auto_exposure(const struct glint_image *img)
{
	size_t n = (size_t)img->width * img->height, k = 0;
	float *lum = malloc(n * sizeof(float));
	double ev = 0;

	if (!lum)
		return 0;
	for (size_t i = 0; i < n; i++) {
		const float *p = img->data + 3 * i;
		double l = rgb_luminance(p[0], p[1], p[2]);
		if (l > 0 && isfinite(l))
			lum[k++] = (float)l;
	}
	if (k) {
		qsort(lum, k, sizeof(float), cmp_float);
		double p99 = lum[(size_t)(0.99 * (double)(k - 1))];
		ev = log2(0.9 / p99);
	}
	free(lum);
	return ev;
}

uint8_t glint_tonemap_srgb8(double v)
{
	if (!(v > 0))
		return 0;
	if (v >= 1)
		return 255;
	v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
	return (uint8_t)lrint(v * 255.0);
}

/* 8-bit sRGB previews. */
static const struct glint_png_layout rgb8 = { 8, 3, 1, 0, NULL, NULL };

int glint_png_write_rows(const char *path, int w, int h,
			 const struct glint_png_layout *l,
			 void (*get_row)(void *ctx, int y, uint8_t *row),
			 void *ctx)
{
	struct glint_atomic_file af;
	png_structp png = NULL;
	png_infop info = NULL;
	uint8_t *row;
	int ret;

	row = malloc((size_t)w * l->channels * (l->bit_depth / 8));
	if (!row)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	ret = glint_atomic_open(&af, path);
	if (ret < 0) {
		free(row);
		return ret;
	}
	png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	if (png)
		info = png_create_info_struct(png);
	if (!png || !info) {
		ret = glint_error_set(ENOMEM, "%s: libpng setup failed", path);
		goto err;
	}
	if (setjmp(png_jmpbuf(png))) {
		ret = glint_error_set(EIO, "%s: libpng failed while writing",
				      path);
		goto err;
	}
	png_init_io(png, af.fp);
	if (l->fast)
		png_set_compression_level(png, 1);
	png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, l->bit_depth,
		     l->channels == 3 ? PNG_COLOR_TYPE_RGB
				      : PNG_COLOR_TYPE_GRAY,
		     PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
		     PNG_FILTER_TYPE_DEFAULT);
	if (l->srgb)
		png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
	png_text text[2];
	memset(text, 0, sizeof(text));
	text[0].compression = PNG_TEXT_COMPRESSION_NONE;
	text[0].key = (png_charp) "Software";
	text[0].text = (png_charp)GLINT_OUTPUT_SOFTWARE;
	if (l->text_key) {
		text[1].compression = PNG_ITXT_COMPRESSION_NONE;
		text[1].key = (png_charp)l->text_key;
		text[1].text = (png_charp)l->text;
	}
	png_set_text(png, info, text, l->text_key ? 2 : 1);
	png_write_info(png, info);
	for (int y = 0; y < h; y++) {
		get_row(ctx, y, row);
		png_write_row(png, row);
	}
	png_write_end(png, info);
	png_destroy_write_struct(&png, &info);
	free(row);
	return glint_atomic_commit(&af);
err:
	if (png)
		png_destroy_write_struct(&png, info ? &info : NULL);
	free(row);
	glint_atomic_abort(&af);
	return ret;
}

struct tonemap_rows {
	const struct glint_image *img;
	double scale;
};

static void tonemap_row(void *ctx, int y, uint8_t *row)
{
	struct tonemap_rows *t = ctx;
	const float *p = glint_image_px(t->img, 0, y);

	for (int i = 0; i < t->img->width * 3; i++)
		row[i] = glint_tonemap_srgb8(p[i] * t->scale);
}

int glint_png_write(const char *path, const struct glint_image *img,
		    double exposure)
{
	struct tonemap_rows t = { img, 0 };

	if (isnan(exposure))
		exposure = glint_png_auto_exposure(img);
	t.scale = exp2(exposure);
	return glint_png_write_rows(path, img->width, img->height, &rgb8,
				    tonemap_row, &t);
}

struct rgb8_rows {
	int w;
	const uint8_t *px;
};

static void rgb8_row(void *ctx, int y, uint8_t *row)
{
	struct rgb8_rows *t = ctx;
	memcpy(row, t->px + (size_t)y * t->w * 3, (size_t)t->w * 3);
}

int glint_png_write_rgb8(const char *path, int w, int h, const uint8_t *px)
{
	struct rgb8_rows t = { w, px };

	return glint_png_write_rows(path, w, h, &rgb8, rgb8_row, &t);
}

int glint_png_check_chunks(const char *path)
{
	static const uint8_t sig[8] = { 137, 'P', 'N', 'G', 13, 10, 26, 10 };
	uint8_t head[8];
	long long size = glint_file_size(path), pos = 8;
	FILE *fp = glint_fopen_regular(path, "rb");
	int ret = 0;

	if (!fp)
		return -errno;
	if (size < 0 || fread(head, 1, 8, fp) != 8 || memcmp(head, sig, 8))
		goto out; /* not a PNG: libpng says so */
	while (fread(head, 1, 8, fp) == 8) {
		uint32_t len = (uint32_t)head[0] << 24 |
			       (uint32_t)head[1] << 16 |
			       (uint32_t)head[2] << 8 | head[3];
		char type[5];
		for (int i = 0; i < 4; i++)
			type[i] =
				isalpha(head[4 + i]) ? (char)head[4 + i] : '?';
		type[4] = '\0';
		if (len > 0x7fffffffu || pos + 12 + (long long)len > size) {
			ret = glint_error_set(
				EINVAL,
				"%s: chunk '%s' at byte %lld says "
				"%u bytes, but the file holds %lld",
				path, type, pos, len, size);
			break;
		}
		if (!memcmp(head + 4, "IEND", 4))
			break;
		pos += 12 + (long long)len;
		if (fseek(fp, (long)pos, SEEK_SET) < 0)
			break;
	}
out:
	fclose(fp);
	return ret;
}

int glint_png_software(const char *path, char *buf, size_t n)
{
	int ret = glint_png_check_chunks(path);
	if (ret < 0)
		return ret;
	FILE *fp = glint_fopen_regular(path, "rb");
	if (!fp)
		return -errno;
	png_structp png =
		png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!info) {
		png_destroy_read_struct(&png, NULL, NULL);
		fclose(fp);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	volatile int res = -ENOENT; /* set after setjmp */
	if (setjmp(png_jmpbuf(png))) {
		res = glint_error_set(EIO, "%s: not a readable PNG", path);
	} else {
		/* The header's chunks only (texts before the image data). */
		png_set_chunk_malloc_max(png, 1 << 20);
		png_init_io(png, fp);
		png_read_info(png, info);
		png_textp t = NULL;
		int nt = png_get_text(png, info, &t, NULL);
		for (int k = 0; k < nt; k++)
			if (!strcmp(t[k].key, "Software") && t[k].text) {
				snprintf(buf, n, "%s", t[k].text);
				res = 0;
				break;
			}
	}
	png_destroy_read_struct(&png, &info, NULL);
	fclose(fp);
	return res;
}

int glint_png_read_rgb8(const char *path, int *w, int *h, uint8_t **px)
{
	png_image img;

	*px = NULL;
	int ret = glint_png_check_chunks(path);
	if (ret < 0)
		return ret;
	memset(&img, 0, sizeof(img));
	img.version = PNG_IMAGE_VERSION;
	if (!png_image_begin_read_from_file(&img, path))
		return glint_error_set(EIO, "%s: %s", path, img.message);
	/* Deflate packs at most 1032 bytes (pixels, at 8-bit grey) into one
	 * byte of the file. */
	ret = glint_image_size_check(path, "IHDR", img.width, img.height,
				     glint_file_size(path),
				     (double)img.width * img.height / 1032);
	if (ret < 0) {
		png_image_free(&img);
		return ret;
	}
	/* No gamma handling: 8-bit in, the same 8-bit values out. */
	img.format = PNG_FORMAT_RGB;
	size_t n = PNG_IMAGE_SIZE(img);
	*px = malloc(n);
	if (!*px) {
		png_image_free(&img);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	if (!png_image_finish_read(&img, NULL, *px, 0, NULL)) {
		free(*px);
		*px = NULL;
		return glint_error_set(EIO, "%s: %s", path, img.message);
	}
	*w = (int)img.width;
	*h = (int)img.height;
	return 0;
}
