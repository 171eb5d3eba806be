/* SPDX-License-Identifier: MIT */
#include "capture/hdr/frame_file.h"

#include "capture/hdr/dng.h"

#include "core/formats.h"
#include "core/error.h"
#include "core/path.h"

#include <jansson.h>
#include <png.h>
#include <zlib.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* CRC-32 (zlib's) of the samples as the PNG stores them. */
static uint32_t pixels_crc32(const uint16_t *data, size_t n)
{
	uint8_t buf[4096];
	uLong crc = crc32(0L, Z_NULL, 0);
	for (size_t i = 0; i < n;) {
		size_t k = 0;
		for (; k < sizeof(buf) && i < n; k += 2, i++) {
			buf[k] = (uint8_t)(data[i] >> 8);
			buf[k + 1] = (uint8_t)(data[i] & 0xff);
		}
		crc = crc32(crc, buf, (uInt)k);
	}
	return (uint32_t)crc;
}

uint32_t glint_frame_pixels_crc32(const struct glint_frame *f)
{
	return pixels_crc32(f->data, (size_t)f->width * f->height *
					     (f->channels == 3 ? 3 : 1));
}

char *glint_frame_metadata_json(const struct glint_frame *f, int index)
{
	size_t n = (size_t)f->width * f->height * (f->channels == 3 ? 3 : 1);
	json_t *o = json_pack(
		"{s:i, s:i, s:i, s:s, s:s, s:i, s:i, s:b, s:f, s:f, s:f, s:f, "
		"s:f, s:I, s:I}",
		"index", index, "width", f->width, "height", f->height,
		"format", f->format, "source_format", f->source_format,
		"channels", f->channels, "bit_depth", f->bit_depth, "linear",
		f->linear, "exposure_s", f->exposure_s, "gain", f->gain,
		"black_level", f->black_level, "t_start", f->t_start, "t_end",
		f->t_end, "sequence", (json_int_t)f->sequence, "pixels_crc32",
		(json_int_t)pixels_crc32(f->data, n));
	char *s = o ? json_dumps(o, JSON_INDENT(2) | JSON_REAL_PRECISION(17))
		    : NULL;
	json_decref(o);
	return s;
}

/* A row of a frame as PNG wants it: 16-bit big-endian samples. */
static void frame_row(void *ctx, int y, uint8_t *row)
{
	const struct glint_frame *f = ctx;
	int n = f->width * (f->channels == 3 ? 3 : 1);
	const uint16_t *s = f->data + (size_t)y * n;
	for (int i = 0; i < n; i++) {
		row[2 * i] = (uint8_t)(s[i] >> 8);
		row[2 * i + 1] = (uint8_t)(s[i] & 0xff);
	}
}

int glint_frame_write(const char *path, const struct glint_frame *f,
		      const char *meta)
{
	char ext[16];
	if (!strcmp(glint_path_ext(path, ext, sizeof(ext)), "dng"))
		return glint_dng_write(path, f, meta);
	/* Level 1: raw sensor data barely compresses; time matters more. */
	struct glint_png_layout l = {
		16, f->channels == 3 ? 3 : 1, 0, 1, "glint:frame", meta
	};
	return glint_png_write_rows(path, f->width, f->height, &l, frame_row,
				    (void *)f);
}

static int meta_from_text(const char *path, const char *text,
			  struct glint_frame *f, int *index, json_int_t *crc)
{
	json_error_t e;
	json_t *o = json_loads(text, 0, &e);
	const char *fmt = NULL, *src = "";
	int lin = 1;
	json_int_t seq = 0;

	if (!o ||
	    json_unpack(o, "{s:s, s?s, s:i, s?b, s:F, s:F, s:F, s?I, s?i, s?I}",
			"format", &fmt, "source_format", &src, "bit_depth",
			&f->bit_depth, "linear", &lin, "exposure_s",
			&f->exposure_s, "gain", &f->gain, "black_level",
			&f->black_level, "sequence", &seq, "index", index,
			"pixels_crc32", crc) != 0) {
		json_decref(o);
		return glint_error_set(EINVAL,
				       "%s: glint:frame metadata is missing "
				       "or incomplete",
				       path);
	}
	snprintf(f->format, sizeof(f->format), "%s", fmt);
	snprintf(f->source_format, sizeof(f->source_format), "%s", src);
	f->linear = lin;
	f->sequence = (uint64_t)seq;
	json_decref(o);
	return 0;
}

/* The checks every frame file gets: pixels against their checksum. */
static int check_crc(const char *path, const struct glint_frame *f,
		     json_int_t crc, uint32_t *pixels_crc)
{
	uint32_t got = pixels_crc32(f->data,
				    (size_t)f->width * f->height * f->channels);
	if (pixels_crc)
		*pixels_crc = got;
	if (crc >= 0 && got != (uint32_t)crc)
		return glint_error_set(EINVAL,
				       "%s: the pixels do not match their "
				       "checksum (CRC-32 %08x, its metadata "
				       "says %08x): the frame was edited or "
				       "damaged",
				       path, got, (uint32_t)crc);
	return 0;
}

static int frame_read_dng(const char *path, struct glint_frame *f, int *index,
			  uint32_t *pixels_crc)
{
	char *meta = NULL, layout[16];
	int idx = -1, ret = glint_dng_read(path, f, &meta);
	json_int_t crc = -1;

	if (ret < 0)
		return ret;
	snprintf(layout, sizeof(layout), "%s", f->format);
	ret = meta ? meta_from_text(path, meta, f, &idx, &crc)
		   : glint_error_set(EINVAL,
				     "%s: no glint:frame metadata (its "
				     "ImageDescription): not a frame glint "
				     "wrote",
				     path);
	if (ret == 0 && strcmp(layout, f->format))
		ret = glint_error_set(EINVAL,
				      "%s: its DNG tags say %s, its metadata "
				      "%s",
				      path, layout, f->format);
	if (ret == 0)
		ret = check_crc(path, f, crc, pixels_crc);
	free(meta);
	if (ret < 0)
		glint_frame_release(f);
	else if (index)
		*index = idx;
	return ret;
}

int glint_frame_read(const char *path, struct glint_frame *f, int *index)
{
	return glint_frame_read_crc(path, f, index, NULL);
}

int glint_frame_read_crc(const char *path, struct glint_frame *f, int *index,
			 uint32_t *pixels_crc)
{
	if (glint_dng_is_tiff(path))
		return frame_read_dng(path, f, index, pixels_crc);
	int idx = -1;
	json_int_t crc = -1;
	FILE *fp = glint_fopen_regular(path, "rb");
	png_structp png = NULL;
	png_infop info = NULL;
	uint8_t *volatile row = NULL; /* survives longjmp */
	int ret = 0;

	memset(f, 0, sizeof(*f));
	if (!fp)
		return -errno;
	ret = glint_png_check_chunks(path);
	if (ret < 0) {
		fclose(fp);
		return ret;
	}
	png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	if (png)
		info = png_create_info_struct(png);
	if (!png || !info) {
		ret = glint_error_set(ENOMEM, "%s: libpng setup failed", path);
		goto out;
	}
	if (setjmp(png_jmpbuf(png))) {
		ret = glint_error_set(EIO,
				      "%s: not a PNG, or truncated or "
				      "corrupt",
				      path);
		goto out;
	}
	png_init_io(png, fp);
	png_read_info(png, info);
	int depth = png_get_bit_depth(png, info),
	    type = png_get_color_type(png, info);
	int ch = type == PNG_COLOR_TYPE_RGB ? 3 : 1;
	if (depth != 16 ||
	    (type != PNG_COLOR_TYPE_GRAY && type != PNG_COLOR_TYPE_RGB)) {
		ret = glint_error_set(EINVAL,
				      "%s: %d-bit PNG of colour type %d: "
				      "expected a 16-bit grey or RGB glint "
				      "frame",
				      path, depth, type);
		goto out;
	}
	png_textp texts;
	int ntext = 0;
	png_get_text(png, info, &texts, &ntext);
	ret = -EINVAL;
	for (int i = 0; i < ntext; i++)
		if (!strcmp(texts[i].key, "glint:frame"))
			ret = meta_from_text(path, texts[i].text, f, &idx,
					     &crc);
	if (ret == -EINVAL && !ntext)
		ret = glint_error_set(EINVAL, "%s: no glint:frame metadata",
				      path);
	if (ret < 0)
		goto out;
	f->width = (int)png_get_image_width(png, info);
	f->height = (int)png_get_image_height(png, info);
	f->channels = ch;
	/* Deflate packs at most 1032 bytes into one byte of the file. */
	ret = glint_image_size_check(path, "IHDR", f->width, f->height,
				     glint_file_size(path),
				     2.0 * ch * f->width * f->height / 1032);
	if (ret < 0)
		goto out;
	f->data = malloc((size_t)f->width * f->height * ch * sizeof(uint16_t));
	row = malloc((size_t)f->width * ch * 2);
	if (!f->data || !row) {
		ret = glint_error_set(ENOMEM, "%s: out of memory", path);
		goto out;
	}
	for (int y = 0; y < f->height; y++) {
		png_read_row(png, row, NULL);
		uint16_t *d = f->data + (size_t)y * f->width * ch;
		for (int i = 0; i < f->width * ch; i++)
			d[i] = (uint16_t)(row[2 * i] << 8 | row[2 * i + 1]);
	}
	png_read_end(png, NULL);
	ret = check_crc(path, f, crc, pixels_crc);
	if (index)
		*index = idx;
out:
	if (png)
		png_destroy_read_struct(&png, info ? &info : NULL, NULL);
	free(row);
	fclose(fp);
	if (ret < 0)
		glint_frame_release(f);
	return ret;
}
