/* SPDX-License-Identifier: MIT */
/* OpenEXR: the OpenEXRCore reader and its DWA fallback, whole and through
 * a window (what glint fit reads of a frame-sized photo or weights: only
 * the chunks the window needs). */
#include "fuzz.h"

#include "core/formats.h"
#include "core/image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path(data, size);
	struct glint_image *img = NULL;
	int w, h;

	glint_exr_read(path, &img);
	glint_image_free(img);
	if (glint_exr_size(path, &w, &h) < 0 || w < 1 || h < 1)
		return 0;
	/* the middle half, and the last row (the chunks after it skipped) */
	struct glint_image_window mid = { w / 4, h / 4, w - w / 2, h - h / 2 };
	struct glint_image_window last = { 0, h - 1, w, 1 };
	img = NULL;
	glint_exr_read_window(path, &mid, &img);
	glint_image_free(img);
	img = NULL;
	glint_exr_read_window(path, &last, &img);
	glint_image_free(img);
	return 0;
}
