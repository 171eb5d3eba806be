/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_EXIF_H
#define GLINT_CORE_EXIF_H

/*
 * A photo's exposure time from its EXIF data: JPEG through libexif (the
 * APP1 segment), TIFF through libtiff (its EXIF directory).  *t in
 * seconds; an error names the file and says what is missing (no EXIF,
 * no ExposureTime, a zero or negative one).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: nothing
 * (values).
 */
int glint_exif_exposure_time(const char *path, double *t);
/* The same, and *iso the EXIF ISOSpeedRatings (0 when it has none). */
int glint_exif_exposure(const char *path, double *t, double *iso);

#endif
