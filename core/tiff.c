/* SPDX-License-Identifier: MIT */
/* TIFF in and out with libtiff (tiff.h). */
#define _POSIX_C_SOURCE 200809L /* unlink */
#include "tiff.h"

#include "atomic_file.h"
#include "error.h"
#include "path.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* libtiff's message formats (it checks them itself). */
static int on_error(TIFF *tif, void *user, const char *module, const char *fmt,
		    va_list ap) GLINT_PRINTF(4, 0);
static int on_error(TIFF *tif, void *user, const char *module, const char *fmt,
		    va_list ap)
{
	struct glint_tiff_msgs *m = user;
	(void)tif;
	(void)module;
	if (!m->text[0])
		vsnprintf(m->text, sizeof(m->text), fmt, ap);
	return 1;
}

static int on_warning(TIFF *tif, void *user, const char *module,
		      const char *fmt, va_list ap)
{
	(void)tif;
	(void)user;
	(void)module;
	(void)fmt;
	(void)ap;
	return 1; /* unknown private tags and the like: not errors */
}

TIFF *glint_tiff_open(const char *path, const char *mode,
		      struct glint_tiff_msgs *m)
{
	TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
	TIFF *tif;

	m->text[0] = 0;
	/* libtiff opens by path: a FIFO or a device is refused first (the
	 * message, glint_error_msg's, names it) rather than blocking it */
	if (mode[0] == 'r' && glint_check_regular(path) < 0) {
		const char *why = glint_error_msg();
		size_t pl = strlen(path);
		if (!strncmp(why, path, pl) && !strncmp(why + pl, ": ", 2))
			why += pl + 2;
		snprintf(m->text, sizeof(m->text), "%s", why);
		TIFFOpenOptionsFree(o);
		return NULL;
	}
	if (!o)
		return NULL;
	TIFFOpenOptionsSetErrorHandlerExtR(o, on_error, m);
	TIFFOpenOptionsSetWarningHandlerExtR(o, on_warning, m);
	TIFFOpenOptionsSetMaxSingleMemAlloc(o, glint_image_max_bytes());
	tif = TIFFOpenExt(path, mode, o);
	TIFFOpenOptionsFree(o);
	return tif;
}

/* A whole TIFF's samples: bits 8, 16 (uint) or 32 (float), 1 or 3+
 * samples a pixel (the first three, or the one, kept). */
struct samples {
	int w, h, spp, bits;
	void *data; /* w * h * spp samples */
};

static int read_samples(const char *path, struct samples *s)
{
	struct glint_tiff_msgs m;
	uint32_t w = 0, h = 0;
	uint16_t bps = 0, spp = 1, fmt = SAMPLEFORMAT_UINT;
	uint16_t planar = PLANARCONFIG_CONTIG, comp = COMPRESSION_NONE;
	int ret = 0;

	memset(s, 0, sizeof(*s));
	TIFF *tif = glint_tiff_open(path, "r", &m);
	if (!tif)
		return glint_error_set(EIO, "%s: not a readable TIFF: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
	TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
	TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bps);
	TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
	TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &fmt);
	TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
	TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &comp);
	int ok_type = (bps == 8 && fmt == SAMPLEFORMAT_UINT) ||
		      (bps == 16 && fmt == SAMPLEFORMAT_UINT) ||
		      (bps == 32 && fmt == SAMPLEFORMAT_IEEEFP);
	if (!ok_type || planar != PLANARCONFIG_CONTIG || spp < 1 || spp > 8 ||
	    TIFFIsTiled(tif))
		ret = glint_error_set(EINVAL,
				      "%s: a %u-bit TIFF of sample format "
				      "%u, %u samples a pixel%s: expected "
				      "8- or 16-bit integer or 32-bit float "
				      "samples, interleaved, in strips",
				      path, bps, fmt, spp,
				      TIFFIsTiled(tif) ? ", tiled" : "");
	double bytes = (double)w * h * spp * (bps / 8);
	if (ret == 0)
		ret = glint_image_size_check(
			path, "TIFF ImageWidth/ImageLength", w, h,
			glint_file_size(path),
			comp == COMPRESSION_NONE ? bytes : bytes / 1032);
	if (ret == 0 && (double)TIFFScanlineSize64(tif) != bytes / h)
		ret = glint_error_set(EINVAL, "%s: unexpected scanline size",
				      path);
	if (ret == 0) {
		s->data = malloc((size_t)bytes);
		if (!s->data)
			ret = glint_error_set(ENOMEM, "%s: out of memory",
					      path);
	}
	size_t row = (size_t)w * spp * (bps / 8);
	for (uint32_t y = 0; ret == 0 && y < h; y++)
		if (TIFFReadScanline(tif, (char *)s->data + row * y, y, 0) < 0)
			ret = glint_error_set(EIO,
					      "%s: truncated or corrupt at "
					      "row %u: %s",
					      path, y,
					      m.text[0] ? m.text : "?");
	TIFFClose(tif);
	if (ret < 0) {
		free(s->data);
		s->data = NULL;
		return ret;
	}
	s->w = (int)w;
	s->h = (int)h;
	s->spp = spp;
	s->bits = bps;
	return 0;
}

/* Sample c (0..2) of pixel i: grey images repeat their one sample. */
static double sample(const struct samples *s, size_t i, int c)
{
	size_t k = i * s->spp + (s->spp >= 3 ? (size_t)c : 0);
	if (s->bits == 8)
		return ((const uint8_t *)s->data)[k];
	if (s->bits == 16)
		return ((const uint16_t *)s->data)[k];
	return ((const float *)s->data)[k];
}

int glint_tiff_read(const char *path, struct glint_image **out)
{
	struct samples s;
	int ret = read_samples(path, &s);

	*out = NULL;
	if (ret < 0)
		return ret;
	if (s.bits == 8) {
		free(s.data);
		return glint_error_set(EINVAL,
				       "%s: an 8-bit TIFF holds camera-encoded "
				       "values, not radiance: merge a bracket "
				       "of them (glint hdr --times), or give a "
				       "16-bit linear or float TIFF",
				       path);
	}
	struct glint_image *img = glint_image_new(s.w, s.h);
	if (!img) {
		free(s.data);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	double scale = s.bits == 16 ? 1.0 / 65535 : 1.0;
	for (size_t i = 0; i < (size_t)s.w * s.h; i++)
		for (int c = 0; c < 3; c++) {
			double v = sample(&s, i, c) * scale;
			if (!isfinite(v)) {
				glint_image_free(img);
				free(s.data);
				return glint_error_set(
					EINVAL,
					"%s: pixel (%zu, %zu) channel %c is "
					"%s",
					path, i % (size_t)s.w, i / (size_t)s.w,
					"RGB"[c],
					isnan(v) ? "nan" : "infinite");
			}
			img->data[3 * i + c] = (float)v;
		}
	free(s.data);
	*out = img;
	return 0;
}

int glint_tiff_read_rgb8(const char *path, int *w, int *h, uint8_t **rgb)
{
	struct samples s;
	int ret = read_samples(path, &s);

	*rgb = NULL;
	if (ret < 0)
		return ret;
	if (s.bits != 8) {
		free(s.data);
		return glint_error_set(EINVAL,
				       "%s: a %d-bit TIFF where 8-bit "
				       "camera-encoded frames are expected",
				       path, s.bits);
	}
	*rgb = malloc((size_t)s.w * s.h * 3);
	if (!*rgb) {
		free(s.data);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	for (size_t i = 0; i < (size_t)s.w * s.h; i++)
		for (int c = 0; c < 3; c++)
			(*rgb)[3 * i + c] = (uint8_t)sample(&s, i, c);
	free(s.data);
	*w = s.w;
	*h = s.h;
	return 0;
}

int glint_tiff_read_rgb16(const char *path, int *w, int *h, int *channels,
			  uint16_t **px)
{
	struct samples s;
	int ret = read_samples(path, &s);

	*px = NULL;
	if (ret < 0)
		return ret;
	if (s.bits != 16) {
		free(s.data);
		return glint_error_set(EINVAL,
				       "%s: a %d-bit TIFF where 16-bit linear "
				       "samples are expected",
				       path, s.bits);
	}
	/* The samples as read, the extra (alpha) ones dropped in place. */
	int nc = s.spp >= 3 ? 3 : 1;
	uint16_t *d = s.data;
	for (size_t i = 0; s.spp != nc && i < (size_t)s.w * s.h; i++)
		for (int c = 0; c < nc; c++)
			d[nc * i + c] = d[s.spp * i + c];
	*px = d;
	*w = s.w;
	*h = s.h;
	*channels = nc;
	return 0;
}

int glint_tiff_sample_bits(const char *path)
{
	struct glint_tiff_msgs m;
	uint16_t bps = 0;
	TIFF *tif = glint_tiff_open(path, "r", &m);

	if (!tif)
		return glint_error_set(EIO, "%s: not a readable TIFF: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bps);
	TIFFClose(tif);
	return bps;
}

int glint_tiff_write(const char *path, const struct glint_image *img)
{
	char tmp[4096];
	struct glint_tiff_msgs m;
	int ret = glint_atomic_tmpname(path, tmp, sizeof(tmp));

	if (ret < 0)
		return ret;
	TIFF *tif = glint_tiff_open(tmp, "w", &m);
	if (!tif) {
		unlink(tmp);
		return glint_error_set(EIO, "%s: cannot write: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	}
	int ok =
		TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, (uint32_t)img->width) &&
		TIFFSetField(tif, TIFFTAG_IMAGELENGTH, (uint32_t)img->height) &&
		TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32) &&
		TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP) &&
		TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 3) &&
		TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB) &&
		TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG) &&
		TIFFSetField(tif, TIFFTAG_COMPRESSION,
			     COMPRESSION_ADOBE_DEFLATE) &&
		TIFFSetField(tif, TIFFTAG_PREDICTOR, PREDICTOR_FLOATINGPOINT) &&
		TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16) &&
		TIFFSetField(tif, TIFFTAG_SOFTWARE, "glint");
	/* libtiff's predictor works in place: a row copy per scanline. */
	float *row = malloc((size_t)img->width * 3 * sizeof(float));
	ok = ok && row;
	for (int y = 0; ok && y < img->height; y++) {
		memcpy(row, img->data + (size_t)y * img->width * 3,
		       (size_t)img->width * 3 * sizeof(float));
		ok = TIFFWriteScanline(tif, row, (uint32_t)y, 0) >= 0;
	}
	free(row);
	TIFFClose(tif);
	if (!ok || m.text[0]) {
		unlink(tmp);
		return glint_error_set(EIO, "%s: writing the TIFF failed: %s",
				       path,
				       m.text[0] ? m.text : "libtiff failed");
	}
	return glint_atomic_rename(tmp, path);
}
