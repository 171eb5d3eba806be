/* SPDX-License-Identifier: MIT */
/* Portable float map. */
#include "fuzz.h"

#include "core/formats.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct glint_image *img = NULL;
	glint_pfm_read(fuzz_path(data, size), &img);
	glint_image_free(img);
	return 0;
}
