/* SPDX-License-Identifier: MIT */
/*
 * 8-bit images (JPEG through libjpeg-turbo; TGA, BMP through stb_image;
 * PNG through libpng; TIFF through libtiff) for
 * detection and previews: camera-encoded code values, not radiance.
 */
#include "error.h"
#include "formats.h"
#include "image.h"
#include "path.h"
#include "tiff.h"

#include <stb_image.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int glint_ldr_read(const char *path, int *w, int *h, uint8_t **rgb)
{
	char ext[16];
	int n;

	*rgb = NULL;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "png"))
		return glint_png_read_rgb8(path, w, h, rgb);
	if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		return glint_tiff_read_rgb8(path, w, h, rgb);
	/* JPEG by its signature, whatever the name: libjpeg-turbo, never
	 * stb's decoder (which asserts, and so aborts, on some damaged
	 * Huffman tables). */
	unsigned char sig[3] = { 0 };
	FILE *fp = glint_fopen_regular(path, "rb");
	if (!fp)
		return -errno;
	size_t got = fread(sig, 1, sizeof(sig), fp);
	fclose(fp);
	if (got == 3 && sig[0] == 0xff && sig[1] == 0xd8 && sig[2] == 0xff)
		return glint_jpeg_read_rgb8(path, w, h, rgb);
	/* stb allocates what the header says: check the size first.  Its
	 * densest format (run-length TGA: 128 pixels in 2 bytes) stays under
	 * 1032 pixels a byte. */
	if (!stbi_info(path, w, h, &n))
		return glint_error_set(EIO, "%s: %s", path,
				       stbi_failure_reason());
	int ret = glint_image_size_check(path, "header", *w, *h,
					 glint_file_size(path),
					 (double)*w * *h / 1032);
	if (ret < 0)
		return ret;
	uint8_t *p = stbi_load(path, w, h, &n, 3);
	if (!p)
		return glint_error_set(EIO, "%s: %s", path,
				       stbi_failure_reason());
	/* stb's buffer is freed with free() (its default allocator); copy
	 * to be independent of how the library was built. */
	size_t size = (size_t)*w * *h * 3;
	*rgb = malloc(size);
	if (*rgb)
		memcpy(*rgb, p, size);
	stbi_image_free(p);
	return *rgb ? 0 : glint_error_set(ENOMEM, "%s: out of memory", path);
}

int glint_ldr_read_image(const char *path, struct glint_image **out)
{
	uint8_t *rgb;
	int w, h, ret = glint_ldr_read(path, &w, &h, &rgb);
	*out = NULL;
	if (ret < 0)
		return ret;
	struct glint_image *img = glint_image_new(w, h);
	if (!img) {
		free(rgb);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	for (size_t i = 0; i < (size_t)w * h * 3; i++)
		img->data[i] = rgb[i] / 255.0f;
	free(rgb);
	*out = img;
	return 0;
}
