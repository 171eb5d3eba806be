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

/* The formats stb_image would decode besides BMP and TGA (and PNG and
 * JPEG, read above), named by their signatures: glint does not read them
 * as photos, so stb's untested decoders for them never see a file. */
static const char *ldr_other_format(const unsigned char *sig, size_t n)
{
	static const struct {
		const char *magic;
		size_t len;
		const char *name;
	} formats[] = {
		{ "GIF8", 4, "GIF" },
		{ "8BPS", 4, "Photoshop" },
		{ "\x53\x80\xf6\x34", 4, "Softimage PIC" },
		{ "#?", 2, "Radiance HDR" },
		{ "P5", 2, "PGM" },
		{ "P6", 2, "PPM" },
	};
	for (size_t i = 0; i < sizeof(formats) / sizeof(formats[0]); i++)
		if (n >= formats[i].len &&
		    !memcmp(sig, formats[i].magic, formats[i].len))
			return formats[i].name;
	return NULL;
}

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
	/* By signature, whatever the name.  stb_image is given only what
	 * could be BMP or TGA: its own JPEG decoder asserts, and so aborts,
	 * on some damaged Huffman tables, and it takes a file for a JPEG when
	 * 0xff fill bytes come before the SOI marker.  So a file starting
	 * 0xff goes to libjpeg-turbo, which wants its SOI at byte 0 and says
	 * so, unless its second byte is 0 or 1: a TGA with a 255-byte ID
	 * field and a colour-map type, which stb's JPEG test refuses. */
	unsigned char sig[4] = { 0 };
	FILE *fp = glint_fopen_regular(path, "rb");
	if (!fp)
		return -errno;
	size_t got = fread(sig, 1, sizeof(sig), fp);
	fclose(fp);
	if (got >= 1 && sig[0] == 0xff && (got < 2 || sig[1] > 1))
		return glint_jpeg_read_rgb8(path, w, h, rgb);
	if (got == 4 && !memcmp(sig, "\x89PNG", 4))
		return glint_png_read_rgb8(path, w, h, rgb);
	if (got == 4 && (!memcmp(sig, "II*", 4) || !memcmp(sig, "MM\0*", 4)))
		return glint_tiff_read_rgb8(path, w, h, rgb);
	const char *other = ldr_other_format(sig, got);
	if (other)
		return glint_error_set(EIO,
				       "%s: a %s image; 8-bit photos are read "
				       "as JPEG, PNG, TIFF, BMP or TGA",
				       path, other);
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
