/* SPDX-License-Identifier: MIT */
/* A JPEG's EXIF (APP1) exposure time through libexif (core/exif.h), and
 * the same bytes' pixels as glint reads an 8-bit bracket's JPEG. */
#include "fuzz.h"

#include "core/exif.h"
#include "core/formats.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path_ext(data, size, "jpg");
	uint8_t *rgb = NULL;
	int w, h;
	double t;

	glint_exif_exposure_time(path, &t);
	if (glint_ldr_read(path, &w, &h, &rgb) == 0)
		free(rgb);
	return 0;
}
