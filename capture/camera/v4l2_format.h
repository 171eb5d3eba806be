/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_CAMERA_V4L2_FORMAT_H
#define GLINT_CAPTURE_CAMERA_V4L2_FORMAT_H

/*
 * The V4L2 pixel formats glint reads, and their conversion to a
 * glint_frame's uint16 samples.  Pure logic (no ioctls), so it is tested
 * on its own against independently packed buffers.
 *
 * Preference when configuring a camera (`rank`, higher is better): raw
 * Bayer at the highest bit depth (unpacked before packed at equal depth:
 * no unpacking cost), then 16- and 8-bit greyscale, then RGB24 and YUYV,
 * which the camera has already tone-mapped (`linear` = 0).
 *
 * Errors: none; an unknown format is NULL.  Threads: the table is static
 * and read only.  Who frees: nothing (entries are static).
 */

#include <stddef.h>
#include <stdint.h>

enum glint_v4l2_packing {
	GLINT_PACK_8,	  /* one byte per sample */
	GLINT_PACK_16,	  /* little-endian uint16, value right-aligned */
	GLINT_PACK_10P,	  /* MIPI CSI-2: 4 samples in 5 bytes */
	GLINT_PACK_12P,	  /* MIPI CSI-2: 2 samples in 3 bytes */
	GLINT_PACK_RGB24, /* R, G, B bytes */
	GLINT_PACK_YUYV,  /* Y0 Cb Y1 Cr for two pixels, BT.601 limited */
};

struct glint_v4l2_format {
	uint32_t fourcc;
	const char *name;   /* V4L2's name without V4L2_PIX_FMT_ */
	const char *layout; /* glint_frame.format: RGGB16, MONO16, RGB16 */
	int bits;	    /* significant bits per sample */
	enum glint_v4l2_packing packing;
	int channels; /* of the converted frame */
	int linear;
	int rank;
};

/* The entry for a fourcc (static: never freed), or NULL when glint does
 * not read it. */
const struct glint_v4l2_format *glint_v4l2_format_find(uint32_t fourcc);
/* The entry for a name such as "SRGGB12P" (static), or NULL. */
const struct glint_v4l2_format *glint_v4l2_format_by_name(const char *name);

/* Bytes one row needs at least (before driver padding). */
size_t glint_v4l2_row_bytes(const struct glint_v4l2_format *f, int width);

/*
 * Convert one frame: `src` holds `height` rows `stride` bytes apart
 * (`size` bytes in all); `dst` receives width * height * channels samples.
 * Fails (naming the sizes) when the buffer is too short for the format.
 */
int glint_v4l2_convert(const struct glint_v4l2_format *f, const uint8_t *src,
		       size_t size, size_t stride, int width, int height,
		       uint16_t *dst);

struct glint_frame;
/* Fill a converted frame's geometry, layout, source format, channels,
 * bit depth and linearity from its format. */
void glint_v4l2_frame_describe(const struct glint_v4l2_format *f, int width,
			       int height, struct glint_frame *frame);

/* "pRCC" from a fourcc (buf has room for 5). */
void glint_fourcc_str(uint32_t fourcc, char buf[5]);

#endif
