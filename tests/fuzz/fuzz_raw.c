/* SPDX-License-Identifier: MIT */
/* Other cameras' raw files (capture/hdr/raw_file.h): the same bytes as a
 * camera raw through LibRaw (the file's layout, black and white levels,
 * CFA pattern and sizes checked by glint before it unpacks or allocates)
 * and as a 16-bit linear TIFF through libtiff with its EXIF exposure and
 * ISO; and the 8-bit test that picks glint hdr's mode. */
#include "fuzz.h"

#include "capture/hdr/raw_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const char *const ext[] = { "mrw", "tif" };
	for (int k = 0; k < 2; k++) {
		const char *path = fuzz_path_ext(data, size, ext[k]);
		struct glint_frame f;
		struct glint_raw_info info;
		if (glint_raw_file_read(path, &f, &info) == 0)
			glint_frame_release(&f);
		glint_raw_file_is_8bit(path);
	}
	return 0;
}
