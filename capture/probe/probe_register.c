/* SPDX-License-Identifier: MIT */
#include "capture/probe/probe_register.h"

#include "capture/probe/probe.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/path.h"

#include <errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double glint_rotation_angle_deg(const struct mat3 *a, const struct mat3 *b)
{
	/* trace(a^T b) = 1 + 2 cos(angle) */
	double tr = 0;
	for (int i = 0; i < 3; i++)
		for (int k = 0; k < 3; k++)
			tr += a->m[k][i] * b->m[k][i];
	return acos(fmax(-1, fmin(1, 0.5 * (tr - 1)))) * 180 / M_PI;
}

int glint_register_points(const struct vec3 *a, const struct vec3 *b, int n,
			  struct mat3 *r, double *rms_deg)
{
	if (n < 2)
		return glint_error_set(EINVAL,
				       "registration: %d correspondence(s): "
				       "need at least 2",
				       n);
	/* B = sum a_i b_i^T; R = U diag(1, 1, det(U V^T)) V^T. */
	gsl_matrix *u = gsl_matrix_calloc(3, 3), *v = gsl_matrix_alloc(3, 3);
	gsl_vector *s = gsl_vector_alloc(3), *work = gsl_vector_alloc(3);
	for (int i = 0; i < n; i++) {
		double av[3] = { a[i].x, a[i].y, a[i].z },
		       bv[3] = { b[i].x, b[i].y, b[i].z };
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++)
				gsl_matrix_set(u, (size_t)p, (size_t)q,
					       gsl_matrix_get(u, (size_t)p,
							      (size_t)q) +
						       av[p] * bv[q]);
	}
	int ret = gsl_linalg_SV_decomp(u, v, s, work)
			  ? glint_error_set(EDOM, "registration: SVD failed")
			  : 0;
	if (ret == 0 && gsl_vector_get(s, 1) < 1e-9 * gsl_vector_get(s, 0))
		ret = glint_error_set(EDOM,
				      "registration: the correspondences are "
				      "all along one direction");
	if (ret == 0) {
		double det = 0;
		struct mat3 uu, vv;
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++) {
				uu.m[p][q] =
					gsl_matrix_get(u, (size_t)p, (size_t)q);
				vv.m[p][q] =
					gsl_matrix_get(v, (size_t)p, (size_t)q);
			}
		struct mat3 t;
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++) {
				t.m[p][q] = 0;
				for (int k = 0; k < 3; k++)
					t.m[p][q] += uu.m[p][k] * vv.m[q][k];
			}
		det = t.m[0][0] *
			      (t.m[1][1] * t.m[2][2] - t.m[1][2] * t.m[2][1]) -
		      t.m[0][1] *
			      (t.m[1][0] * t.m[2][2] - t.m[1][2] * t.m[2][0]) +
		      t.m[0][2] *
			      (t.m[1][0] * t.m[2][1] - t.m[1][1] * t.m[2][0]);
		double dg[3] = { 1, 1, det < 0 ? -1 : 1 };
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++) {
				r->m[p][q] = 0;
				for (int k = 0; k < 3; k++)
					r->m[p][q] +=
						uu.m[p][k] * dg[k] * vv.m[q][k];
			}
		if (rms_deg) {
			double ss = 0;
			for (int i = 0; i < n; i++) {
				struct vec3 rb = m3_mul(r, b[i]);
				double c = v3_dot(v3_norm(a[i]), v3_norm(rb));
				double ang = acos(fmax(-1, fmin(1, c)));
				ss += ang * ang;
			}
			*rms_deg = sqrt(ss / n) * 180 / M_PI;
		}
	}
	gsl_matrix_free(u);
	gsl_matrix_free(v);
	gsl_vector_free(s);
	gsl_vector_free(work);
	return ret;
}

/* Log luminance and weight of a lat-long map resampled to w x h. */
struct small {
	int w, h;
	float *ll, *wt;
};

static int shrink(const struct glint_image *env, const struct glint_image *m,
		  int w, int h, struct small *s)
{
	struct glint_image *e = NULL, *mm = NULL;
	int ret = glint_probe_convert(env, GLINT_PROBE_LATLONG,
				      GLINT_PROBE_LATLONG, w, h, &e);
	if (ret == 0 && m)
		ret = glint_probe_convert(m, GLINT_PROBE_LATLONG,
					  GLINT_PROBE_LATLONG, w, h, &mm);
	s->w = w;
	s->h = h;
	s->ll = malloc(sizeof(float) * w * h);
	s->wt = malloc(sizeof(float) * w * h);
	if (ret == 0 && (!s->ll || !s->wt))
		ret = glint_error_set(ENOMEM, "registration: out of memory");
	for (int i = 0; ret == 0 && i < w * h; i++) {
		const float *p = e->data + 3 * i;
		double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
		s->ll[i] = (float)log(fmax(l, 1e-6));
		double wm = mm ? mm->data[3 * i] : 1;
		/* sin(theta): texels shrink towards the poles. */
		s->wt[i] = (float)((wm > 0.99 && l > 0) *
				   sin(M_PI * (i / w + 0.5) / h));
	}
	glint_image_free(e);
	glint_image_free(mm);
	return ret;
}

static double cost_of(const struct small *a, const struct small *b,
		      const struct mat3 *r)
{
	double sw = 0, swd = 0;
	for (int y = 0; y < a->h; y++)
		for (int x = 0; x < a->w; x++) {
			int i = y * a->w + x;
			if (a->wt[i] <= 0)
				continue;
			struct vec3 d;
			glint_probe_pixel_dir(GLINT_PROBE_LATLONG, a->w, a->h,
					      x + 0.5, y + 0.5, &d);
			struct vec3 d2 = m3_tmul(r, d);
			double px, py;
			glint_probe_dir_pixel(GLINT_PROBE_LATLONG, b->w, b->h,
					      d2, &px, &py);
			int bx = (int)px % b->w, by = (int)py;
			if (by < 0 || by >= b->h)
				continue;
			int j = by * b->w + (bx < 0 ? bx + b->w : bx);
			if (b->wt[j] <= 0)
				continue;
			double dl = a->ll[i] - b->ll[j];
			sw += a->wt[i];
			swd += a->wt[i] * dl * dl;
		}
	/* Too little overlap is no evidence. */
	return sw > 0.05 * a->w * a->h ? swd / sw : INFINITY;
}

static struct mat3 euler(const struct mat3 *g, double rx, double ry, double rz)
{
	struct mat3 d = m3_rotation_xyz_deg(rx, ry, rz);
	return m3_mul_m3(&d, g);
}

int glint_register_auto(const struct glint_image *env1,
			const struct glint_image *mask1,
			const struct glint_image *env2,
			const struct glint_image *mask2,
			const struct mat3 *guess, struct mat3 *r, double *cost)
{
	struct small a[2] = { { 0 } }, b[2] = { { 0 } };
	static const int sizes[2][2] = { { 64, 32 }, { 128, 64 } };
	int ret = 0;
	for (int k = 0; k < 2 && ret == 0; k++) {
		ret = shrink(env1, mask1, sizes[k][0], sizes[k][1], &a[k]);
		if (ret == 0)
			ret = shrink(env2, mask2, sizes[k][0], sizes[k][1],
				     &b[k]);
	}
	if (ret < 0)
		goto out;
	/* Coarse: yaw every 5 degrees, pitch and roll every 5 within 10. */
	double best = INFINITY, by = 0, bp = 0, br = 0;
	for (double yaw = -180; yaw < 180; yaw += 5)
		for (double p = -10; p <= 10; p += 5)
			for (double rl = -10; rl <= 10; rl += 5) {
				struct mat3 m = euler(guess, p, yaw, rl);
				double c = cost_of(&a[0], &b[0], &m);
				if (c < best) {
					best = c;
					by = yaw;
					bp = p;
					br = rl;
				}
			}
	if (!isfinite(best)) {
		ret = glint_error_set(ERANGE,
				      "registration: the views do not overlap "
				      "where both are reliable");
		goto out;
	}
	/* Fine: coordinate descent with shrinking steps, on 128 x 64. */
	double x[3] = { bp, by, br }, step = 4;
	struct mat3 m0 = euler(guess, x[0], x[1], x[2]);
	best = cost_of(&a[1], &b[1], &m0);
	while (step > 0.05) {
		int moved = 0;
		for (int k = 0; k < 3; k++)
			for (int s = -1; s <= 1; s += 2) {
				double y[3] = { x[0], x[1], x[2] };
				y[k] += s * step;
				struct mat3 m = euler(guess, y[0], y[1], y[2]);
				double c = cost_of(&a[1], &b[1], &m);
				if (c < best) {
					best = c;
					memcpy(x, y, sizeof(x));
					moved = 1;
				}
			}
		if (!moved)
			step *= 0.5;
	}
	*r = euler(guess, x[0], x[1], x[2]);
	if (cost)
		*cost = best;
out:
	for (int k = 0; k < 2; k++) {
		free(a[k].ll);
		free(a[k].wt);
		free(b[k].ll);
		free(b[k].wt);
	}
	return ret;
}

int glint_probe_blend(const struct glint_image *env1,
		      const struct glint_image *w1,
		      const struct glint_image *env2,
		      const struct glint_image *w2, const struct mat3 *r,
		      struct glint_image **out)
{
	int w = env1->width, h = env1->height;
	struct glint_image *o = glint_image_new(w, h);
	*out = NULL;
	if (!o)
		return glint_error_set(ENOMEM, "blend: out of memory");
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			struct vec3 d;
			float c2[3], wt2[3] = { 1, 1, 1 };
			glint_probe_pixel_dir(GLINT_PROBE_LATLONG, w, h,
					      x + 0.5, y + 0.5, &d);
			struct vec3 d2 = m3_tmul(r, d);
			glint_probe_lookup(env2, GLINT_PROBE_LATLONG, d2, c2);
			if (w2)
				glint_probe_lookup(w2, GLINT_PROBE_LATLONG, d2,
						   wt2);
			const float *c1 = glint_image_px(env1, x, y);
			double a = w1 ? glint_image_px(w1, x, y)[0] : 1,
			       b = wt2[0];
			float *p = glint_image_px(o, x, y);
			for (int c = 0; c < 3; c++)
				p[c] = a + b > 0 ? (float)((a * c1[c] +
							    b * c2[c]) /
							   (a + b))
						 : 0.5f * (c1[c] + c2[c]);
		}
	*out = o;
	return 0;
}

/* ENV-mask.png x ENV-density.exr, or NULL when absent. */
struct glint_image *glint_probe_view_weight(const char *env)
{
	char mp[GLINT_PATH_MAX], dp[GLINT_PATH_MAX];
	struct glint_image *m = NULL, *d = NULL;
	if (glint_path_sibling(mp, sizeof(mp), env, "-mask.png") < 0 ||
	    glint_path_sibling(dp, sizeof(dp), env, "-density.exr") < 0 ||
	    glint_image_read(mp, &m) < 0 || glint_image_read(dp, &d) < 0 ||
	    m->width != d->width || m->height != d->height) {
		glint_image_free(m);
		glint_image_free(d);
		glint_error_clear();
		return NULL;
	}
	for (size_t i = 0; i < (size_t)m->width * m->height * 3; i++)
		m->data[i] = (m->data[i] > 0.5f) * d->data[i];
	glint_image_free(d);
	return m;
}

int glint_register_points_file(const char *path, const struct glint_image *e1,
			       const struct glint_image *e2, struct mat3 *r,
			       double *rms_deg)
{
	struct vec3 a[256], b[256];
	double x1, y1, x2, y2;
	int n = 0, ret = 0;
	FILE *f = glint_fopen_regular(path, "r");

	if (!f)
		return -errno;
	while (n < 256 &&
	       fscanf(f, " %lf %lf %lf %lf", &x1, &y1, &x2, &y2) == 4) {
		glint_probe_pixel_dir(GLINT_PROBE_LATLONG, e1->width,
				      e1->height, x1, y1, &a[n]);
		glint_probe_pixel_dir(GLINT_PROBE_LATLONG, e2->width,
				      e2->height, x2, y2, &b[n]);
		n++;
	}
	if (!feof(f))
		ret = glint_error_set(EINVAL,
				      "%s: line %d: expected 'x1 y1 x2 y2' "
				      "(lat-long pixels%s)",
				      path, n + 1,
				      n == 256 ? ", at most 256 lines" : "");
	fclose(f);
	return ret < 0 ? ret : glint_register_points(a, b, n, r, rms_deg);
}
