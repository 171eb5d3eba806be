/* SPDX-License-Identifier: MIT */
#include "probe_sim.h"

#include "core/error.h"
#include "core/parallel.h"

#include <complex.h>
#include <math.h>

/* Unpolarised Fresnel reflectance of a conductor eta = n + ik. */
static double fresnel(double n, double k, double cos_i)
{
	double complex eta = n + k * I;
	double s2 = 1 - cos_i * cos_i;
	double complex ct = csqrt(eta * eta - s2); /* eta cos(t) */
	double complex rs = (cos_i - ct) / (cos_i + ct);
	double complex rp = (eta * eta * cos_i - ct) / (eta * eta * cos_i + ct);
	return 0.5 * (creal(rs * conj(rs)) + creal(rp * conj(rp)));
}

/* Bilinear lat-long lookup: u = 0.5 + atan2(x, -z) / 2pi, v = acos(y) / pi
 * (docs/conventions.md), wrapping across, clamped at the poles. */
static void lookup(const struct glint_image *m, struct vec3 d, double rgb[3])
{
	double u = 0.5 + atan2(d.x, -d.z) / (2 * M_PI);
	double v = acos(fmax(-1, fmin(1, d.y))) / M_PI;
	double fx = u * m->width - 0.5, fy = v * m->height - 0.5;
	fy = fmin(fmax(fy, 0), m->height - 1);
	int x0 = (int)floor(fx), y0 = (int)floor(fy);
	double tx = fx - x0, ty = fy - y0;
	int y1 = y0 + 1 < m->height ? y0 + 1 : y0;
	int xa = ((x0 % m->width) + m->width) % m->width,
	    xb = ((x0 + 1) % m->width + m->width) % m->width;
	for (int c = 0; c < 3; c++)
		rgb[c] = (1 - ty) * ((1 - tx) * glint_image_px(m, xa, y0)[c] +
				     tx * glint_image_px(m, xb, y0)[c]) +
			 ty * ((1 - tx) * glint_image_px(m, xa, y1)[c] +
			       tx * glint_image_px(m, xb, y1)[c]);
}

struct ball_job {
	const struct glint_image *latlong;
	struct glint_image *img;
	double fpx, radius;
	struct vec3 centre;
	const double *n, *k;
	int spp;
};

/* Rows [y0, y1) of the ball's image: spp x spp rays a pixel. */
static void ball_rows(void *ctx, int y0, int y1, int thread)
{
	const struct ball_job *j = ctx;
	int w = j->img->width, h = j->img->height, spp = j->spp;
	/* one Fresnel evaluation where the channels share an ior */
	int same[3] = { 0, j->n[1] == j->n[0] && j->k[1] == j->k[0],
			j->n[2] == j->n[1] && j->k[2] == j->k[1] };

	(void)thread;
	for (int y = y0; y < y1; y++)
		for (int x = 0; x < w; x++) {
			double acc[3] = { 0, 0, 0 };
			for (int sy = 0; sy < spp; sy++)
				for (int sx = 0; sx < spp; sx++) {
					double px = x + (sx + 0.5) / spp,
					       py = y + (sy + 0.5) / spp;
					struct vec3 dir = v3_norm(v3(
						(px - w / 2.0) / j->fpx,
						-(py - h / 2.0) / j->fpx, -1));
					/* |t dir - c|^2 = r^2 */
					double bq = v3_dot(dir, j->centre);
					double disc =
						bq * bq -
						v3_dot(j->centre, j->centre) +
						j->radius * j->radius;
					if (disc < 0)
						continue;
					double t = bq - sqrt(disc);
					struct vec3 p = v3_scale(dir, t);
					struct vec3 nn =
						v3_scale(v3_sub(p, j->centre),
							 1 / j->radius);
					double c = -v3_dot(dir, nn);
					struct vec3 r = v3_add(
						dir, v3_scale(nn, 2 * c));
					double rgb[3], f = 0;
					lookup(j->latlong, r, rgb);
					for (int ch = 0; ch < 3; ch++) {
						if (!same[ch])
							f = fresnel(j->n[ch],
								    j->k[ch],
								    c);
						acc[ch] += rgb[ch] * f;
					}
				}
			float *o = glint_image_px(j->img, x, y);
			for (int ch = 0; ch < 3; ch++)
				o[ch] = (float)(acc[ch] / (spp * spp));
		}
}

int glint_sim_mirror_ball(const struct glint_image *latlong, int w, int h,
			  double fpx, struct vec3 centre, double radius,
			  const double n[3], const double k[3], int spp,
			  struct glint_image **out)
{
	struct ball_job j = { .latlong = latlong,
			      .img = glint_image_new(w, h),
			      .fpx = fpx,
			      .radius = radius,
			      .centre = centre,
			      .n = n,
			      .k = k,
			      .spp = spp };
	*out = NULL;
	if (!j.img)
		return glint_error_set(ENOMEM, "mirror ball: out of memory");
	/* threads that cannot start leave the rows to this one */
	if (glint_parallel_for(h, 4, 0, ball_rows, &j) < 0)
		glint_error_clear();
	*out = j.img;
	return 0;
}
