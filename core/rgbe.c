/* SPDX-License-Identifier: MIT */
/*
 * Radiance RGBE (.hdr).  Written here rather than taken from stb_image
 * because stb_image reads past the end of a truncated file as zeros and
 * accepts run lengths that overflow a scanline without a word: a light probe
 * cut short must be an error that names the row, not a black band.
 * Decoding follows Radiance's colr_color(): (m + 0.5) * 2^(e - 136).
 */
#include "atomic_file.h"
#include "error.h"
#include "path.h"
#include "formats.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct rgbe_reader {
	FILE *fp;
	const char *path;
	int row;
};

static int rd_bytes(struct rgbe_reader *r, uint8_t *buf, size_t n)
{
	if (fread(buf, 1, n, r->fp) != n)
		return glint_error_set(
			EINVAL,
			"%s: truncated in pixel row %d: expected "
			"more RGBE data",
			r->path, r->row);
	return 0;
}

static void rgbe_to_float(const uint8_t *in, float *out)
{
	if (in[3] == 0) {
		out[0] = out[1] = out[2] = 0.0f;
		return;
	}
	float f = ldexpf(1.0f, (int)in[3] - (128 + 8));
	for (int c = 0; c < 3; c++)
		out[c] = ((float)in[c] + 0.5f) * f;
}

/* One scanline of `w` RGBE pixels into buf (4 * w bytes). */
static int read_scanline(struct rgbe_reader *r, uint8_t *buf, int w)
{
	uint8_t head[4];
	int ret;

	if (w < 8 || w > 0x7fff)
		return rd_bytes(r, buf, (size_t)w * 4);
	ret = rd_bytes(r, head, 4);
	if (ret < 0)
		return ret;
	if (head[0] != 2 || head[1] != 2 || (head[2] & 0x80)) {
		/* Flat (or old-style run-length) pixels. */
		int shift = 0;
		memcpy(buf, head, 4);
		for (int x = 1; x < w;) {
			uint8_t *p = buf + 4 * x;
			ret = rd_bytes(r, p, 4);
			if (ret < 0)
				return ret;
			if (p[0] == 1 && p[1] == 1 && p[2] == 1) {
				long n = (long)p[3] << shift;
				if (x + n > w)
					return glint_error_set(
						EINVAL,
						"%s: row %d: old-style run of "
						"%ld overflows width %d",
						r->path, r->row, n, w);
				for (long i = 0; i < n; i++, x++)
					memcpy(buf + 4 * x, buf + 4 * (x - 1),
					       4);
				shift += 8;
			} else {
				x++;
				shift = 0;
			}
		}
		return 0;
	}
	if (((int)head[2] << 8 | head[3]) != w)
		return glint_error_set(EINVAL,
				       "%s: row %d: run-length scanline says "
				       "width %d: expected %d",
				       r->path, r->row,
				       (int)head[2] << 8 | head[3], w);
	for (int c = 0; c < 4; c++) {
		for (int x = 0; x < w;) {
			uint8_t count, val;
			ret = rd_bytes(r, &count, 1);
			if (ret < 0)
				return ret;
			int n = count > 128 ? count - 128 : count;
			if (n == 0 || x + n > w)
				return glint_error_set(
					EINVAL,
					"%s: row %d: corrupt run length %d at "
					"column %d of %d",
					r->path, r->row, n, x, w);
			if (count > 128) {
				ret = rd_bytes(r, &val, 1);
				if (ret < 0)
					return ret;
				for (int i = 0; i < n; i++)
					buf[4 * (x++) + c] = val;
			} else {
				for (int i = 0; i < n; i++) {
					ret = rd_bytes(r, &buf[4 * (x++) + c],
						       1);
					if (ret < 0)
						return ret;
				}
			}
		}
	}
	return 0;
}

static int read_header(FILE *fp, const char *path, int *w, int *h, int *flip_y)
{
	char line[512];
	char ya[3], xa[3];

	if (!fgets(line, sizeof(line), fp) || strncmp(line, "#?", 2) != 0)
		return glint_error_set(EINVAL,
				       "%s: not a Radiance file: expected "
				       "'#?RADIANCE' on the first line",
				       path);
	for (;;) {
		if (!fgets(line, sizeof(line), fp))
			return glint_error_set(EINVAL,
					       "%s: header ends before the "
					       "resolution line",
					       path);
		if (line[0] == '\n' || (line[0] == '\r' && line[1] == '\n'))
			break;
		if (!strncmp(line, "FORMAT=", 7) &&
		    strncmp(line + 7, "32-bit_rle_rgbe", 15) != 0) {
			line[strcspn(line, "\r\n")] = '\0';
			return glint_error_set(EINVAL,
					       "%s: %s: expected "
					       "FORMAT=32-bit_rle_rgbe",
					       path, line);
		}
	}
	if (!fgets(line, sizeof(line), fp) ||
	    sscanf(line, "%2s %d %2s %d", ya, h, xa, w) != 4 ||
	    (strcmp(ya, "-Y") && strcmp(ya, "+Y")) || strcmp(xa, "+X")) {
		line[strcspn(line, "\r\n")] = '\0';
		return glint_error_set(EINVAL,
				       "%s: resolution line '%s': expected "
				       "'-Y <height> +X <width>'",
				       path, line);
	}
	*flip_y = ya[0] == '+';
	return 0;
}

/*
 * The fewest bytes w x h pixels can be stored in: rows narrower than 8 or
 * wider than 32767 are flat (4 bytes a pixel); others may be old-style
 * runs: a first pixel and runs of up to 255 << 8k repeats, 4 bytes each
 * (8 bytes a row up to 256 pixels, 12 beyond).
 */
static double min_data_bytes(int w, int h)
{
	if (w < 8 || w > 0x7fff)
		return 4.0 * w * h;
	return (w <= 256 ? 8.0 : 12.0) * h;
}

int glint_rgbe_read(const char *path, struct glint_image **out)
{
	struct rgbe_reader r = { .path = path };
	struct glint_image *img = NULL;
	uint8_t *row = NULL;
	int w, h, flip, ret;

	*out = NULL;
	r.fp = glint_fopen_regular(path, "rb");
	if (!r.fp)
		return -errno;
	ret = read_header(r.fp, path, &w, &h, &flip);
	if (ret < 0)
		goto out;
	ret = glint_image_size_check(path, "resolution line", w, h,
				     glint_file_bytes_left(r.fp),
				     min_data_bytes(w, h));
	if (ret < 0)
		goto out;
	img = glint_image_new(w, h);
	if (!img) {
		ret = glint_error_prefix(EINVAL, "%s", path);
		goto out;
	}
	row = malloc((size_t)w * 4);
	if (!row) {
		ret = glint_error_set(ENOMEM, "%s: out of memory", path);
		goto out;
	}
	for (r.row = 0; r.row < h; r.row++) {
		int y = flip ? h - 1 - r.row : r.row;
		ret = read_scanline(&r, row, w);
		if (ret < 0)
			goto out;
		for (int x = 0; x < w; x++)
			rgbe_to_float(row + 4 * x, glint_image_px(img, x, y));
	}
	*out = img;
	img = NULL;
	ret = 0;
out:
	free(row);
	glint_image_free(img);
	fclose(r.fp);
	return ret;
}

static void float_to_rgbe(const float *in, uint8_t *out)
{
	double v = fmax(in[0], fmax(in[1], in[2]));
	int e;

	if (!(v > 1e-32)) {
		out[0] = out[1] = out[2] = out[3] = 0;
		return;
	}
	double scale = frexp(v, &e) * 256.0 / v;
	for (int c = 0; c < 3; c++) {
		double m = in[c] > 0 ? in[c] * scale : 0;
		out[c] = (uint8_t)(m > 255 ? 255 : m);
	}
	out[3] = (uint8_t)(e + 128);
}

/* Run-length encode one component of a scanline (Radiance's scheme). */
static void write_component(FILE *fp, const uint8_t *buf, int w, int c)
{
	int x = 0;

	while (x < w) {
		/* Find the next run of at least 4 equal bytes. */
		int run_start = x, run_len = 0;
		while (run_start < w) {
			run_len = 1;
			while (run_start + run_len < w && run_len < 127 &&
			       buf[4 * (run_start + run_len) + c] ==
				       buf[4 * run_start + c])
				run_len++;
			if (run_len >= 4)
				break;
			run_start += run_len;
		}
		if (run_len < 4)
			run_start = w;
		/* Literals before the run, at most 128 at a time. */
		while (x < run_start) {
			int n = run_start - x > 128 ? 128 : run_start - x;
			fputc(n, fp);
			for (int i = 0; i < n; i++)
				fputc(buf[4 * (x + i) + c], fp);
			x += n;
		}
		if (run_start < w) {
			fputc(128 + run_len, fp);
			fputc(buf[4 * run_start + c], fp);
			x = run_start + run_len;
		}
	}
}

int glint_rgbe_write(const char *path, const struct glint_image *img)
{
	struct glint_atomic_file af;
	int w = img->width, ret;
	uint8_t *row = malloc((size_t)w * 4);

	if (!row)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	ret = glint_atomic_open(&af, path);
	if (ret < 0) {
		free(row);
		return ret;
	}
	fprintf(af.fp,
		"#?RADIANCE\n# written by glint\n"
		"FORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n",
		img->height, w);
	for (int y = 0; y < img->height; y++) {
		for (int x = 0; x < w; x++)
			float_to_rgbe(glint_image_px(img, x, y), row + 4 * x);
		if (w < 8 || w > 0x7fff) {
			fwrite(row, 4, (size_t)w, af.fp);
			continue;
		}
		uint8_t head[4] = { 2, 2, (uint8_t)(w >> 8),
				    (uint8_t)(w & 0xff) };
		fwrite(head, 1, 4, af.fp);
		for (int c = 0; c < 4; c++)
			write_component(af.fp, row, w, c);
	}
	free(row);
	return glint_atomic_commit(&af);
}
