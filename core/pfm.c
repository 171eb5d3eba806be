/* SPDX-License-Identifier: MIT */
/* Portable float map: "PF" (RGB) or "Pf" (grey), rows bottom to top. */
#include "atomic_file.h"
#include "error.h"
#include "path.h"
#include "formats.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int host_is_little(void)
{
	const uint16_t one = 1;
	return *(const uint8_t *)&one == 1;
}

static float swap_float(float f)
{
	uint32_t u;
	memcpy(&u, &f, 4);
	u = (u >> 24) | ((u >> 8) & 0xff00) | ((u << 8) & 0xff0000) | (u << 24);
	memcpy(&f, &u, 4);
	return f;
}

int glint_pfm_read(const char *path, struct glint_image **out)
{
	struct glint_image *img = NULL;
	char magic[3] = { 0 };
	double scale;
	int w, h, nc, ret = 0;
	float *row = NULL;
	FILE *fp = glint_fopen_regular(path, "rb");

	*out = NULL;
	if (!fp)
		return -errno;
	if (fscanf(fp, "%2s %d %d %lf", magic, &w, &h, &scale) != 4 ||
	    (strcmp(magic, "PF") && strcmp(magic, "Pf")) || scale == 0 ||
	    fgetc(fp) == EOF) {
		ret = glint_error_set(EINVAL,
				      "%s: bad PFM header: expected 'PF' or "
				      "'Pf', width, height and a non-zero "
				      "scale",
				      path);
		goto out;
	}
	nc = magic[1] == 'F' ? 3 : 1;
	ret = glint_image_size_check(path, "PFM header", w, h,
				     glint_file_bytes_left(fp),
				     (double)w * h * nc * sizeof(float));
	if (ret < 0)
		goto out;
	img = glint_image_new(w, h);
	if (!img) {
		ret = glint_error_prefix(EINVAL, "%s", path);
		goto out;
	}
	row = malloc((size_t)w * nc * sizeof(float));
	if (!row) {
		ret = glint_error_set(ENOMEM, "%s: out of memory", path);
		goto out;
	}
	int swap = (scale < 0) != host_is_little();
	for (int i = 0; i < h; i++) {
		int y = h - 1 - i;
		if (fread(row, sizeof(float) * nc, (size_t)w, fp) !=
		    (size_t)w) {
			ret = glint_error_set(EINVAL,
					      "%s: truncated at stored row %d "
					      "of %d",
					      path, i, h);
			goto out;
		}
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y);
			for (int c = 0; c < 3; c++) {
				float v = row[x * nc + (nc == 3 ? c : 0)];
				p[c] = swap ? swap_float(v) : v;
			}
		}
	}
	*out = img;
	img = NULL;
out:
	free(row);
	glint_image_free(img);
	fclose(fp);
	return ret;
}

int glint_pfm_write(const char *path, const struct glint_image *img)
{
	struct glint_atomic_file af;
	int ret = glint_atomic_open(&af, path);

	if (ret < 0)
		return ret;
	fprintf(af.fp, "PF\n%d %d\n%s\n", img->width, img->height,
		host_is_little() ? "-1.0" : "1.0");
	for (int y = img->height - 1; y >= 0; y--)
		fwrite(glint_image_px(img, 0, y), sizeof(float) * 3,
		       (size_t)img->width, af.fp);
	return glint_atomic_commit(&af);
}
