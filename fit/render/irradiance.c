/* SPDX-License-Identifier: MIT */
#include "irradiance.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct irr_job {
	struct glint_irradiance *ir;
	const double *lt;	/* reduced texels: radiance x solid angle */
	const struct vec3 *dir; /* their world directions */
	int n;
};

static void irr_rows(void *ctx, int y0, int y1, int thread)
{
	struct irr_job *job = ctx;
	struct glint_irradiance *ir = job->ir;

	(void)thread;
	for (int y = y0; y < y1; y++)
		for (int x = 0; x < ir->w; x++) {
			struct vec3 n = glint_envmap_uv_to_dir(
				(x + 0.5) / ir->w, (y + 0.5) / ir->h);
			double e[3] = { 0, 0, 0 };
			for (int k = 0; k < job->n; k++) {
				double c = v3_dot(n, job->dir[k]);
				if (c <= 0)
					continue;
				for (int ch = 0; ch < 3; ch++)
					e[ch] +=
						c * job->lt[3 * (size_t)k + ch];
			}
			memcpy(ir->e + ((size_t)y * ir->w + x) * 3, e,
			       sizeof(e));
		}
}

static int imin(int a, int b)
{
	return a < b ? a : b;
}

int glint_irradiance_build(const struct glint_envmap *env,
			   const unsigned char *exclude, int w, int nthreads,
			   struct glint_irradiance *ir)
{
	static const double k[3] = { 1.0 / 8, 6.0 / 8, 1.0 / 8 };
	const struct glint_image *img = env->img;
	int W = img->width, H = img->height;
	int f = W / 128 > 1 ? W / 128 : 1;
	/* Blocks of f x f texels; the last row and column of blocks may be
	 * narrower when f does not divide the size. */
	int dw = (W + f - 1) / f, dh = (H + f - 1) / f;
	double *lt = calloc((size_t)dw * dh * 3, sizeof(double));
	struct vec3 *dir = malloc((size_t)dw * dh * sizeof(struct vec3));

	ir->w = w;
	ir->h = w / 2;
	ir->e = calloc((size_t)ir->w * ir->h * 3, sizeof(double));
	if (!lt || !dir || !ir->e) {
		free(lt);
		free(dir);
		glint_irradiance_free(ir);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int j = 0; j < H; j++) {
		double t0 = M_PI * j / H, t1 = M_PI * (j + 1) / H;
		double omega = (2 * M_PI / W) * (cos(t0) - cos(t1));
		for (int i = 0; i < W; i++) {
			if (exclude && exclude[(size_t)j * W + i])
				continue;
			double *dst = lt + ((size_t)(j / f) * dw + i / f) * 3;
			for (int dy = -1; dy <= 1; dy++) {
				int y = j + dy < 0    ? 0
					: j + dy >= H ? H - 1
						      : j + dy;
				for (int dx = -1; dx <= 1; dx++) {
					int x = ((i + dx) % W + W) % W;
					const float *p =
						glint_image_px(img, x, y);
					for (int c = 0; c < 3; c++)
						dst[c] += k[dx + 1] *
							  k[dy + 1] * p[c] *
							  omega * env->scale;
				}
			}
		}
	}
	for (int j = 0; j < dh; j++)
		for (int i = 0; i < dw; i++)
			dir[(size_t)j * dw + i] = m3_mul(
				&env->rot,
				glint_envmap_uv_to_dir(
					(i * f + 0.5 * imin(f, W - i * f)) / W,
					(j * f + 0.5 * imin(f, H - j * f)) /
						H));
	struct irr_job job = { ir, lt, dir, dw * dh };
	glint_parallel_for(ir->h, 1, nthreads, irr_rows, &job);
	free(lt);
	free(dir);
	return 0;
}

void glint_irradiance_lookup(const struct glint_irradiance *ir, struct vec3 n,
			     double e[3])
{
	double u, v;

	glint_envmap_dir_to_uv(n, &u, &v);
	double x = u * ir->w - 0.5, y = v * ir->h - 0.5;
	double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
	int x0 = ((int)fx % ir->w + ir->w) % ir->w, x1 = (x0 + 1) % ir->w;
	int y0 = (int)fy, y1 = y0 + 1;
	y0 = y0 < 0 ? 0 : y0 >= ir->h ? ir->h - 1 : y0;
	y1 = y1 < 0 ? 0 : y1 >= ir->h ? ir->h - 1 : y1;
	const double *a = ir->e + ((size_t)y0 * ir->w + x0) * 3;
	const double *b = ir->e + ((size_t)y0 * ir->w + x1) * 3;
	const double *c = ir->e + ((size_t)y1 * ir->w + x0) * 3;
	const double *d = ir->e + ((size_t)y1 * ir->w + x1) * 3;
	for (int ch = 0; ch < 3; ch++)
		e[ch] = (1 - ty) * ((1 - tx) * a[ch] + tx * b[ch]) +
			ty * ((1 - tx) * c[ch] + tx * d[ch]);
}

void glint_irradiance_free(struct glint_irradiance *ir)
{
	free(ir->e);
	ir->e = NULL;
}
