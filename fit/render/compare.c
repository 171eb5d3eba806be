/* SPDX-License-Identifier: MIT */
#include "compare.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A 5x7 bitmap font for the few glyphs the labels need. */
static const struct {
	char c;
	uint8_t rows[7];
} font[] = {
	{ '0', { 0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E } },
	{ '1', { 0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E } },
	{ '2', { 0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F } },
	{ '3', { 0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E } },
	{ '4', { 0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02 } },
	{ '5', { 0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E } },
	{ '6', { 0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E } },
	{ '7', { 0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08 } },
	{ '8', { 0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E } },
	{ '9', { 0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C } },
	{ '.', { 0, 0, 0, 0, 0, 0x0C, 0x0C } },
	{ '-', { 0, 0, 0, 0x1F, 0, 0, 0 } },
	{ '+', { 0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0 } },
	{ 'e', { 0, 0, 0x0E, 0x11, 0x1F, 0x10, 0x0E } },
	{ 'P', { 0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10 } },
	{ 'H', { 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11 } },
	{ 'O', { 0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E } },
	{ 'T', { 0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04 } },
	{ 'R', { 0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11 } },
	{ 'E', { 0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F } },
	{ 'N', { 0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11 } },
	{ 'D', { 0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C } },
	{ 'V', { 0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04 } },
	{ 'I', { 0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E } },
	{ 'W', { 0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A } },
	{ 'A', { 0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11 } },
	{ 'G', { 0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F } },
	{ 'L', { 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F } },
	{ 'M', { 0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11 } },
	{ 'S', { 0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E } },
};

struct canvas {
	int w, h;
	uint8_t *px;
};

static void put(struct canvas *cv, int x, int y, const uint8_t rgb[3])
{
	if (x < 0 || y < 0 || x >= cv->w || y >= cv->h)
		return;
	memcpy(cv->px + ((size_t)y * cv->w + x) * 3, rgb, 3);
}

/* Text at (x, y), glyphs scaled by `s`. */
static void text(struct canvas *cv, int x, int y, int s, const char *str)
{
	static const uint8_t ink[3] = { 20, 20, 20 };

	for (; *str; str++, x += 6 * s) {
		for (size_t g = 0; g < sizeof(font) / sizeof(font[0]); g++) {
			if (font[g].c != *str)
				continue;
			for (int r = 0; r < 7; r++)
				for (int c = 0; c < 5; c++)
					if (font[g].rows[r] & (0x10 >> c))
						for (int dy = 0; dy < s; dy++)
							for (int dx = 0; dx < s;
							     dx++)
								put(cv,
								    x + c * s +
									    dx,
								    y + r * s +
									    dy,
								    ink);
		}
	}
}

/* Diverging map: -1 blue, 0 white, +1 red. */
static void diverging(double t, uint8_t rgb[3])
{
	t = t < -1 ? -1 : t > 1 ? 1 : t;
	double a = fabs(t);
	if (t < 0) {
		rgb[0] = (uint8_t)lrint(255 * (1 - a) + 33 * a);
		rgb[1] = (uint8_t)lrint(255 * (1 - a) + 102 * a);
		rgb[2] = (uint8_t)lrint(255 * (1 - a) + 172 * a);
	} else {
		rgb[0] = (uint8_t)lrint(255 * (1 - a) + 178 * a);
		rgb[1] = (uint8_t)lrint(255 * (1 - a) + 24 * a);
		rgb[2] = (uint8_t)lrint(255 * (1 - a) + 43 * a);
	}
}

static int cmp_d(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void fill(struct canvas *cv, int x0, int y0, int x1, int y1,
		 const uint8_t rgb[3])
{
	for (int y = y0; y <= y1; y++)
		for (int x = x0; x <= x1; x++)
			put(cv, x, y, rgb);
}

/* One residual plot in the box (x0, y0, pw x ph). */
static void plot(struct canvas *cv, int x0, int y0, int pw, int ph, int s,
		 const struct glint_compare_plot *p)
{
	static const uint8_t axis[3] = { 150, 150, 150 };
	static const uint8_t ink[3] = { 20, 20, 20 };
	static const uint8_t red[3] = { 178, 24, 43 };
	int top = 10 * s + 4, bottom = 10 * s + 4;
	int gy0 = y0 + top, gh = ph - top - bottom, zero = gy0 + gh / 2;
	double ymax = 0;
	char buf[32];

	for (int k = 0; k < p->n; k++)
		if (p->pixels[k] >= 20 && isfinite(p->mean[k]) &&
		    isfinite(p->se[k]))
			ymax = fmax(ymax, fabs(p->mean[k]) + 2 * p->se[k]);
	if (!(ymax > 0))
		ymax = 1e-6;
	text(cv, x0, y0, s, p->title);
	snprintf(buf, sizeof(buf), "+%.2g", ymax);
	text(cv, x0 + pw - (int)strlen(buf) * 6 * s, y0, s, buf);
	fill(cv, x0, zero, x0 + pw - 1, zero, axis);
	fill(cv, x0, gy0, x0, gy0 + gh, axis);
	for (int k = 0; k < p->n; k++) {
		int bx = x0 + (int)((k + 0.5) * pw / p->n);
		snprintf(buf, sizeof(buf), "%g", p->edges[k]);
		text(cv, x0 + k * pw / p->n + 2, gy0 + gh + 4, 1, buf);
		if (p->pixels[k] < 20 || !isfinite(p->mean[k]) ||
		    !isfinite(p->se[k]))
			continue;
		const uint8_t *c = fabs(p->mean[k]) > 5 * p->se[k] ? red : ink;
		double f = gh / 2.0 / ymax;
		int ym = zero - (int)lrint(p->mean[k] * f);
		int e = (int)lrint(2 * p->se[k] * f);
		fill(cv, bx, ym - e, bx, ym + e, c);
		fill(cv, bx - 2 * s, ym - 1 - s, bx + 2 * s, ym + 1 + s, c);
	}
}

int glint_compare_png(const char *path, const struct glint_image *photo,
		      const struct glint_image *render,
		      const struct glint_image *mask, double *scale_out)
{
	return glint_compare_png_plots(path, photo, render, mask, NULL, 0,
				       scale_out);
}

int glint_compare_png_plots(const char *path, const struct glint_image *photo,
			    const struct glint_image *render,
			    const struct glint_image *mask,
			    const struct glint_compare_plot *plots, int nplots,
			    double *scale_out)
{
	int w = photo->width, h = photo->height, gap = 6, s = w >= 256 ? 2 : 1;
	int top = 10 * s + 6, bar = 12, bottom = bar + 12 * s + 10;
	int ph = nplots ? (h / 2 > 120 ? h / 2 : 120) : 0;
	struct canvas cv = { 3 * w + 2 * gap, top + h + bottom + ph, NULL };
	size_t n = (size_t)w * h;
	double *err = malloc(n * sizeof(double)),
	       *mag = malloc(n * sizeof(double));
	int ret;

	if (render->width != w || render->height != h)
		return glint_error_set(EINVAL,
				       "compare: render %dx%d vs photo %dx%d",
				       render->width, render->height, w, h);
	cv.px = malloc((size_t)cv.w * cv.h * 3);
	if (!cv.px || !err || !mag) {
		free(cv.px);
		free(err);
		free(mag);
		return glint_error_set(ENOMEM, "out of memory");
	}
	memset(cv.px, 255, (size_t)cv.w * cv.h * 3);
	double scale = exp2(glint_png_auto_exposure(photo));
	size_t nm = 0;
	for (size_t i = 0; i < n; i++) {
		const float *a = photo->data + 3 * i, *b = render->data + 3 * i;
		err[i] = rgb_luminance(b[0], b[1], b[2]) -
			 rgb_luminance(a[0], a[1], a[2]);
		if ((!mask || mask->data[3 * i] > 0) && isfinite(err[i]))
			mag[nm++] = fabs(err[i]);
	}
	double es = 0;
	if (nm) {
		qsort(mag, nm, sizeof(double), cmp_d);
		es = mag[(size_t)(0.99 * (double)(nm - 1))];
	}
	if (!(es > 0))
		es = 1e-6;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			uint8_t a[3], b[3], e[3] = { 128, 128, 128 };
			for (int c = 0; c < 3; c++) {
				a[c] = glint_tonemap_srgb8(
					photo->data[3 * i + c] * scale);
				b[c] = glint_tonemap_srgb8(
					render->data[3 * i + c] * scale);
			}
			if ((!mask || mask->data[3 * i] > 0) &&
			    isfinite(err[i]))
				diverging(err[i] / es, e);
			put(&cv, x, top + y, a);
			put(&cv, w + gap + x, top + y, b);
			put(&cv, 2 * (w + gap) + x, top + y, e);
		}
	text(&cv, 2, 3, s, "PHOTO");
	text(&cv, w + gap + 2, 3, s, "RENDER");
	text(&cv, 2 * (w + gap) + 2, 3, s, "RENDER - PHOTO");
	/* Scale bar under the error panel. */
	int bx = 2 * (w + gap), by = top + h + 4;
	for (int x = 0; x < w; x++) {
		uint8_t c[3];
		diverging(2.0 * x / (w - 1) - 1, c);
		for (int y = 0; y < bar; y++)
			put(&cv, bx + x, by + y, c);
	}
	char lo[32], hi[32];
	snprintf(lo, sizeof(lo), "-%.3g", es);
	snprintf(hi, sizeof(hi), "+%.3g", es);
	text(&cv, bx, by + bar + 3, s, lo);
	text(&cv, bx + w / 2 - 3 * s, by + bar + 3, s, "0");
	text(&cv, bx + w - (int)strlen(hi) * 6 * s, by + bar + 3, s, hi);
	for (int k = 0; k < nplots; k++) {
		int pw = (cv.w - (nplots + 1) * 3 * gap) / nplots;
		plot(&cv, 3 * gap + k * (pw + 3 * gap), top + h + bottom, pw,
		     ph - gap, s, &plots[k]);
	}
	ret = glint_png_write_rgb8(path, cv.w, cv.h, cv.px);
	if (scale_out)
		*scale_out = es;
	free(cv.px);
	free(err);
	free(mag);
	return ret;
}
