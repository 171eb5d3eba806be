// SPDX-License-Identifier: MIT
// The one C++ file of core/: OpenEXR's C++ RgbaInputFile for what the C core
// cannot decode.  Exceptions never cross into C.
extern "C" {
#include "error.h"
#include "image.h"
}
#include "exr_cxx.h"

#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfRgbaFile.h>

#include <climits>
#include <cstdint>
#include <exception>

extern "C" int glint_exr_read_cxx(const char *path, struct glint_image **out)
{
	struct glint_image *img = nullptr;

	*out = nullptr;
	try {
		Imf::RgbaInputFile file(path);
		Imath::Box2i dw = file.dataWindow();
		/* 64-bit: a damaged header's corners may be far apart */
		int64_t w64 = (int64_t)dw.max.x - dw.min.x + 1;
		int64_t h64 = (int64_t)dw.max.y - dw.min.y + 1;
		if (w64 < 1 || h64 < 1 || w64 > INT_MAX || h64 > INT_MAX)
			return glint_error_set(
				EINVAL,
				"%s: data window (%d,%d)-(%d,%d) "
				"is not a valid size",
				path, dw.min.x, dw.min.y, dw.max.x, dw.max.y);
		int w = (int)w64, h = (int)h64;
		img = glint_image_new(w, h);
		if (!img)
			return glint_error_prefix(EINVAL, "%s: data window",
						  path);
		Imf::Array2D<Imf::Rgba> px(h, w);
		/*
		 * OpenEXR addresses pixel (x, y) as base + x + y * w, with
		 * (x, y) in the data window's coordinates.  The base lies
		 * outside the array when the window does not start at the
		 * origin, so it is formed in unsigned address arithmetic,
		 * which wraps, rather than as a pointer that would overflow.
		 */
		uintptr_t origin = (uintptr_t)dw.min.x +
				   (uintptr_t)dw.min.y * (uintptr_t)w;
		uintptr_t base = reinterpret_cast<uintptr_t>(&px[0][0]) -
				 origin * sizeof(Imf::Rgba);
		file.setFrameBuffer(reinterpret_cast<Imf::Rgba *>(base), 1, w);
		file.readPixels(dw.min.y, dw.max.y);
		for (int y = 0; y < h; y++) {
			for (int x = 0; x < w; x++) {
				float *p = glint_image_px(img, x, y);
				p[0] = px[y][x].r;
				p[1] = px[y][x].g;
				p[2] = px[y][x].b;
			}
		}
		*out = img;
		return 0;
	} catch (const std::exception &e) {
		glint_image_free(img);
		return glint_error_set(EINVAL,
				       "%s: not a readable OpenEXR file: %s",
				       path, e.what());
	} catch (...) {
		glint_image_free(img);
		return glint_error_set(EINVAL,
				       "%s: not a readable OpenEXR file", path);
	}
}
