/* SPDX-License-Identifier: MIT */
/* PNG: 8-bit photos (libpng's simplified API) and glint's 16-bit raw
 * frames with their glint:frame metadata and pixel checksum. */
#include "fuzz.h"

#include "capture/hdr/frame_file.h"
#include "core/formats.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path(data, size);
	uint8_t *px = NULL;
	int w, h, index;
	glint_png_read_rgb8(path, &w, &h, &px);
	free(px);
	struct glint_frame f;
	if (glint_frame_read(path, &f, &index) == 0)
		glint_frame_release(&f);
	return 0;
}
