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

#include <exception>

extern "C" int glint_exr_read_cxx(const char *path, struct glint_image **out)
{
	struct glint_image *img = nullptr;

	*out = nullptr;
	try {
		Imf::RgbaInputFile file(path);
		Imath::Box2i dw = file.dataWindow();
		int w = dw.max.x - dw.min.x + 1;
		int h = dw.max.y - dw.min.y + 1;
		img = glint_image_new(w, h);
		if (!img)
			return glint_error_prefix(EINVAL, "%s: data window",
						  path);
		Imf::Array2D<Imf::Rgba> px(h, w);
		file.setFrameBuffer(&px[0][0] - dw.min.x - dw.min.y * w, 1, w);
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
