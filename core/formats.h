/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_FORMATS_H
#define GLINT_CORE_FORMATS_H

/*
 * Individual image formats.  Readers return a new image in *out (caller
 * frees); writers are atomic (see atomic_file.h).  Every error message names
 * the file and what was wrong.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (the file, the field, the size limit).  Threads:
 * re-entrant.  Who frees: images out with glint_image_free().
 */

#include "image.h"

#include <stdint.h>

/* Readers store a new image in *out: the caller's (glint_image_free()).
 *
 * OpenEXR through the OpenEXRCore C API; RGB or Y channels, any of half,
 * float or uint; scanline or tiled (level 0); DWAA/DWAB fall back to the
 * C++ library (exr_cxx.cpp). */
int glint_exr_read(const char *path, struct glint_image **out);
/* The data window's size, from the header alone. */
int glint_exr_size(const char *path, int *width, int *height);
/* The header's "software" string attribute (who wrote the file) into
 * buf: 0, -ENOENT without one, or the error met reading the header. */
int glint_exr_software(const char *path, char *buf, size_t n);
/* Only a window of the data window (which it must lie in), decoding only
 * the chunks (scanline blocks or tiles) it touches. */
int glint_exr_read_window(const char *path,
			  const struct glint_image_window *win,
			  struct glint_image **out);
/* ZIP-compressed scanline EXR with R, G, B as 32-bit float or half,
 * "software" glint
 * (opts->exr_half); the data window and display window as opts says
 * (glint_write_opts), checked to lie inside the frame. */
int glint_exr_write(const char *path, const struct glint_image *img,
		    const struct glint_write_opts *opts);

/* Radiance RGBE (.hdr), flat or new-style RLE scanlines, -Y H +X W. */
int glint_rgbe_read(const char *path, struct glint_image **out);
int glint_rgbe_write(const char *path, const struct glint_image *img);

/* Portable float map, colour ("PF") or grey ("Pf"), either endianness. */
int glint_pfm_read(const char *path, struct glint_image **out);
int glint_pfm_write(const char *path, const struct glint_image *img);

/*
 * 8-bit sRGB PNG preview.  Tone map: v' = clamp(v * 2^exposure, 0, 1), then
 * the sRGB transfer function (IEC 61966-2-1).  A NaN exposure means "auto":
 * the 99th percentile of the non-zero luminances is mapped to 0.9.
 */
int glint_png_write(const char *path, const struct glint_image *img,
		    double exposure);
/* A PNG's "Software" text (tEXt, zTXt or iTXt) into buf: 0, -ENOENT
 * without one, or the error met reading it. */
int glint_png_software(const char *path, char *buf, size_t n);

/* A PNG written atomically, rows from get_row(ctx, y, row): bit_depth 8 or
 * 16 (big-endian samples, as PNG stores them), 1 or 3 channels, an sRGB
 * chunk, level-1 compression when `fast`, a "Software" text naming glint
 * and one optional text chunk more. */
struct glint_png_layout {
	int bit_depth, channels, srgb, fast;
	const char *text_key, *text;
};
int glint_png_write_rows(const char *path, int w, int h,
			 const struct glint_png_layout *l,
			 void (*get_row)(void *ctx, int y, uint8_t *row),
			 void *ctx);

/* 8-bit sRGB PNG of ready-made pixels (w * h * 3 bytes), atomically. */
int glint_png_write_rgb8(const char *path, int w, int h, const uint8_t *px);

/* Read any PNG as 8-bit RGB (w * h * 3 bytes, caller frees): the camera's
 * code values as stored, no gamma or colour conversion. */
int glint_png_read_rgb8(const char *path, int *w, int *h, uint8_t **px);

/* Read a JPEG as 8-bit RGB (w * h * 3 bytes, caller frees) through
 * libjpeg-turbo; any corrupt-data warning is an error. */
int glint_jpeg_read_rgb8(const char *path, int *w, int *h, uint8_t **px);

/* Walk a PNG's chunks before libpng reads it: libpng allocates what a
 * chunk's length says, so each must fit in the file; one promising more
 * is an error naming the chunk and its offset.  0 for a non-PNG (libpng
 * then says what is wrong). */
int glint_png_check_chunks(const char *path);

/* Any 8-bit image (PNG, TGA, JPEG, BMP, TIFF) as RGB bytes, caller frees. */
int glint_ldr_read(const char *path, int *w, int *h, uint8_t **rgb);
/* The same as an image of code / 255 (camera-encoded, not radiance). */
int glint_ldr_read_image(const char *path, struct glint_image **out);

/* The tone map above for one linear value already scaled by 2^EV. */
uint8_t glint_tonemap_srgb8(double v);

/* Exposure (stops) that the auto rule above picks for img. */
double glint_png_auto_exposure(const struct glint_image *img);

#endif
