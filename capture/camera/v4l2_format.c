/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "capture/camera/v4l2_format.h"

#include "capture/camera/camera.h"

#include "core/error.h"

#include <linux/videodev2.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define F(fmt, layout, bits, pack, ch, lin, rank)                              \
	{                                                                      \
		V4L2_PIX_FMT_##fmt, #fmt, layout, bits, GLINT_PACK_##pack, ch, \
			lin, rank                                              \
	}

static const struct glint_v4l2_format formats[] = {
	F(SRGGB16, "RGGB16", 16, 16, 1, 1, 100),
	F(SGRBG16, "GRBG16", 16, 16, 1, 1, 100),
	F(SGBRG16, "GBRG16", 16, 16, 1, 1, 100),
	F(SBGGR16, "BGGR16", 16, 16, 1, 1, 100),
	F(SRGGB12, "RGGB16", 12, 16, 1, 1, 81),
	F(SGRBG12, "GRBG16", 12, 16, 1, 1, 81),
	F(SGBRG12, "GBRG16", 12, 16, 1, 1, 81),
	F(SBGGR12, "BGGR16", 12, 16, 1, 1, 81),
	F(SRGGB12P, "RGGB16", 12, 12P, 1, 1, 80),
	F(SGRBG12P, "GRBG16", 12, 12P, 1, 1, 80),
	F(SGBRG12P, "GBRG16", 12, 12P, 1, 1, 80),
	F(SBGGR12P, "BGGR16", 12, 12P, 1, 1, 80),
	F(SRGGB10, "RGGB16", 10, 16, 1, 1, 61),
	F(SGRBG10, "GRBG16", 10, 16, 1, 1, 61),
	F(SGBRG10, "GBRG16", 10, 16, 1, 1, 61),
	F(SBGGR10, "BGGR16", 10, 16, 1, 1, 61),
	F(SRGGB10P, "RGGB16", 10, 10P, 1, 1, 60),
	F(SGRBG10P, "GRBG16", 10, 10P, 1, 1, 60),
	F(SGBRG10P, "GBRG16", 10, 10P, 1, 1, 60),
	F(SBGGR10P, "BGGR16", 10, 10P, 1, 1, 60),
	F(SRGGB8, "RGGB16", 8, 8, 1, 1, 40),
	F(SGRBG8, "GRBG16", 8, 8, 1, 1, 40),
	F(SGBRG8, "GBRG16", 8, 8, 1, 1, 40),
	F(SBGGR8, "BGGR16", 8, 8, 1, 1, 40),
	F(Y16, "MONO16", 16, 16, 1, 1, 30),
	F(GREY, "MONO16", 8, 8, 1, 1, 20),
	F(RGB24, "RGB16", 8, RGB24, 3, 0, 10),
	F(YUYV, "RGB16", 8, YUYV, 3, 0, 5),
};

const struct glint_v4l2_format *glint_v4l2_format_find(uint32_t fourcc)
{
	for (size_t i = 0; i < sizeof(formats) / sizeof(formats[0]); i++)
		if (formats[i].fourcc == fourcc)
			return &formats[i];
	return NULL;
}

const struct glint_v4l2_format *glint_v4l2_format_by_name(const char *name)
{
	for (size_t i = 0; i < sizeof(formats) / sizeof(formats[0]); i++)
		if (!strcmp(formats[i].name, name))
			return &formats[i];
	return NULL;
}

size_t glint_v4l2_row_bytes(const struct glint_v4l2_format *f, int width)
{
	size_t w = (size_t)width;
	switch (f->packing) {
	case GLINT_PACK_8:
		return w;
	case GLINT_PACK_16:
	case GLINT_PACK_YUYV:
		return 2 * w;
	case GLINT_PACK_10P:
		return (w + 3) / 4 * 5;
	case GLINT_PACK_12P:
		return (w + 1) / 2 * 3;
	case GLINT_PACK_RGB24:
		return 3 * w;
	}
	return 0;
}

void glint_fourcc_str(uint32_t fourcc, char buf[5])
{
	for (int i = 0; i < 4; i++) {
		char c = (char)((fourcc >> (8 * i)) & 0xff);
		buf[i] = c >= 32 && c < 127 ? c : '?';
	}
	buf[4] = 0;
}

static uint16_t clamp8(double v)
{
	return (uint16_t)(v < 0 ? 0 : v > 255 ? 255 : lround(v));
}

/* BT.601 limited range (what UVC cameras send) to R'G'B'. */
static void yuv_to_rgb(int y, int cb, int cr, uint16_t *rgb)
{
	double l = 1.164383 * (y - 16), u = cb - 128, v = cr - 128;
	rgb[0] = clamp8(l + 1.596027 * v);
	rgb[1] = clamp8(l - 0.391762 * u - 0.812968 * v);
	rgb[2] = clamp8(l + 2.017232 * u);
}

static void convert_row(const struct glint_v4l2_format *f, const uint8_t *s,
			int w, uint16_t *d)
{
	switch (f->packing) {
	case GLINT_PACK_8:
		for (int x = 0; x < w; x++)
			d[x] = s[x];
		break;
	case GLINT_PACK_16: {
		uint16_t top = (uint16_t)((1u << f->bits) - 1);
		for (int x = 0; x < w; x++) {
			uint16_t v = (uint16_t)(s[2 * x] | s[2 * x + 1] << 8);
			d[x] = v > top ? top : v; /* stray high bits */
		}
		break;
	}
	case GLINT_PACK_10P:
		/* Bytes 0-3: the high 8 bits of 4 samples; byte 4: their low
		 * 2 bits, first sample in bits 0-1. */
		for (int x = 0; x < w; x++) {
			const uint8_t *g = s + x / 4 * 5;
			int k = x % 4;
			d[x] = (uint16_t)(g[k] << 2 | ((g[4] >> (2 * k)) & 3));
		}
		break;
	case GLINT_PACK_12P:
		/* Bytes 0-1: the high 8 bits of 2 samples; byte 2: their low
		 * 4 bits, first sample in bits 0-3. */
		for (int x = 0; x < w; x++) {
			const uint8_t *g = s + x / 2 * 3;
			int k = x % 2;
			d[x] = (uint16_t)(g[k] << 4 | ((g[2] >> (4 * k)) & 15));
		}
		break;
	case GLINT_PACK_RGB24:
		for (int x = 0; x < 3 * w; x++)
			d[x] = s[x];
		break;
	case GLINT_PACK_YUYV:
		for (int x = 0; x + 1 < w; x += 2) {
			const uint8_t *g = s + 2 * x;
			yuv_to_rgb(g[0], g[1], g[3], d + 3 * x);
			yuv_to_rgb(g[2], g[1], g[3], d + 3 * x + 3);
		}
		if (w & 1) {
			const uint8_t *g = s + 2 * (w - 1);
			yuv_to_rgb(g[0], g[1], 128, d + 3 * (w - 1));
		}
		break;
	}
}

int glint_v4l2_convert(const struct glint_v4l2_format *f, const uint8_t *src,
		       size_t size, size_t stride, int width, int height,
		       uint16_t *dst)
{
	size_t row = glint_v4l2_row_bytes(f, width);

	if (stride < row)
		return glint_error_set(EINVAL,
				       "%s frame: %zu bytes per line for %d "
				       "pixels: expected at least %zu",
				       f->name, stride, width, row);
	if (height <= 0 || size < stride * (size_t)(height - 1) + row)
		return glint_error_set(EIO,
				       "%s frame %dx%d: %zu bytes delivered, "
				       "expected %zu (short frame)",
				       f->name, width, height, size,
				       stride * (size_t)height);
	for (int y = 0; y < height; y++)
		convert_row(f, src + (size_t)y * stride, width,
			    dst + (size_t)y * width * f->channels);
	return 0;
}

void glint_v4l2_frame_describe(const struct glint_v4l2_format *f, int width,
			       int height, struct glint_frame *frame)
{
	frame->width = width;
	frame->height = height;
	snprintf(frame->format, sizeof(frame->format), "%s", f->layout);
	snprintf(frame->source_format, sizeof(frame->source_format), "%s",
		 f->name);
	frame->channels = f->channels;
	frame->bit_depth = f->bits;
	frame->linear = f->linear;
}
