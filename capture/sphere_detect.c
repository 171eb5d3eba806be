/* SPDX-License-Identifier: MIT */
#include "sphere_detect.h"

#include "core/error.h"
#include "core/vec.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int cmp_float(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

static double sample(const float *m, int w, int h, double x, double y)
{
	x = fmin(fmax(x, 0), w - 1.001);
	y = fmin(fmax(y, 0), h - 1.001);
	int ix = (int)x, iy = (int)y;
	double tx = x - ix, ty = y - iy;
	const float *p = m + (size_t)iy * w + ix;
	return (1 - ty) * ((1 - tx) * p[0] + tx * p[1]) +
	       ty * ((1 - tx) * p[w] + tx * p[w + 1]);
}

int glint_sphere_detect(const struct glint_image *img, double r_min,
			double r_max, struct glint_circle *out)
{
	int w = img->width, h = img->height, ret = 0;
	size_t n = (size_t)w * h;
	float *l = malloc(n * sizeof(float)), *gx = malloc(n * sizeof(float)),
	      *gy = malloc(n * sizeof(float)), *m = malloc(n * sizeof(float)),
	      *acc = calloc(n, sizeof(float)), *tmp = malloc(n * sizeof(float));
	unsigned char *edge = calloc(n, 1);
	double *px = NULL, *py = NULL;

	memset(out, 0, sizeof(*out));
	if (!l || !gx || !gy || !m || !acc || !tmp || !edge) {
		ret = glint_error_set(ENOMEM,
				      "sphere detection: out of memory");
		goto out;
	}
	if (w < 16 || h < 16) {
		ret = glint_error_set(
			EINVAL, "sphere detection: %dx%d image: too small", w,
			h);
		goto out;
	}
	if (r_min <= 0 || r_max <= 0) {
		r_min = 0.05 * (w < h ? w : h);
		r_max = 0.5 * (w < h ? w : h);
	}
	/* 1. log luminance, Sobel, thinning, strongest 6 %. */
	double mean = 0;
	for (size_t i = 0; i < n; i++) {
		const float *p = img->data + 3 * i;
		double v = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
		l[i] = (float)(isfinite(v) && v > 0 ? v : 0);
		mean += l[i];
	}
	mean /= (double)n;
	if (!(mean > 0)) {
		ret = glint_error_set(ERANGE,
				      "sphere detection: the image is black");
		goto out;
	}
	/* Linear gradient magnitude (for sub-pixel edge positions: the log
	 * would pull them towards the dark side) into acc, which is free. */
	for (int y = 1; y < h - 1; y++)
		for (int x = 1; x < w - 1; x++) {
			const float *p = l + (size_t)y * w + x;
			float ax = (p[-w + 1] + 2 * p[1] + p[w + 1]) -
				   (p[-w - 1] + 2 * p[-1] + p[w - 1]);
			float ay = (p[w - 1] + 2 * p[w] + p[w + 1]) -
				   (p[-w - 1] + 2 * p[-w] + p[-w + 1]);
			acc[(size_t)y * w + x] = hypotf(ax, ay);
		}
	for (size_t i = 0; i < n; i++)
		l[i] = (float)log(l[i] + 0.01 * mean);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			if (x == 0 || y == 0 || x == w - 1 || y == h - 1) {
				gx[i] = gy[i] = m[i] = 0;
				continue;
			}
			const float *p = l + i;
			gx[i] = (p[-w + 1] + 2 * p[1] + p[w + 1]) -
				(p[-w - 1] + 2 * p[-1] + p[w - 1]);
			gy[i] = (p[w - 1] + 2 * p[w] + p[w + 1]) -
				(p[-w - 1] + 2 * p[-w] + p[-w + 1]);
			m[i] = hypotf(gx[i], gy[i]);
		}
	/* The strongest 6 % of the non-flat pixels (a photo that is mostly
	 * black background has mostly zero gradient). */
	size_t nz = 0;
	for (size_t i = 0; i < n; i++)
		if (m[i] > 1e-6f)
			tmp[nz++] = m[i];
	qsort(tmp, nz, sizeof(float), cmp_float);
	float thr = nz ? tmp[(size_t)(0.94 * (double)(nz - 1))] : 0;
	if (!(thr > 0)) {
		ret = glint_error_set(ERANGE,
				      "sphere detection: no edges (a flat "
				      "image)");
		goto out;
	}
	long nedge = 0;
	for (int y = 1; y < h - 1; y++)
		for (int x = 1; x < w - 1; x++) {
			size_t i = (size_t)y * w + x;
			if (m[i] < thr)
				continue;
			double ux = gx[i] / m[i], uy = gy[i] / m[i];
			if (m[i] >= sample(m, w, h, x + ux, y + uy) &&
			    m[i] >= sample(m, w, h, x - ux, y - uy)) {
				edge[i] = 1;
				nedge++;
			}
		}
	/* 2-3. RANSAC: two edge points and the first one's gradient give a
	 * circle (its centre lies on that gradient line); the circle with
	 * the most edges on it (within 1.5 px, gradient along the radius)
	 * wins.  A silhouette is the longest such contour. */
	int *ex = malloc((size_t)nedge * sizeof(int));
	if (!ex) {
		ret = glint_error_set(ENOMEM,
				      "sphere detection: out of memory");
		goto out;
	}
	long ne = 0;
	for (size_t i = 0; i < n; i++)
		if (edge[i])
			ex[ne++] = (int)i;
	uint64_t rng = 0x9e3779b97f4a7c15ull;
	double bx = 0, by = 0, r0 = 0;
	long best = 0;
	for (int it = 0; it < 4000 && ne >= 2; it++) {
		rng ^= rng << 13;
		rng ^= rng >> 7;
		rng ^= rng << 17;
		size_t i1 = (size_t)ex[rng % (uint64_t)ne];
		size_t i2 = (size_t)ex[(rng >> 32) % (uint64_t)ne];
		double x1 = (double)(i1 % (size_t)w),
		       y1 = (double)(i1 / (size_t)w);
		double x2 = (double)(i2 % (size_t)w),
		       y2 = (double)(i2 / (size_t)w);
		double ux = gx[i1] / m[i1], uy = gy[i1] / m[i1];
		double dx = x1 - x2, dy = y1 - y2;
		double den = 2 * (ux * dx + uy * dy);
		if (fabs(den) < 1e-9)
			continue;
		double t = -(dx * dx + dy * dy) / den;
		double cx = x1 + t * ux, cy = y1 + t * uy, r = fabs(t);
		if (r < r_min || r > r_max)
			continue;
		/* The second point's gradient must be radial too. */
		double d2 = hypot(x2 - cx, y2 - cy);
		if (d2 <= 0 || fabs(((x2 - cx) * gx[i2] + (y2 - cy) * gy[i2]) /
				    (d2 * m[i2])) < 0.9)
			continue;
		long support = 0;
		for (long k = 0; k < ne; k++) {
			size_t e = (size_t)ex[k];
			double ex_ = (double)(e % (size_t)w) - cx,
			       ey_ = (double)(e / (size_t)w) - cy;
			double d = hypot(ex_, ey_);
			if (fabs(d - r) > 1.5 || d <= 0)
				continue;
			if (fabs((ex_ * gx[e] + ey_ * gy[e]) / (d * m[e])) >
			    0.9)
				support++;
		}
		if (support > best) {
			best = support;
			bx = cx;
			by = cy;
			r0 = r;
		}
	}
	free(ex);
	/* 4. sub-pixel edges near that circle, and a geometric fit. */
	px = malloc((size_t)nedge * sizeof(double));
	py = malloc((size_t)nedge * sizeof(double));
	if (!px || !py) {
		ret = glint_error_set(ENOMEM,
				      "sphere detection: out of memory");
		goto out;
	}
	double cx = bx + 0.5, cy = by + 0.5, r = r0;
	int np = 0;
	for (int pass = 0; pass < 3; pass++) {
		double band = pass == 0 ? 4 : 2;
		np = 0;
		for (int y = 1; y < h - 1; y++)
			for (int x = 1; x < w - 1; x++) {
				size_t i = (size_t)y * w + x;
				if (!edge[i])
					continue;
				double dx = x + 0.5 - cx, dy = y + 0.5 - cy,
				       d = hypot(dx, dy);
				if (d <= 0 || fabs(d - r) > band)
					continue;
				double ux = gx[i] / m[i], uy = gy[i] / m[i];
				if (fabs((dx * ux + dy * uy) / d) < 0.9)
					continue;
				double a = sample(acc, w, h, x - ux, y - uy),
				       b = acc[i],
				       c = sample(acc, w, h, x + ux, y + uy);
				double den = a - 2 * b + c, off = 0;
				if (den < 0)
					off = 0.5 * (a - c) / den;
				off = fmax(-0.5, fmin(0.5, off));
				/* Pixel (x, y) spans [x, x + 1): its centre
				 * is at + 0.5 (glint's image coordinates). */
				px[np] = x + 0.5 + off * ux;
				py[np] = y + 0.5 + off * uy;
				np++;
			}
		if (np < 8)
			break;
		for (int it = 0; it < 20; it++) {
			/* Gauss-Newton on (cx, cy, r), Huber weights at
			 * 0.5 px. */
			double jtj[3][3] = { { 0 } }, jtr[3] = { 0 };
			for (int k = 0; k < np; k++) {
				double dx = px[k] - cx, dy = py[k] - cy,
				       d = hypot(dx, dy);
				if (d <= 0)
					continue;
				double res = d - r,
				       wt = fabs(res) < 0.5 ? 1
							    : 0.5 / fabs(res);
				double j[3] = { -dx / d, -dy / d, -1 };
				for (int a = 0; a < 3; a++) {
					jtr[a] += wt * j[a] * res;
					for (int b = 0; b < 3; b++)
						jtj[a][b] += wt * j[a] * j[b];
				}
			}
			/* Solve jtj delta = -jtr (3 x 3, Cramer). */
			double(*A)[3] = jtj;
			double det = A[0][0] * (A[1][1] * A[2][2] -
						A[1][2] * A[2][1]) -
				     A[0][1] * (A[1][0] * A[2][2] -
						A[1][2] * A[2][0]) +
				     A[0][2] * (A[1][0] * A[2][1] -
						A[1][1] * A[2][0]);
			if (fabs(det) < 1e-12)
				break;
			double dlt[3];
			for (int c = 0; c < 3; c++) {
				double B[3][3];
				memcpy(B, A, sizeof(B));
				for (int rr = 0; rr < 3; rr++)
					B[rr][c] = -jtr[rr];
				dlt[c] = (B[0][0] * (B[1][1] * B[2][2] -
						     B[1][2] * B[2][1]) -
					  B[0][1] * (B[1][0] * B[2][2] -
						     B[1][2] * B[2][0]) +
					  B[0][2] * (B[1][0] * B[2][1] -
						     B[1][1] * B[2][0])) /
					 det;
			}
			cx += dlt[0];
			cy += dlt[1];
			r += dlt[2];
			if (fabs(dlt[0]) + fabs(dlt[1]) + fabs(dlt[2]) < 1e-6)
				break;
		}
	}
	if (np < 8 || !(r > 0)) {
		ret = glint_error_set(ENOENT,
				      "sphere detection: no circle found "
				      "between radius %.0f and %.0f px",
				      r_min, r_max);
		goto out;
	}
	/* Report: RMS and the arc the points cover (in 10-degree bins). */
	double ss = 0;
	int bins[36] = { 0 };
	for (int k = 0; k < np; k++) {
		double d = hypot(px[k] - cx, py[k] - cy) - r;
		ss += d * d;
		double a = atan2(py[k] - cy, px[k] - cx) * 180 / M_PI + 180;
		bins[(int)(a / 10) % 36] = 1;
	}
	int covered = 0;
	for (int k = 0; k < 36; k++)
		covered += bins[k];
	out->cx = cx;
	out->cy = cy;
	out->r = r;
	out->points = np;
	out->rms_px = sqrt(ss / np);
	out->arc_deg = 10.0 * covered;
out:
	free(l);
	free(gx);
	free(gy);
	free(m);
	free(acc);
	free(tmp);
	free(edge);
	free(px);
	free(py);
	return ret;
}

int glint_mask_circle(const struct glint_image *mask, struct glint_circle *out)
{
	double sx = 0, sy = 0, a = 0;
	memset(out, 0, sizeof(*out));
	for (int y = 0; y < mask->height; y++)
		for (int x = 0; x < mask->width; x++)
			if (glint_image_px(mask, x, y)[0] > 0.5) {
				sx += x + 0.5;
				sy += y + 0.5;
				a += 1;
			}
	if (a < 10)
		return glint_error_set(EINVAL, "mask: %g pixels set", a);
	out->cx = sx / a;
	out->cy = sy / a;
	out->r = sqrt(a / M_PI);
	out->points = (int)a;
	return 0;
}
