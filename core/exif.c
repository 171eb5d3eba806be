/* SPDX-License-Identifier: MIT */
/* Exposure times from EXIF (exif.h). */
#include "exif.h"

#include "error.h"
#include "image.h"
#include "path.h"
#include "tiff.h"

#include <errno.h>
#include <libexif/exif-data.h>
#include <math.h>
#include <string.h>

static double jpeg_iso(ExifData *ed)
{
	ExifEntry *e = exif_content_get_entry(ed->ifd[EXIF_IFD_EXIF],
					      EXIF_TAG_ISO_SPEED_RATINGS);
	if (!e || e->format != EXIF_FORMAT_SHORT || e->components < 1 ||
	    e->size < 2)
		return 0;
	return exif_get_short(e->data, exif_data_get_byte_order(ed));
}

static int from_jpeg(const char *path, double *t, double *iso)
{
	int reg = glint_check_regular(path); /* libexif opens by path */
	if (reg < 0)
		return reg;
	ExifData *ed = exif_data_new_from_file(path);
	if (!ed)
		return glint_error_set(EINVAL, "%s: no EXIF data", path);
	ExifEntry *e = exif_content_get_entry(ed->ifd[EXIF_IFD_EXIF],
					      EXIF_TAG_EXPOSURE_TIME);
	int ret = 0;
	if (!e || e->format != EXIF_FORMAT_RATIONAL || e->components < 1 ||
	    e->size < 8) {
		ret = glint_error_set(EINVAL,
				      "%s: its EXIF data has no "
				      "ExposureTime",
				      path);
	} else {
		ExifRational r = exif_get_rational(
			e->data, exif_data_get_byte_order(ed));
		*t = r.denominator ? (double)r.numerator / r.denominator : 0;
		*iso = jpeg_iso(ed);
	}
	exif_data_unref(ed);
	return ret;
}

/* A RATIONAL tag's value: libtiff hands it out as a float or a double
 * depending on the tag's definition (TIFFFieldSetGetSize says which). */
static int tiff_rational(TIFF *tif, uint32_t tag, double *v)
{
	const TIFFField *fip = TIFFFieldWithTag(tif, tag);
	if (!fip)
		return 0;
	if (TIFFFieldSetGetSize(fip) == sizeof(float)) {
		float f = 0;
		if (!TIFFGetField(tif, tag, &f))
			return 0;
		*v = f;
		return 1;
	}
	return TIFFGetField(tif, tag, v);
}

static int from_tiff(const char *path, double *t, double *iso)
{
	struct glint_tiff_msgs m;
	TIFF *tif = glint_tiff_open(path, "r", &m);
	uint64_t off = 0;
	int ret = 0;

	if (!tif)
		return glint_error_set(EIO, "%s: not a readable TIFF: %s", path,
				       m.text[0] ? m.text : "libtiff failed");
	if (!TIFFGetField(tif, TIFFTAG_EXIFIFD, &off) || !off ||
	    !TIFFReadEXIFDirectory(tif, off))
		ret = glint_error_set(EINVAL, "%s: no EXIF directory", path);
	else
		ret = tiff_rational(tif, EXIFTAG_EXPOSURETIME, t)
			      ? 0
			      : glint_error_set(EINVAL,
						"%s: its EXIF directory has no "
						"ExposureTime",
						path);
	uint16_t count = 0, *speeds = NULL;
	if (ret == 0 &&
	    TIFFGetField(tif, EXIFTAG_ISOSPEEDRATINGS, &count, &speeds) &&
	    count >= 1 && speeds)
		*iso = speeds[0];
	TIFFClose(tif);
	return ret;
}

int glint_exif_exposure_time(const char *path, double *t)
{
	double iso;
	return glint_exif_exposure(path, t, &iso);
}

int glint_exif_exposure(const char *path, double *t, double *iso)
{
	char ext[16];
	int ret;

	*t = *iso = 0;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		ret = from_tiff(path, t, iso);
	else if (!strcmp(ext, "jpg") || !strcmp(ext, "jpeg"))
		ret = from_jpeg(path, t, iso);
	else
		ret = glint_error_set(EINVAL,
				      "%s: exposure times are read from the "
				      "EXIF data of JPEG and TIFF photos only",
				      path);
	if (ret == 0 && !(isfinite(*t) && *t > 0))
		ret = glint_error_set(EINVAL, "%s: EXIF ExposureTime %g s",
				      path, *t);
	return ret;
}
