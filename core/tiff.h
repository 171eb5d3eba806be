/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_TIFF_H
#define GLINT_CORE_TIFF_H

/*
 * TIFF through libtiff: 32-bit float RGB out (linear radiance, as image
 * editors and raw tools exchange HDR); in, float (linear radiance),
 * 16-bit integer (linear, as dcraw -4 -T and raw converters' linear
 * exports write it: value / 65535) and 8-bit (camera-encoded code values,
 * read only as such: glint_tiff_read_rgb8).  RGB or greyscale, with any
 * extra (alpha) samples ignored; any compression libtiff decodes.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (libtiff's own message for the file).  Threads:
 * re-entrant (messages per call).  Who frees: images with
 * glint_image_free(), code values with free().
 */

#include "image.h"

#include <stdint.h>
#include <tiffio.h>

/* libtiff's first error message for one file. */
struct glint_tiff_msgs {
	char text[512];
};

/* TIFFOpen with this file's messages kept in m (warnings dropped) and no
 * single allocation beyond glint's image limit. */
TIFF *glint_tiff_open(const char *path, const char *mode,
		      struct glint_tiff_msgs *m);

/* Float or 16-bit TIFF as linear radiance; an 8-bit one is refused (its
 * values are camera-encoded, not radiance). */
int glint_tiff_read(const char *path, struct glint_image **out);
/* An 8-bit TIFF's code values (w * h * 3 bytes, caller frees). */
int glint_tiff_read_rgb8(const char *path, int *w, int *h, uint8_t **rgb);
/* A 16-bit TIFF's samples as they are (a raw converter's linear output,
 * e.g. dcraw -4 -T): *channels 3 (RGB; extra samples dropped) or 1 (grey),
 * w * h * channels values, caller frees. */
int glint_tiff_read_rgb16(const char *path, int *w, int *h, int *channels,
			  uint16_t **px);
/* Bits per sample of a TIFF's first image, or a negative errno naming
 * the file. */
int glint_tiff_sample_bits(const char *path);
/* 32-bit float RGB, deflate with the floating-point predictor, atomic. */
int glint_tiff_write(const char *path, const struct glint_image *img);

#endif
