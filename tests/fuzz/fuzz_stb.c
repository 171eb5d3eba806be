/* SPDX-License-Identifier: MIT */
/* 8-bit images by content, as glint_ldr_read takes them: a JPEG through
 * libjpeg-turbo, TGA and BMP through stb_image. */
#include "fuzz.h"

#include "core/formats.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	uint8_t *rgb = NULL;
	int w, h;
	glint_ldr_read(fuzz_path(data, size), &w, &h, &rgb);
	free(rgb);
	return 0;
}
