/* SPDX-License-Identifier: MIT */
/* TIFF through libtiff: float and 16-bit linear radiance, 8-bit code
 * values, and the EXIF directory's exposure time (core/tiff.h,
 * core/exif.h). */
#include "fuzz.h"

#include "core/exif.h"
#include "core/tiff.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path_ext(data, size, "tif");
	struct glint_image *img = NULL;
	uint8_t *rgb = NULL;
	int w, h;
	double t;

	glint_tiff_read(path, &img);
	glint_image_free(img);
	if (glint_tiff_read_rgb8(path, &w, &h, &rgb) == 0)
		free(rgb);
	glint_exif_exposure_time(path, &t);
	return 0;
}
