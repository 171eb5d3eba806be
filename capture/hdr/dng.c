/* SPDX-License-Identifier: MIT */
/* Raw frames as DNG, with libtiff (dng.h). */
#define _POSIX_C_SOURCE 200809L /* strdup, unlink */
#include "capture/hdr/dng.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/path.h"
#include "core/image.h"
#include "core/tiff.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* DNG's PhotometricInterpretation values beyond baseline TIFF's. */
#define PHOTOMETRIC_LINEAR_RAW 34892

static const struct {
	const char *format;
	uint8_t pattern[4];
} cfa[] = {
	{ "RGGB16", { 0, 1, 1, 2 } },
	{ "GRBG16", { 1, 0, 2, 1 } },
	{ "GBRG16", { 1, 2, 0, 1 } },
	{ "BGGR16", { 2, 1, 1, 0 } },
};

/* XYZ (D65) to linear sRGB, IEC 61966-2-1. */
static const float xyz_to_srgb[9] = { 3.2406f,	-1.5372f, -0.4986f,
				      -0.9689f, 1.8758f,  0.0415f,
				      0.0557f,	-0.2040f, 1.0570f };

static int write_tags(TIFF *tif, const struct glint_frame *f, const char *meta)
{
	int ch = f->channels == 3 ? 3 : 1;
	int k = -1;
	for (int i = 0; i < 4; i++)
		if (!strcmp(f->format, cfa[i].format))
			k = i;
	uint16_t photometric = k >= 0	 ? PHOTOMETRIC_CFA
			       : ch == 3 ? PHOTOMETRIC_LINEAR_RAW
					 : PHOTOMETRIC_MINISBLACK;
	static const uint16_t dim[2] = { 2, 2 };
	float black[3] = { (float)f->black_level, (float)f->black_level,
			   (float)f->black_level };
	uint32_t white[3];
	static const float neutral[3] = { 1, 1, 1 };
	int depth = f->bit_depth > 0 && f->bit_depth <= 16 ? f->bit_depth : 16;
	for (int i = 0; i < 3; i++)
		white[i] = (1u << depth) - 1;

	int ok = TIFFSetField(tif, TIFFTAG_SUBFILETYPE, 0) &&
		 TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, (uint32_t)f->width) &&
		 TIFFSetField(tif, TIFFTAG_IMAGELENGTH, (uint32_t)f->height) &&
		 TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 16) &&
		 TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, ch) &&
		 TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG) &&
		 TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_NONE) &&
		 TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, photometric) &&
		 TIFFSetField(tif, TIFFTAG_ORIENTATION, ORIENTATION_TOPLEFT) &&
		 TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16) &&
		 TIFFSetField(tif, TIFFTAG_SOFTWARE, "glint") &&
		 TIFFSetField(tif, TIFFTAG_MAKE, "glint") &&
		 TIFFSetField(tif, TIFFTAG_MODEL,
			      f->source_format[0] ? f->source_format
						  : "camera") &&
		 TIFFSetField(tif, TIFFTAG_IMAGEDESCRIPTION, meta) &&
		 TIFFSetField(tif, TIFFTAG_DNGVERSION, "\001\004\000\000") &&
		 TIFFSetField(tif, TIFFTAG_DNGBACKWARDVERSION,
			      "\001\001\000\000") &&
		 TIFFSetField(tif, TIFFTAG_UNIQUECAMERAMODEL, "glint camera") &&
		 TIFFSetField(tif, TIFFTAG_BLACKLEVEL, ch, black) &&
		 TIFFSetField(tif, TIFFTAG_WHITELEVEL, ch, white);
	if (ok && k >= 0)
		ok = TIFFSetField(tif, TIFFTAG_CFAREPEATPATTERNDIM, dim) &&
		     TIFFSetField(tif, TIFFTAG_CFAPATTERN, 4, cfa[k].pattern);
	if (ok && (k >= 0 || ch == 3))
		ok = TIFFSetField(tif, TIFFTAG_COLORMATRIX1, 9, xyz_to_srgb) &&
		     TIFFSetField(tif, TIFFTAG_CALIBRATIONILLUMINANT1, 21) &&
		     TIFFSetField(tif, TIFFTAG_ASSHOTNEUTRAL, 3, neutral);
	/* The EXIF IFD's offset, filled in once it is written. */
	if (ok)
		ok = TIFFSetField(tif, TIFFTAG_EXIFIFD, (uint64_t)0);
	return ok ? 0 : -1;
}

static int write_exif(TIFF *tif, const struct glint_frame *f)
{
	uint16_t iso = (uint16_t)(f->gain * 100 + 0.5);
	uint64_t off = 0;

	if (TIFFCreateEXIFDirectory(tif) ||
	    !TIFFSetField(tif, EXIFTAG_EXPOSURETIME, f->exposure_s) ||
	    !TIFFSetField(tif, EXIFTAG_ISOSPEEDRATINGS, 1, &iso) ||
	    !TIFFWriteCustomDirectory(tif, &off))
		return -1;
	/* Back to IFD 0 to point at it; TIFFClose writes IFD 0 again. */
	if (!TIFFSetDirectory(tif, 0) ||
	    !TIFFSetField(tif, TIFFTAG_EXIFIFD, off))
		return -1;
	return 0;
}

int glint_dng_write(const char *path, const struct glint_frame *f,
		    const char *meta_json)
{
	char tmp[4096];
	struct glint_tiff_msgs m;
	int ch = f->channels == 3 ? 3 : 1;
	/* dcraw (9.28) reads 512 bytes of an ImageDescription whatever its
	 * length, and fails when they run past the end of the file: the
	 * JSON is padded with spaces to 512 bytes. */
	size_t len = strlen(meta_json);
	char *meta = malloc(len < 512 ? 513 : len + 1);
	if (!meta)
		return glint_error_set(ENOMEM, "out of memory");
	memcpy(meta, meta_json, len + 1);
	if (len < 512) {
		memset(meta + len, ' ', 512 - len);
		meta[512] = 0;
	}
	int ret = glint_atomic_tmpname(path, tmp, sizeof(tmp));

	if (ret < 0) {
		free(meta);
		return ret;
	}
	TIFF *tif = glint_tiff_open(tmp, "w", &m);
	if (!tif) {
		unlink(tmp);
		free(meta);
		return glint_error_set(EIO, "%s: cannot write: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	}
	ret = write_tags(tif, f, meta);
	for (int y = 0; ret == 0 && y < f->height; y++)
		if (TIFFWriteScanline(
			    tif, (void *)(f->data + (size_t)y * f->width * ch),
			    (uint32_t)y, 0) < 0)
			ret = -1;
	if (ret == 0 && !TIFFWriteDirectory(tif))
		ret = -1;
	if (ret == 0)
		ret = write_exif(tif, f);
	TIFFClose(tif);
	free(meta);
	if (ret < 0 || m.text[0]) {
		unlink(tmp);
		return glint_error_set(EIO, "%s: writing the DNG failed: %s",
				       path,
				       m.text[0] ? m.text : "libtiff failed");
	}
	return glint_atomic_rename(tmp, path);
}

int glint_dng_is_tiff(const char *path)
{
	unsigned char b[4] = { 0 };
	FILE *fp = glint_fopen_regular(path, "rb");
	if (!fp) {
		glint_error_clear(); /* the reader that follows says why */
		return 0;
	}
	size_t n = fread(b, 1, 4, fp);
	fclose(fp);
	return n == 4 &&
	       ((b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0) ||
		(b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42));
}

/* The frame's layout from the DNG's tags. */
static int read_layout(const char *path, TIFF *tif, struct glint_frame *f)
{
	uint32_t w = 0, h = 0;
	uint16_t bps = 0, spp = 1, photometric = 0,
		 planar = PLANARCONFIG_CONTIG;

	TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
	TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
	TIFFGetField(tif, TIFFTAG_BITSPERSAMPLE, &bps);
	TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
	TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
	TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
	if (bps != 16 || planar != PLANARCONFIG_CONTIG ||
	    !((spp == 1 && (photometric == PHOTOMETRIC_CFA ||
			    photometric == PHOTOMETRIC_MINISBLACK)) ||
	      (spp == 3 && photometric == PHOTOMETRIC_LINEAR_RAW)))
		return glint_error_set(EINVAL,
				       "%s: a %u-bit, %u-sample image of "
				       "photometric type %u: expected a "
				       "16-bit CFA, LinearRaw or greyscale "
				       "raw frame",
				       path, bps, spp, photometric);
	f->width = (int)w;
	f->height = (int)h;
	f->channels = spp;
	snprintf(f->format, sizeof(f->format), "%s",
		 spp == 3 ? "RGB16" : "MONO16");
	if (photometric == PHOTOMETRIC_CFA) {
		uint16_t n = 0;
		uint8_t *pat = NULL;
		uint16_t *dim = NULL;
		int k = -1;
		if (TIFFGetField(tif, TIFFTAG_CFAREPEATPATTERNDIM, &dim) &&
		    dim && dim[0] == 2 && dim[1] == 2 &&
		    TIFFGetField(tif, TIFFTAG_CFAPATTERN, &n, &pat) && n == 4)
			for (int i = 0; i < 4; i++)
				if (!memcmp(pat, cfa[i].pattern, 4))
					k = i;
		if (k < 0)
			return glint_error_set(EINVAL,
					       "%s: a colour filter array "
					       "other than a 2 x 2 Bayer "
					       "pattern",
					       path);
		snprintf(f->format, sizeof(f->format), "%s", cfa[k].format);
	}
	return 0;
}

int glint_dng_read(const char *path, struct glint_frame *f, char **metadata)
{
	struct glint_tiff_msgs m;
	char *desc = NULL;
	int ret;

	memset(f, 0, sizeof(*f));
	*metadata = NULL;
	TIFF *tif = glint_tiff_open(path, "r", &m);
	if (!tif)
		return glint_error_set(EIO, "%s: not a readable DNG: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	ret = read_layout(path, tif, f);
	if (ret == 0) {
		/* Allocation from the header only once the file is seen to
		 * hold that many samples (uncompressed: all of them). */
		uint16_t comp = COMPRESSION_NONE;
		TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &comp);
		double need = 2.0 * f->channels * f->width * f->height;
		ret = glint_image_size_check(
			path, "DNG ImageWidth/ImageLength", f->width, f->height,
			glint_file_size(path),
			comp == COMPRESSION_NONE ? need : need / 1032);
	}
	if (ret == 0) {
		size_t row = (size_t)f->width * f->channels;
		f->data = malloc(row * f->height * sizeof(uint16_t));
		if (!f->data)
			ret = glint_error_set(ENOMEM, "%s: out of memory",
					      path);
		if (ret == 0 && (size_t)TIFFScanlineSize64(tif) != row * 2)
			ret = glint_error_set(
				EINVAL, "%s: unexpected scanline size", path);
		for (int y = 0; ret == 0 && y < f->height; y++)
			if (TIFFReadScanline(tif, f->data + row * y,
					     (uint32_t)y, 0) < 0)
				ret = glint_error_set(EIO,
						      "%s: truncated or "
						      "corrupt at row %d: %s",
						      path, y,
						      m.text[0] ? m.text : "?");
	}
	if (ret == 0 && TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &desc) &&
	    desc) {
		*metadata = strdup(desc);
		if (!*metadata)
			ret = glint_error_set(ENOMEM, "out of memory");
	}
	TIFFClose(tif);
	if (ret < 0) {
		glint_frame_release(f);
		free(*metadata);
		*metadata = NULL;
	}
	return ret;
}
