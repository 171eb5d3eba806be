/* SPDX-License-Identifier: MIT */
#include "compare.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/plot.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static const uint8_t plot_ink[3] = { 20, 20, 20 };
static const uint8_t plot_red[3] = { 178, 24, 43 };

/* A band's mark: a dot at ym with a bar of half-height e. */
static void mark(struct glint_canvas *cv, int x, int ym, int e, int s,
		 const uint8_t c[3])
{
	glint_canvas_fill(cv, x, ym - e, x, ym + e, c);
	glint_canvas_fill(cv, x - 2 * s, ym - 1 - s, x + 2 * s, ym + 1 + s, c);
}

/* One residual plot in the box (x0, y0, pw x ph): its title, the y axis
 * (render - photo, luminance) with its range, the bands' edges in degrees
 * and the x axis's name under them. */
static void plot(struct glint_canvas *cv, int x0, int y0, int pw, int ph, int s,
		 const struct glint_compare_plot *p)
{
	static const uint8_t axis[3] = { 150, 150, 150 };
	const uint8_t *ink = plot_ink, *red = plot_red;
	int top = 20 * s + 4, bottom = 20 * s + 8;
	int gy0 = y0 + top, gh = ph - top - bottom, zero = gy0 + gh / 2;
	double ymax = 0;
	char buf[32];

	for (int k = 0; k < p->n; k++)
		if (p->pixels[k] >= 20 && isfinite(p->mean[k]) &&
		    isfinite(p->se[k]))
			ymax = fmax(ymax, fabs(p->mean[k]) + 2 * p->se[k]);
	if (!(ymax > 0))
		ymax = 1e-6;
	glint_canvas_text(cv, x0, y0, s, p->title);
	glint_canvas_text(cv, x0, y0 + 10 * s, 1, "MEAN RENDER - PHOTO");
	snprintf(buf, sizeof(buf), "+%.2g", ymax);
	glint_canvas_text(cv, x0 + pw - (int)strlen(buf) * 6, gy0 + 2, 1, buf);
	snprintf(buf, sizeof(buf), "-%.2g", ymax);
	glint_canvas_text(cv, x0 + pw - (int)strlen(buf) * 6, gy0 + gh - 8, 1,
			  buf);
	glint_canvas_text(cv, x0 + pw - 6, zero - 9, 1, "0");
	/* Every edge's label that has room (every other one, ...). */
	int step = 1;
	for (int k = 0; k <= p->n; k++) {
		snprintf(buf, sizeof(buf), "%g", p->edges[k]);
		while (step < p->n &&
		       (int)strlen(buf) * 6 + 3 > step * pw / p->n)
			step++;
	}
	glint_canvas_fill(cv, x0, zero, x0 + pw - 1, zero, axis);
	glint_canvas_fill(cv, x0, gy0, x0, gy0 + gh, axis);
	glint_canvas_fill(cv, x0, gy0, x0 + 3, gy0, axis);
	glint_canvas_fill(cv, x0, gy0 + gh, x0 + 3, gy0 + gh, axis);
	glint_canvas_text(cv, x0, gy0 + gh + 14, 1,
			  p->xlabel ? p->xlabel : "DEGREES");
	for (int k = 0; k < p->n; k++) {
		int bx = x0 + (int)((k + 0.5) * pw / p->n);
		snprintf(buf, sizeof(buf), "%g", p->edges[k]);
		glint_canvas_fill(cv, x0 + k * pw / p->n, gy0 + gh - 2,
				  x0 + k * pw / p->n, gy0 + gh + 2, axis);
		if (k % step == 0)
			glint_canvas_text(cv, x0 + k * pw / p->n + 1,
					  gy0 + gh + 4, 1, buf);
		if (p->pixels[k] < 20 || !isfinite(p->mean[k]) ||
		    !isfinite(p->se[k]))
			continue;
		const uint8_t *c = fabs(p->mean[k]) > 5 * p->se[k] ? red : ink;
		double f = gh / 2.0 / ymax;
		int ym = zero - (int)lrint(p->mean[k] * f);
		int e = (int)lrint(2 * p->se[k] * f);
		mark(cv, bx, ym, e, s, c);
	}
}

/* The plots' legend, one line at (x, y). */
static void legend(struct glint_canvas *cv, int x, int y, int s)
{
	mark(cv, x + 3 * s, y + 3, 4, s, plot_ink);
	glint_canvas_text(cv, x + 8 * s, y, 1, "MEAN +-2 S.E.");
	x += 8 * s + 13 * 6 + 12;
	mark(cv, x + 3 * s, y + 3, 4, s, plot_red);
	glint_canvas_text(cv, x + 8 * s, y, 1, "BEYOND 5 S.E.");
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
	int ph = nplots ? (h / 2 > 150 ? h / 2 : 150) + 14 : 0;
	struct glint_canvas cv = { 0 };
	size_t n = (size_t)w * h;
	int ret;

	if (render->width != w || render->height != h)
		return glint_error_set(EINVAL,
				       "compare: render %dx%d vs photo %dx%d",
				       render->width, render->height, w, h);
	double *err = malloc(n * sizeof(double)),
	       *mag = malloc(n * sizeof(double));
	if (!err || !mag ||
	    glint_canvas_init(&cv, 3 * w + 2 * gap, top + h + bottom + ph) <
		    0) {
		free(err);
		free(mag);
		return glint_error_set(ENOMEM, "out of memory");
	}
	double scale = exp2(glint_png_auto_exposure(photo));
	size_t nm = 0;
	for (size_t i = 0; i < n; i++) {
		const float *a = photo->data + 3 * i, *b = render->data + 3 * i;
		err[i] = rgb_luminance(b[0], b[1], b[2]) -
			 rgb_luminance(a[0], a[1], a[2]);
		/* The scale from the pixels the sphere covers whole: a
		 * blurred rim, half sphere and half background, would set it
		 * and leave the rest of the panel white. */
		if ((!mask || mask->data[3 * i] >= 0.999f) && isfinite(err[i]))
			mag[nm++] = fabs(err[i]);
	}
	if (!nm) /* no whole pixel: every one on the sphere */
		for (size_t i = 0; i < n; i++)
			if ((!mask || mask->data[3 * i] > 0) &&
			    isfinite(err[i]))
				mag[nm++] = fabs(err[i]);
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
			glint_canvas_put(&cv, x, top + y, a);
			glint_canvas_put(&cv, w + gap + x, top + y, b);
			glint_canvas_put(&cv, 2 * (w + gap) + x, top + y, e);
		}
	glint_canvas_text(&cv, 2, 3, s, "PHOTO");
	glint_canvas_text(&cv, w + gap + 2, 3, s, "RENDER");
	glint_canvas_text(&cv, 2 * (w + gap) + 2, 3, s, "RENDER - PHOTO");
	/* Scale bar under the error panel. */
	int bx = 2 * (w + gap), by = top + h + 4;
	for (int x = 0; x < w; x++) {
		uint8_t c[3];
		diverging(2.0 * x / (w - 1) - 1, c);
		for (int y = 0; y < bar; y++)
			glint_canvas_put(&cv, bx + x, by + y, c);
	}
	char lo[32], hi[32];
	snprintf(lo, sizeof(lo), "-%.2g", es);
	snprintf(hi, sizeof(hi), "+%.2g", es);
	glint_canvas_text(&cv, bx, by + bar + 3, s, lo);
	if ((int)strlen(lo) * 6 * s + 6 * s < w / 2 - 3 * s)
		glint_canvas_text(&cv, bx + w / 2 - 3 * s, by + bar + 3, s,
				  "0");
	glint_canvas_text(&cv, bx + w - (int)strlen(hi) * 6 * s, by + bar + 3,
			  s, hi);
	for (int k = 0; k < nplots; k++) {
		int pw = (cv.w - (nplots + 1) * 3 * gap) / nplots;
		plot(&cv, 3 * gap + k * (pw + 3 * gap), top + h + bottom, pw,
		     ph - gap - 14, s, &plots[k]);
	}
	if (nplots)
		legend(&cv, 3 * gap, top + h + bottom + ph - 14, s);
	ret = glint_canvas_write_png(&cv, path);
	if (scale_out)
		*scale_out = es;
	glint_canvas_free(&cv);
	free(err);
	free(mag);
	return ret;
}
