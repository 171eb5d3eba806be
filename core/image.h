/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_IMAGE_H
#define GLINT_CORE_IMAGE_H

/*
 * The one image type: linear, scene-referred float RGB, interleaved,
 * row-major, row 0 at the top.  Pixel (x, y) covers [x, x+1) x [y, y+1) in
 * image coordinates; its centre is (x + 0.5, y + 0.5).
 *
 * Ownership, for every function in glint: an image returned, or stored
 * through a `struct glint_image **` out-parameter, is the caller's and is
 * freed with glint_image_free() (which takes NULL); on failure nothing is
 * stored and nothing is to be freed.  Images passed as `const` are
 * borrowed for the call only.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (NULL from the constructors when out of memory).
 * Threads: an image is not locked: share it read only.  Who frees:
 * glint_image_free() (NULL allowed).
 */

#include <stddef.h>
#include <stdio.h>

struct glint_image {
	int width;
	int height;
	float *data; /* width * height * 3 floats, owned by the image */
};

/*
 * Allocate a zeroed width x height image.  Returns NULL (with a message) on
 * a bad size or when out of memory.  Free with glint_image_free().
 */
struct glint_image *glint_image_new(int width, int height);
void glint_image_free(struct glint_image *img);
/* A copy (the caller's), or NULL when out of memory. */
struct glint_image *glint_image_dup(const struct glint_image *img);
/* Box-average by an integer factor f (width / f x height / f, the
 * remainder rows and columns dropped); NULL if out of memory. */
struct glint_image *glint_image_downsample(const struct glint_image *src,
					   int f);
/* The w x h rectangle of src at (x, y), which must lie inside src; NULL
 * if out of memory. */
struct glint_image *glint_image_crop(const struct glint_image *src, int x,
				     int y, int w, int h);

static inline float *glint_image_px(const struct glint_image *img, int x, int y)
{
	return img->data + ((size_t)y * img->width + x) * 3;
}

/*
 * The size policy of every reader of outside images, applied to a header's
 * width and height before anything is allocated.  Accepted only when
 *  - each side is 1..65536;
 *  - w * h is at most the pixel limit: GLINT_MAX_PIXELS in the environment,
 *    default 2^27 (134 M pixels, a 1.6 GB float image);
 *  - the decoded float image (12 bytes a pixel) is at most the byte limit:
 *    GLINT_MAX_IMAGE_MB (MiB), default 2048;
 *  - the file holds enough data for that many pixels: have_bytes (what the
 *    file holds after its header) >= need_bytes (the least the format can
 *    store w x h pixels in: the raw size, or the codec's best case).
 * `field` names the header field that gave the size ("PFM header", "EXR
 * dataWindow").  Returns 0 or -EFBIG / -EINVAL with a message naming the
 * file, the field and the limit.
 */
int glint_image_size_check(const char *path, const char *field, long long w,
			   long long h, long long have_bytes,
			   double need_bytes);

/* The limits above as set now (for messages and tests). */
long long glint_image_max_pixels(void);
long long glint_image_max_bytes(void);

/* Bytes from `fp`'s position to its end (st_size - ftell), or -1. */
long long glint_file_bytes_left(FILE *fp);
/* Size of the regular file at path, or -1. */
long long glint_file_size(const char *path);

/*
 * Check that every value is finite (and >= 0 when nonneg is set).  On
 * failure the message names `what`, the first bad pixel, its channel and
 * value, and how many values are bad.  Returns 0 or -EINVAL.
 */
int glint_image_check_finite(const struct glint_image *img, const char *what,
			     int nonneg);
/* The same for a window of a file at (x0, y0): pixels named in the file's
 * coordinates. */
int glint_image_check_finite_at(const struct glint_image *img, const char *what,
				int nonneg, int x0, int y0);

/*
 * Read an image, choosing the format from the file extension (.exr, .hdr,
 * .pic, .pfm).  On success *out holds a new image the caller frees.
 */
int glint_image_read(const char *path, struct glint_image **out);

/* A rectangle of an image's pixels. */
struct glint_image_window {
	int x, y, width, height;
};

/* 0 when win lies inside a w x h image, else -EINVAL naming path. */
int glint_image_window_check(const char *path,
			     const struct glint_image_window *win, int w,
			     int h);
/* *img (read from path) replaced by its window win; on error it is freed
 * and NULL. */
int glint_image_window_take(const char *path,
			    const struct glint_image_window *win,
			    struct glint_image **img);

/*
 * Read only window win of the image at path when the image is
 * frame_width x frame_height (*cropped = 1); an image of any other size
 * is read whole (*cropped = 0).  An EXR decodes only the chunks the
 * window touches, so memory is the window's (a 12 MP photo's sphere);
 * other formats are read whole and cropped.
 */
int glint_image_read_window(const char *path, int frame_width, int frame_height,
			    const struct glint_image_window *win,
			    struct glint_image **out, int *cropped);

/*
 * One radiance policy for every command that takes light or a photo to
 * fit (fit, render --env, convert to a float format, probe): an 8-bit
 * image (PNG, TGA, JPEG, BMP) holds camera-encoded values, not radiance.
 * glint_image_encoded() says whether path is one; glint_radiance_check()
 * refuses it, with the one message every command gives, unless srgb;
 * glint_image_read_radiance() reads any image as radiance: HDR formats as
 * they are, an 8-bit one refused, or with srgb linearised through the
 * sRGB curve (IEC 61966-2-1), with a warning that its highlights are
 * clipped.
 */
int glint_image_encoded(const char *path);
int glint_radiance_check(const char *path, int srgb);
int glint_image_read_radiance(const char *path, int srgb,
			      struct glint_image **out);
/* The sRGB curve undone in place (values in 0..1 as the 8-bit readers
 * give them). */
void glint_image_srgb_to_linear(struct glint_image *img);
/* That, for an 8-bit image read from path under --srgb, with the
 * warning every command gives. */
void glint_image_from_srgb(const char *path, struct glint_image *img);

/* Options for glint_image_write(). */
struct glint_write_opts {
	int exr_half;	 /* EXR: store half floats instead of 32-bit */
	double exposure; /* PNG: linear scale 2^exposure before the curve */
	int auto_expose; /* PNG: choose exposure from the image (see png.h) */
	/* EXR only: the image is the data window at (window_x, window_y)
	 * of a frame_width x frame_height display window (0: no window,
	 * the image is the whole frame).  Other formats refuse a window. */
	int window_x, window_y, frame_width, frame_height;
};

/*
 * Write an image atomically (temp file, fsync, rename), choosing the format
 * from the extension (.exr, .hdr, .pfm, .png).  opts may be NULL.
 */
int glint_image_write(const char *path, const struct glint_image *img,
		      const struct glint_write_opts *opts);

/* Lower-case extension of path without the dot, or "" (static storage). */
const char *glint_path_ext(const char *path, char *buf, size_t n);

#endif
