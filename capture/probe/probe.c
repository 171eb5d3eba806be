/* SPDX-License-Identifier: MIT */
#include "capture/probe/probe.h"
#include "capture/probe/probe_internal.h"
#include "capture/probe/probe_sources.h"

#include "capture/probe/sphere_detect.h"

#include "core/error.h"
#include "core/log.h"
#include "core/formats.h"
#include "core/path.h"
#include "core/optics.h"
#include "core/pinhole.h"
#include "core/plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const names[] = { "latlong", "angular", "cross", "ball" };

int glint_probe_format_parse(const char *name, enum glint_probe_format *f)
{
	for (int i = 0; i < 4; i++)
		if (!strcmp(name, names[i])) {
			*f = (enum glint_probe_format)i;
			return 0;
		}
	return glint_error_set(EINVAL,
			       "probe format '%s': expected latlong, angular, "
			       "cross or ball",
			       name);
}

const char *glint_probe_format_name(enum glint_probe_format f)
{
	return names[f];
}

/* Cube cross faces: column, row, and the face's direction from (a, b) in
 * [-1, 1]^2 (a right, b down). */
enum { PX, NX, PY, NY, PZ, NZ };
static const int face_col[6] = { 2, 0, 1, 1, 1, 1 };
static const int face_row[6] = { 1, 1, 0, 2, 3, 1 };

static struct vec3 face_dir(int f, double a, double b)
{
	switch (f) {
	case PX:
		return v3(1, -b, a);
	case NX:
		return v3(-1, -b, -a);
	case PY:
		return v3(a, 1, -b);
	case NY:
		return v3(a, -1, b);
	case PZ:
		return v3(a, b, 1);
	default:
		return v3(a, -b, -1);
	}
}

static int dir_face(struct vec3 d, double *a, double *b)
{
	double ax = fabs(d.x), ay = fabs(d.y), az = fabs(d.z);
	if (ax >= ay && ax >= az) {
		*b = -d.y / ax;
		*a = d.x > 0 ? d.z / ax : -d.z / ax;
		return d.x > 0 ? PX : NX;
	}
	if (ay >= az) {
		*a = d.x / ay;
		*b = d.y > 0 ? -d.z / ay : d.z / ay;
		return d.y > 0 ? PY : NY;
	}
	*a = d.x / az;
	*b = d.z > 0 ? d.y / az : -d.y / az;
	return d.z > 0 ? PZ : NZ;
}

int glint_probe_pixel_dir(enum glint_probe_format f, int w, int h, double x,
			  double y, struct vec3 *d)
{
	switch (f) {
	case GLINT_PROBE_LATLONG:
		*d = glint_latlong_uv_to_dir(x / w, y / h);
		return 1;
	case GLINT_PROBE_ANGULAR:
	case GLINT_PROBE_BALL: {
		double u = 2 * x / w - 1, v = 1 - 2 * y / h;
		double r = hypot(u, v);
		if (r > 1)
			return 0;
		if (f == GLINT_PROBE_ANGULAR) {
			double th = M_PI * r, s = r > 0 ? sin(th) / r : 0;
			*d = v3(u * s, v * s, -cos(th));
		} else {
			double nz = sqrt(fmax(0, 1 - r * r));
			*d = v3(2 * nz * u, 2 * nz * v, 2 * nz * nz - 1);
		}
		return 1;
	}
	case GLINT_PROBE_CROSS: {
		double s = w / 3.0;
		int col = (int)floor(x / s), row = (int)floor(y / s);
		for (int fc = 0; fc < 6; fc++)
			if (face_col[fc] == col && face_row[fc] == row) {
				double a = 2 * (x / s - col) - 1,
				       b = 2 * (y / s - row) - 1;
				*d = v3_norm(face_dir(fc, a, b));
				return 1;
			}
		return 0;
	}
	}
	return 0;
}

void glint_probe_dir_pixel(enum glint_probe_format f, int w, int h,
			   struct vec3 d, double *x, double *y)
{
	switch (f) {
	case GLINT_PROBE_LATLONG: {
		double u, v;
		glint_latlong_dir_to_uv(d, &u, &v);
		*x = u * w;
		*y = v * h;
		return;
	}
	case GLINT_PROBE_ANGULAR:
	case GLINT_PROBE_BALL: {
		double u = 0, v = 0;
		if (f == GLINT_PROBE_ANGULAR) {
			double th = acos(fmax(-1, fmin(1, -d.z)));
			double s = hypot(d.x, d.y);
			if (s > 0) {
				u = th / M_PI * d.x / s;
				v = th / M_PI * d.y / s;
			}
		} else {
			struct vec3 n = v3_add(d, v3(0, 0, 1));
			double l = v3_len(n);
			if (l > 0) {
				u = n.x / l;
				v = n.y / l;
			} else {
				u = 1; /* straight back: the rim */
			}
		}
		*x = (u + 1) * 0.5 * w;
		*y = (1 - v) * 0.5 * h;
		return;
	}
	case GLINT_PROBE_CROSS: {
		double a, b, s = w / 3.0;
		int fc = dir_face(d, &a, &b);
		*x = (face_col[fc] + (a + 1) / 2) * s;
		*y = (face_row[fc] + (b + 1) / 2) * s;
		return;
	}
	}
}

void glint_probe_lookup(const struct glint_image *img,
			enum glint_probe_format f, struct vec3 d, float rgb[3])
{
	double x, y, x0 = 0.5, x1 = img->width - 0.5, y0 = 0.5,
		     y1 = img->height - 0.5;
	glint_probe_dir_pixel(f, img->width, img->height, d, &x, &y);
	if (f == GLINT_PROBE_CROSS) { /* stay inside the face */
		double s = img->width / 3.0;
		int col = (int)floor(x / s), row = (int)floor(y / s);
		col = col < 0 ? 0 : col > 2 ? 2 : col;
		row = row < 0 ? 0 : row > 3 ? 3 : row;
		x0 = col * s + 0.5;
		x1 = (col + 1) * s - 0.5;
		y0 = row * s + 0.5;
		y1 = (row + 1) * s - 0.5;
	}
	int wrap = f == GLINT_PROBE_LATLONG;
	if (!wrap)
		x = fmin(fmax(x, x0), x1);
	y = fmin(fmax(y, y0), y1);
	double fx = x - 0.5, fy = y - 0.5;
	int ix = (int)floor(fx), iy = (int)floor(fy);
	double tx = fx - ix, ty = fy - iy;
	int xa = ix, xb = ix + 1, ya = iy, yb = iy + 1;
	if (wrap) {
		xa = ((xa % img->width) + img->width) % img->width;
		xb = ((xb % img->width) + img->width) % img->width;
	} else {
		xa = xa < 0 ? 0 : xa >= img->width ? img->width - 1 : xa;
		xb = xb < 0 ? 0 : xb >= img->width ? img->width - 1 : xb;
	}
	ya = ya < 0 ? 0 : ya >= img->height ? img->height - 1 : ya;
	yb = yb < 0 ? 0 : yb >= img->height ? img->height - 1 : yb;
	const float *p00 = glint_image_px(img, xa, ya),
		    *p10 = glint_image_px(img, xb, ya),
		    *p01 = glint_image_px(img, xa, yb),
		    *p11 = glint_image_px(img, xb, yb);
	for (int c = 0; c < 3; c++)
		rgb[c] = (float)((1 - ty) * ((1 - tx) * p00[c] + tx * p10[c]) +
				 ty * ((1 - tx) * p01[c] + tx * p11[c]));
}

static void default_size(const struct glint_image *src,
			 enum glint_probe_format from,
			 enum glint_probe_format to, int *w, int *h)
{
	/* Keep the angular resolution: an angular or ball image of side S,
	 * a lat-long of width S and a cross of face S / 4 all have about
	 * 2 pi / S radians per pixel around the horizon. */
	int s = from == GLINT_PROBE_LATLONG ? src->width
		: from == GLINT_PROBE_CROSS ? src->width / 3 * 4
					    : src->width;
	if (to == GLINT_PROBE_LATLONG) {
		*w = s;
		*h = s / 2;
	} else if (to == GLINT_PROBE_CROSS) {
		*w = s / 4 * 3;
		*h = s / 4 * 4;
	} else {
		*w = *h = s;
	}
}

int glint_probe_convert(const struct glint_image *src,
			enum glint_probe_format from,
			enum glint_probe_format to, int w, int h,
			struct glint_image **out)
{
	*out = NULL;
	if ((from == GLINT_PROBE_ANGULAR || from == GLINT_PROBE_BALL) &&
	    src->width != src->height)
		return glint_error_set(EINVAL,
				       "%s probe is %dx%d: expected a square "
				       "image",
				       names[from], src->width, src->height);
	if (from == GLINT_PROBE_CROSS &&
	    (src->width * 4 != src->height * 3 || src->width % 3))
		return glint_error_set(EINVAL,
				       "cross probe is %dx%d: expected 3:4 "
				       "faces (3s x 4s)",
				       src->width, src->height);
	if (w <= 0 || h <= 0)
		default_size(src, from, to, &w, &h);
	if (w < 2 || h < 2)
		return glint_error_set(EINVAL, "probe output %dx%d: too small",
				       w, h);
	struct glint_image *img = glint_image_new(w, h);
	if (!img)
		return glint_error_set(ENOMEM, "probe: out of memory");
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y), rgb[3];
			double acc[3] = { 0, 0, 0 };
			int k = 0;
			for (int s = 0; s < 4; s++) {
				struct vec3 d;
				if (!glint_probe_pixel_dir(
					    to, w, h, x + 0.25 + 0.5 * (s & 1),
					    y + 0.25 + 0.5 * (s >> 1), &d))
					continue;
				glint_probe_lookup(src, from, d, rgb);
				for (int c = 0; c < 3; c++)
					acc[c] += rgb[c];
				k++;
			}
			for (int c = 0; c < 3; c++)
				p[c] = k ? (float)(acc[c] / k) : 0;
		}
	*out = img;
	return 0;
}

void glint_unwrap_default_opts(struct glint_unwrap_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->cx = o->cy = -1;
	for (int c = 0; c < 3; c++) {
		o->n[c] = 3.2;
		o->k[c] = 3.3;
	}
	o->grazing_deg = 80;
	o->camera_cone_deg = 6;
}

/* (capture/probe/probe_internal.h) */
int glint_probe_ball_image(const struct probe_ball *b, struct vec3 d, double *x,
			   double *y, double *ci)
{
	struct vec3 i = v3_norm(b->c), n = i;
	if (b->ortho) {
		n = v3_norm(v3_sub(d, i));
		*ci = -v3_dot(i, n);
		struct vec3 right = v3_norm(v3_cross(i, v3(0, 1, 0)));
		struct vec3 up = v3_cross(right, i);
		*x = b->bcx + b->br * v3_dot(n, right);
		*y = b->bcy - b->br * v3_dot(n, up);
		return *ci > 0;
	}
	for (int it = 0; it < 50; it++) {
		n = v3_norm(v3_sub(d, i));
		struct vec3 ni = v3_norm(v3_add(b->c, n));
		double moved = v3_len(v3_sub(ni, i));
		i = ni;
		if (moved < 1e-12)
			break;
	}
	n = v3_norm(v3_sub(d, i));
	*ci = -v3_dot(i, n);
	struct vec3 p = v3_add(b->c, n);
	if (p.z >= 0 || *ci <= 0)
		return 0;
	*x = b->cx + b->fpx * p.x / -p.z;
	*y = b->cy - b->fpx * p.y / -p.z;
	return 1;
}

int glint_probe_ball_normal(const struct probe_ball *b, double x, double y,
			    struct vec3 *n, struct vec3 *ray)
{
	if (b->ortho) {
		struct vec3 i = v3_norm(b->c);
		struct vec3 right = v3_norm(v3_cross(i, v3(0, 1, 0)));
		struct vec3 up = v3_cross(right, i);
		double u = (x - b->bcx) / b->br, v = -(y - b->bcy) / b->br;
		double w2 = 1 - u * u - v * v;
		if (w2 <= 0)
			return 0;
		*ray = i;
		*n = v3_add(v3_add(v3_scale(right, u), v3_scale(up, v)),
			    v3_scale(i, -sqrt(w2)));
		return 1;
	}
	*ray = v3_norm(v3((x - b->cx) / b->fpx, -(y - b->cy) / b->fpx, -1));
	double bq = v3_dot(*ray, b->c);
	double disc = bq * bq - v3_dot(b->c, b->c) + 1;
	if (disc <= 0)
		return 0;
	*n = v3_sub(v3_scale(*ray, bq - sqrt(disc)), b->c);
	return 1;
}

int glint_probe_ball_reflect(const struct probe_ball *b, double x, double y,
			     struct vec3 *d, double *ci)
{
	struct vec3 r, n;
	if (!glint_probe_ball_normal(b, x, y, &n, &r))
		return 0;
	*ci = -v3_dot(r, n);
	if (*ci <= 0)
		return 0;
	*d = v3_add(r, v3_scale(n, 2 * *ci));
	return 1;
}

/* The photo bilinearly at continuous pixel coordinates (px, py). */
static void photo_bilinear(const struct glint_image *photo, double px,
			   double py, float rgb[3])
{
	double fx = px - 0.5, fy = py - 0.5;
	int ix = (int)floor(fx), iy = (int)floor(fy);
	double tx = fx - ix, ty = fy - iy;
	int ix1 = ix + 1 < photo->width ? ix + 1 : ix,
	    iy1 = iy + 1 < photo->height ? iy + 1 : iy;
	const float *q00 = glint_image_px(photo, ix, iy),
		    *q10 = glint_image_px(photo, ix1, iy),
		    *q01 = glint_image_px(photo, ix, iy1),
		    *q11 = glint_image_px(photo, ix1, iy1);
	for (int c = 0; c < 3; c++)
		rgb[c] = (float)((1 - ty) * ((1 - tx) * q00[c] + tx * q10[c]) +
				 ty * ((1 - tx) * q01[c] + tx * q11[c]));
}

/* Photo pixels per steradian around direction d (imaged at px, py): the
 * image of a small (dth x dth) patch. */
static double pixel_density(const struct probe_ball *b, struct vec3 d,
			    double px, double py, double dth)
{
	struct vec3 t1 = v3_norm(v3_cross(d, v3(0, 1, 0)));
	if (v3_len(v3_cross(d, v3(0, 1, 0))) < 1e-6)
		t1 = v3(1, 0, 0);
	struct vec3 t2 = v3_cross(d, t1);
	double ax, ay, bx, by, c1;
	if (!glint_probe_ball_image(b, v3_norm(v3_add(d, v3_scale(t1, dth))),
				    &ax, &ay, &c1) ||
	    !glint_probe_ball_image(b, v3_norm(v3_add(d, v3_scale(t2, dth))),
				    &bx, &by, &c1))
		return 0;
	return fabs((ax - px) * (by - py) - (ay - py) * (bx - px)) /
	       (dth * dth);
}

int glint_probe_ball_setup(const struct glint_image *photo,
			   const struct glint_unwrap_opts *o,
			   struct probe_ball *b)
{
	struct glint_pinhole cam;

	if (!(o->fpx > 0) || !(o->ball_r > 0))
		return glint_error_set(
			EINVAL,
			"unwrap: focal length %g px, ball radius "
			"%g px: expected both > 0",
			o->fpx, o->ball_r);
	if (o->ball_cx - o->ball_r < 0 || o->ball_cy - o->ball_r < 0 ||
	    o->ball_cx + o->ball_r > photo->width ||
	    o->ball_cy + o->ball_r > photo->height)
		return glint_error_set(EINVAL,
				       "unwrap: the ball (%g, %g) r %g px is "
				       "not inside the %dx%d photo",
				       o->ball_cx, o->ball_cy, o->ball_r,
				       photo->width, photo->height);
	b->fpx = o->fpx;
	b->cx = o->cx >= 0 ? o->cx : photo->width / 2.0;
	b->cy = o->cy >= 0 ? o->cy : photo->height / 2.0;
	b->ortho = o->orthographic;
	b->bcx = o->ball_cx;
	b->bcy = o->ball_cy;
	b->br = o->ball_r;
	int ret = glint_pinhole_init(&cam, photo->width, photo->height, o->fpx,
				     1.0, 0, 0, v3(0, 0, 0), v3(0, 0, -1),
				     v3(0, 1, 0));
	cam.cx = b->cx;
	cam.cy = b->cy;
	if (ret == 0)
		ret = glint_pinhole_sphere_from_circle(
			&cam, o->ball_cx, o->ball_cy, o->ball_r, 1, &b->c);
	return ret;
}

double glint_unwrap_rim_margin_px(const struct glint_unwrap_opts *o)
{
	double s = o->psf_sigma_px > 0 ? o->psf_sigma_px : 0;
	return 3 * sqrt(s * s + (o->olpf ? 0.25 : 0) + 1.0 / 12);
}

/*
 * The directions a single view of the ball does not show reliably lie
 * around the one straight behind it: they are reflected by the ball's
 * grazing rim, compressed into its last pixels and mixed there by the
 * camera's blur with the backdrop beside the ball (on the simulated rig,
 * whose ball is 96 px across, 10-30 deg from that direction came out 15
 * to 55 % dark).  A sample sphere sees them near its own rim, where
 * Fresnel's rise tells ior from specular.  They are filled by the
 * harmonic interpolation of the reliable map around them (Laplace's
 * equation on the lat-long grid, the reliable texels fixed; successive
 * over-relaxation from their mean), smooth and without the rim's dark
 * bias; the mask keeps them marked unreliable.  The camera's own
 * reflection (within cos_cone of to_cam) stays as photographed: the
 * camera is part of what the sample sees.
 */
static int fill_grid(struct glint_image *e, const struct glint_image *m,
		     struct vec3 to_cam, double cos_cone)
{
	int w = e->width, h = e->height;
	size_t n = (size_t)w * h, nf = 0;
	int *idx = malloc(n * sizeof(int));
	double mean[3] = { 0, 0, 0 }, msum = 0;

	if (!idx)
		return glint_error_set(ENOMEM, "unwrap: out of memory");
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			struct vec3 d = glint_latlong_uv_to_dir((x + 0.5) / w,
								(y + 0.5) / h);
			if (m->data[3 * i] > 0.5) {
				for (int c = 0; c < 3; c++)
					mean[c] += e->data[3 * i + c];
				msum++;
			} else if (v3_dot(d, to_cam) < cos_cone) {
				idx[nf++] = (int)i;
			}
		}
	if (!nf || !(msum > 0)) {
		free(idx);
		return 0;
	}
	for (size_t k = 0; k < nf; k++)
		for (int c = 0; c < 3; c++)
			e->data[3 * (size_t)idx[k] + c] =
				(float)(mean[c] / msum);
	/* Gauss-Seidel with over-relaxation over the filled texels (their
	 * neighbours wrap in longitude and stop at the poles), until no
	 * texel moves by 1e-5 of the mean. */
	double tol = 1e-5 * (mean[0] + mean[1] + mean[2]) / (3 * msum);
	for (int it = 0; it < 4000; it++) {
		double moved = 0;
		for (size_t k = 0; k < nf; k++) {
			int i = idx[k], x = i % w, y = i / w;
			int nb[4] = { y * w + (x + 1) % w,
				      y * w + (x + w - 1) % w,
				      (y > 0 ? y - 1 : y) * w + x,
				      (y < h - 1 ? y + 1 : y) * w + x };
			for (int c = 0; c < 3; c++) {
				float *p = e->data + 3 * (size_t)i + c;
				double avg = 0;
				for (int j = 0; j < 4; j++)
					avg += e->data[3 * (size_t)nb[j] + c];
				double d = 1.9 * (0.25 * avg - *p);
				*p += (float)d;
				moved = fmax(moved, fabs(d));
			}
		}
		if (moved < tol)
			break;
	}
	free(idx);
	return 0;
}

/* Above this width the fill is solved on a map box-averaged down to it
 * and read back bilinearly: over-relaxation needs iterations in
 * proportion to the region's width: on a 12 MP probe's 4800-wide map
 * the fill took 31 s at full width and takes about 1 s so; it is smooth
 * at that scale anyway. */
#define FILL_MAX_WIDTH 512

static int fill_behind(struct glint_image *e, const struct glint_image *m,
		       struct vec3 to_cam, double cos_cone)
{
	int w = e->width, h = e->height,
	    f = (w + FILL_MAX_WIDTH - 1) / FILL_MAX_WIDTH;
	if (f <= 1)
		return fill_grid(e, m, to_cam, cos_cone);
	int wc = w / f, hc = h / f;
	struct glint_image *ec = glint_image_new(wc, hc),
			   *mc = glint_image_new(wc, hc);
	int ret = 0;
	if (!ec || !mc) {
		ret = glint_error_set(ENOMEM, "unwrap: out of memory");
		goto out;
	}
	/* A coarse texel: the mean of its reliable fine texels, reliable
	 * when at least half of them are. */
	for (int y = 0; y < hc; y++)
		for (int x = 0; x < wc; x++) {
			double acc[3] = { 0, 0, 0 }, k = 0;
			for (int j = 0; j < f; j++)
				for (int i = 0; i < f; i++) {
					const float *pm = glint_image_px(
						m, f * x + i, f * y + j);
					const float *pe = glint_image_px(
						e, f * x + i, f * y + j);
					if (pm[0] <= 0.5f)
						continue;
					for (int c = 0; c < 3; c++)
						acc[c] += pe[c];
					k++;
				}
			float *q = glint_image_px(ec, x, y),
			      *qm = glint_image_px(mc, x, y);
			for (int c = 0; c < 3; c++) {
				q[c] = k > 0 ? (float)(acc[c] / k) : 0;
				qm[c] = k >= 0.5 * f * f ? 1.0f : 0.0f;
			}
		}
	ret = fill_grid(ec, mc, to_cam, cos_cone);
	/* The fine texels to fill: unreliable, outside the camera's cone. */
	for (int y = 0; ret == 0 && y < h; y++)
		for (int x = 0; x < w; x++) {
			if (glint_image_px(m, x, y)[0] > 0.5f)
				continue;
			struct vec3 d = glint_latlong_uv_to_dir((x + 0.5) / w,
								(y + 0.5) / h);
			if (v3_dot(d, to_cam) >= cos_cone)
				continue;
			double fx = (x + 0.5) / f - 0.5,
			       fy = (y + 0.5) / f - 0.5;
			fy = fmin(fmax(fy, 0), hc - 1);
			int ix = (int)floor(fx), iy = (int)floor(fy);
			double tx = fx - ix, ty = fy - iy;
			float *p = glint_image_px(e, x, y);
			for (int c = 0; c < 3; c++) {
				double v = 0;
				for (int k = 0; k < 4; k++) {
					int xx =
						((ix + (k & 1)) % wc + wc) % wc;
					int yy = iy + (k >> 1) < hc
							 ? iy + (k >> 1)
							 : hc - 1;
					v += ((k & 1) ? tx : 1 - tx) *
					     ((k >> 1) ? ty : 1 - ty) *
					     glint_image_px(ec, xx, yy)[c];
				}
				p[c] = (float)v;
			}
		}
out:
	glint_image_free(ec);
	glint_image_free(mc);
	return ret;
}

int glint_probe_unwrap(const struct glint_image *photo,
		       const struct glint_unwrap_opts *o,
		       struct glint_image **env, struct glint_image **mask,
		       struct glint_image **density)
{
	struct probe_ball b;
	int w = o->width, h = o->height;

	*env = NULL;
	if (mask)
		*mask = NULL;
	if (density)
		*density = NULL;
	int ret = glint_probe_ball_setup(photo, o, &b);
	if (ret < 0)
		return ret;
	if (w <= 0 || h <= 0) {
		w = (int)(4 * o->ball_r);
		h = w / 2;
	}
	struct glint_image *e = glint_image_new(w, h),
			   *m = glint_image_new(w, h),
			   *dn = glint_image_new(w, h);
	if (!e || !m || !dn) {
		glint_image_free(e);
		glint_image_free(m);
		glint_image_free(dn);
		return glint_error_set(ENOMEM, "unwrap: out of memory");
	}
	double cos_graze = cos(o->grazing_deg * M_PI / 180);
	double cos_cone = cos(o->camera_cone_deg * M_PI / 180);
	double inner = o->ball_r - glint_unwrap_rim_margin_px(o);
	struct vec3 to_cam = v3_scale(v3_norm(b.c), -1);
	double dth = M_PI / h;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			struct vec3 d = glint_latlong_uv_to_dir((x + 0.5) / w,
								(y + 0.5) / h);
			double px, py, ci;
			float *pe = glint_image_px(e, x, y),
			      *pm = glint_image_px(m, x, y),
			      *pd = glint_image_px(dn, x, y);
			int ok = glint_probe_ball_image(&b, d, &px, &py, &ci) &&
				 px >= 0.5 && py >= 0.5 &&
				 px <= photo->width - 0.5 &&
				 py <= photo->height - 0.5;
			if (!ok) {
				pe[0] = pe[1] = pe[2] = 0;
				pm[0] = pm[1] = pm[2] = 0;
				pd[0] = pd[1] = pd[2] = 0;
				continue;
			}
			float rgb[3];
			photo_bilinear(photo, px, py, rgb);
			for (int c = 0; c < 3; c++) {
				double r =
					o->reflectivity > 0
						? o->reflectivity
						: glint_fresnel_conductor(
							  o->n[c], o->k[c], ci);
				pe[c] = (float)(rgb[c] / r);
			}
			int reliable =
				ci > cos_graze &&
				v3_dot(d, to_cam) < cos_cone &&
				hypot(px - o->ball_cx, py - o->ball_cy) < inner;
			pm[0] = pm[1] = pm[2] = (float)reliable;
			pd[0] = pd[1] = pd[2] =
				(float)pixel_density(&b, d, px, py, dth);
		}
	if (!o->no_fill && (ret = fill_behind(e, m, to_cam, cos_cone)) < 0) {
		glint_image_free(e);
		glint_image_free(m);
		glint_image_free(dn);
		return ret;
	}
	*env = e;
	if (mask)
		*mask = m;
	else
		glint_image_free(m);
	if (density)
		*density = dn;
	else
		glint_image_free(dn);
	return 0;
}

/*
 * An unwrapped map is light before it is written: finite, and not
 * negative beyond what a merged photo's noise about zero gives (its dark
 * pixels scatter both ways; within 1 % of the map's mean they are set to
 * 0, as the fitter's reader does).  A value further below zero is no
 * light at all (a wrong black level, a photo darker than its noise) and
 * is refused here, where it was made, naming the file and the pixel.
 */
static int check_light(struct glint_image *env, const char *path)
{
	size_t n = (size_t)env->width * env->height * 3;
	double mean = 0;

	for (size_t i = 0; i < n; i++) {
		if (!isfinite(env->data[i]))
			return glint_error_set(
				ERANGE,
				"unwrap: %s: pixel (%zu, %zu) has radiance "
				"%g: expected a finite value",
				path, i / 3 % (size_t)env->width,
				i / 3 / (size_t)env->width,
				(double)env->data[i]);
		mean += env->data[i];
	}
	mean /= (double)n;
	if (!(mean > 0))
		return glint_error_set(ERANGE,
				       "unwrap: %s: the map's mean radiance "
				       "is %g: expected some light",
				       path, mean);
	for (size_t i = 0; i < n; i++) {
		if (env->data[i] >= 0)
			continue;
		if (env->data[i] < -0.01 * mean)
			return glint_error_set(
				ERANGE,
				"unwrap: %s: pixel (%zu, %zu) has radiance "
				"%g, below zero by more than the noise allows "
				"(1 %% of the mean %g): expected light >= 0",
				path, i / 3 % (size_t)env->width,
				i / 3 / (size_t)env->width,
				(double)env->data[i], mean);
		env->data[i] = 0;
	}
	return 0;
}

/* What the log says of each compact source. */
static void log_sources(const struct glint_light_sources *s)
{
	double ty = 0.2126 * s->total_flux[0] + 0.7152 * s->total_flux[1] +
		    0.0722 * s->total_flux[2];
	for (int i = 0; i < s->n; i++) {
		const struct glint_light_source *l = &s->s[i];
		double fy = 0.2126 * l->flux[0] + 0.7152 * l->flux[1] +
			    0.0722 * l->flux[2];
		glint_log_info(
			"light source %d: azimuth %.1f, elevation %.1f deg "
			"(+- %.2f), %.1f %% of the light, %.2f px in the "
			"photo (%.2f deg per px)%s: a point in the map",
			i + 1, atan2(l->dir.x, -l->dir.z) * 180 / M_PI,
			asin(fmax(-1, fmin(1, l->dir.y))) * 180 / M_PI,
			l->dir_sigma_deg, ty > 0 ? 100 * fy / ty : 0,
			l->px_deg > 0 ? l->size_deg / l->px_deg : 0, l->px_deg,
			l->saturated ? ", clipped: its flux is a lower bound"
				     : "");
	}
}

/*
 * ENV-preview.png: the map as seen (auto exposure, sRGB), the directions
 * the mask calls unreliable darkened, each compact light source found
 * ringed and numbered as in the log and -sources.json, and a title line
 * saying so.  At most 1024 pixels across (nearest texel).
 */
static int write_preview(const char *path, const struct glint_image *env,
			 const struct glint_image *mask,
			 const struct glint_light_sources *src)
{
	static const uint8_t ring[3] = { 255, 40, 200 }, halo[3] = { 0, 0, 0 };
	int w = env->width < 1024 ? env->width : 1024, h = w / 2, top = 14;
	double sx = (double)env->width / w, sy = (double)env->height / h;
	double scale = exp2(glint_png_auto_exposure(env));
	struct glint_canvas cv;
	char buf[96];
	int ret = glint_canvas_init(&cv, w, h + top);

	if (ret < 0)
		return ret;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			int ex = (int)(x * sx), ey = (int)(y * sy);
			const float *p = glint_image_px(env, ex, ey);
			int ok =
				!mask || glint_image_px(mask, ex, ey)[0] > 0.5f;
			uint8_t c[3];
			for (int k = 0; k < 3; k++)
				c[k] = (uint8_t)(glint_tonemap_srgb8(p[k] *
								     scale) /
						 (ok ? 1 : 3));
			glint_canvas_put(&cv, x, top + y, c);
		}
	for (int i = 0; i < src->n; i++) {
		const struct vec3 d = src->s[i].dir;
		double u = 0.5 + atan2(d.x, -d.z) / (2 * M_PI);
		double v = acos(fmax(-1, fmin(1, d.y))) / M_PI;
		double cx = u * w, cy = top + v * h, r = 7;
		glint_canvas_ring(&cv, cx, cy, r, 4, halo);
		glint_canvas_ring(&cv, cx, cy, r, 2, ring);
		snprintf(buf, sizeof(buf), "%d", i + 1);
		glint_canvas_text(&cv, (int)(cx + r + 3), (int)(cy - 3), 1,
				  buf);
	}
	snprintf(buf, sizeof(buf),
		 "PROBE MAP: %d COMPACT SOURCE%s RINGED, UNRELIABLE DARKENED",
		 src->n, src->n == 1 ? "" : "S");
	glint_canvas_text(&cv, 2, 3, 1, buf);
	ret = glint_canvas_write_png(&cv, path);
	glint_canvas_free(&cv);
	return ret;
}

/*
 * The width of a map that holds compact sources: a source goes back into
 * the map as a point, which the bilinear splat spreads over 2 x 2
 * texels.  At the ball's own resolution (4 r texels round: 0.94 deg on
 * the simulated rig's 96 px ball) that widened its sun to about 2 deg,
 * and a glossy sample's highlight with it: aluminium bronze's roughness
 * came out 0.0135 for 0.023 (the same photo fitted under the true map:
 * 0.0232).  With texels of 0.5 deg or less it is 0.0228-0.0237.  A
 * larger ball's map is finer already; a width given is kept.
 */
#define SOURCE_MAP_WIDTH 720

int glint_probe_unwrap_write(const struct glint_image *photo,
			     const struct glint_unwrap_opts *opts,
			     const char *env_path, int *width, int *height)
{
	struct glint_unwrap_opts fine = *opts;
	const struct glint_unwrap_opts *o = &fine;
	struct glint_image *env = NULL, *mask = NULL, *dens = NULL;
	struct glint_image *cleaned = NULL;
	struct glint_write_opts png = { 0 };
	struct glint_light_sources src = { 0 };
	struct glint_source_opts so;
	char path[GLINT_PATH_MAX];
	int ret = 0;

	glint_source_default_opts(&so);
	if (!o->no_sources)
		ret = glint_probe_find_sources(photo, o->variance, o->weights,
					       o, &so, &src, &cleaned);
	if (ret == 0 && src.n > 0 && fine.width <= 0 && fine.height <= 0 &&
	    4 * fine.ball_r < SOURCE_MAP_WIDTH) {
		fine.width = SOURCE_MAP_WIDTH;
		fine.height = SOURCE_MAP_WIDTH / 2;
	}
	if (ret == 0)
		ret = glint_probe_unwrap(cleaned ? cleaned : photo, o, &env,
					 &mask, &dens);
	glint_image_free(cleaned);
	if (ret == 0 && !o->no_sources) {
		glint_probe_add_sources(env, &src);
		log_sources(&src);
	}
	if (ret == 0)
		ret = check_light(env, env_path);
	if (ret == 0 && !o->no_sources)
		ret = glint_path_sibling(path, sizeof(path), env_path,
					 "-sources.json");
	if (ret == 0 && !o->no_sources)
		ret = glint_probe_sources_write(path, NULL, &src);
	if (ret == 0)
		ret = glint_image_write(env_path, env, NULL);
	if (ret == 0)
		ret = glint_path_sibling(path, sizeof(path), env_path,
					 "-mask.png");
	if (ret == 0)
		ret = glint_image_write(path, mask, &png);
	if (ret == 0)
		ret = glint_path_sibling(path, sizeof(path), env_path,
					 "-density.exr");
	if (ret == 0)
		ret = glint_image_write(path, dens, NULL);
	if (ret == 0)
		ret = glint_path_sibling(path, sizeof(path), env_path,
					 "-preview.png");
	if (ret == 0)
		ret = write_preview(path, env, mask, &src);
	if (ret == 0 && width)
		*width = env->width;
	if (ret == 0 && height)
		*height = env->height;
	glint_image_free(env);
	glint_image_free(mask);
	glint_image_free(dens);
	return ret;
}

/* The ball's circle: found in the photo when --ball is not given (the
 * capture's detector); a given one is checked against it. */
int glint_probe_find_ball(const struct glint_image *photo, int given,
			  struct glint_unwrap_opts *o)
{
	struct glint_circle c;
	int ret = glint_sphere_detect(photo, 0, 0, &c);

	if (given) {
		double d = hypot(c.cx - o->ball_cx, c.cy - o->ball_cy);
		double dr = fabs(c.r - o->ball_r);
		if (ret == 0 && (d > 2 || dr > 2))
			glint_log_warn(
				"--ball %g,%g,%g disagrees with the ball "
				"found in the photo, %.1f,%.1f,%.1f "
				"(centre %.1f px, radius %.1f px "
				"apart): check it",
				o->ball_cx, o->ball_cy, o->ball_r, c.cx, c.cy,
				c.r, d, dr);
		return 0;
	}
	if (ret < 0)
		return glint_error_prefix(
			ret, "no ball found (give --ball CX,CY,R)");
	o->ball_cx = c.cx;
	o->ball_cy = c.cy;
	o->ball_r = c.r;
	glint_log_info("found the ball at %.2f,%.2f, radius %.2f px (%d rim "
		       "points, %.2f px RMS, %.0f deg of its rim): --ball "
		       "%.2f,%.2f,%.2f",
		       c.cx, c.cy, c.r, c.points, c.rms_px, c.arc_deg, c.cx,
		       c.cy, c.r);
	return 0;
}
