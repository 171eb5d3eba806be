/* SPDX-License-Identifier: MIT */
/* DNG: glint's raw frames as libtiff reads them (capture/hdr/dng.h), with
 * their glint:frame metadata, layout and pixel checksum checks. */
#include "fuzz.h"

#include "capture/hdr/frame_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path(data, size);
	struct glint_frame f;
	int index;
	if (glint_frame_read(path, &f, &index) == 0)
		glint_frame_release(&f);
	return 0;
}
