/* SPDX-License-Identifier: MIT */
#include "core/pinhole.h"

#include "core/error.h"

#include <math.h>
#include <string.h>

int glint_pinhole_init(struct glint_pinhole *cam, int width, int height,
		       double focal_m, double pitch_m, double f_number,
		       double focus_m, struct vec3 pos, struct vec3 look_at,
		       struct vec3 up)
{
	struct vec3 fwd = v3_norm(v3_sub(look_at, pos));
	struct vec3 right = v3_cross(fwd, up);

	if (v3_len(right) < 1e-9 * v3_len(up) || v3_len(fwd) == 0)
		return glint_error_set(EINVAL,
				       "camera pose: 'up' is parallel to the "
				       "view direction (or look_at == "
				       "position)");
	cam->width = width;
	cam->height = height;
	cam->frame_x = cam->frame_y = cam->frame_width = 0;
	cam->psf_sigma_px = 0;
	cam->olpf = 0;
	cam->cfa[0] = cam->cfa[1] = cam->cfa[2] = cam->cfa[3] = -1;
	cam->fpx = focal_m / pitch_m;
	cam->cx = width / 2.0;
	cam->cy = height / 2.0;
	cam->aperture_radius = f_number > 0 ? focal_m / f_number / 2 : 0;
	cam->focus_distance = focus_m;
	cam->pos = pos;
	cam->fwd = fwd;
	cam->right = v3_norm(right);
	cam->up = v3_cross(cam->right, fwd);
	return 0;
}

int glint_pinhole_set_cfa(struct glint_pinhole *cam, const char *layout)
{
	static const char *const known[] = { "RGGB", "GRBG", "GBRG", "BGGR" };

	cam->cfa[0] = cam->cfa[1] = cam->cfa[2] = cam->cfa[3] = -1;
	if (!layout || !*layout)
		return 0;
	for (size_t k = 0; k < sizeof(known) / sizeof(known[0]); k++) {
		if (strcmp(layout, known[k]))
			continue;
		for (int i = 0; i < 4; i++)
			cam->cfa[i] = (signed char)(layout[i] == 'R'   ? 0
						    : layout[i] == 'G' ? 1
								       : 2);
		return 0;
	}
	return glint_error_set(EINVAL,
			       "colour filter array '%s': expected RGGB, "
			       "GRBG, GBRG or BGGR",
			       layout);
}

int glint_pixel_filter_on(const struct glint_pinhole *cam)
{
	return cam->psf_sigma_px > 0 || cam->olpf;
}

/* The cumulative distribution of the unit square (centred on 0)
 * convolved with a Gaussian of sigma: sigma (Psi((x + 1/2) / sigma) -
 * Psi((x - 1/2) / sigma)), Psi(z) = z Phi(z) + phi(z). */
static double psi(double z)
{
	return z * 0.5 * erfc(-z / sqrt(2.0)) +
	       exp(-0.5 * z * z) / sqrt(2 * M_PI);
}

static double box_gauss_cdf(double sigma, double x)
{
	if (sigma <= 0)
		return fmin(1, fmax(0, x + 0.5));
	return sigma * (psi((x + 0.5) / sigma) - psi((x - 0.5) / sigma));
}

void glint_pixel_filter_table(const struct glint_pinhole *cam,
			      float table[GLINT_PIXEL_FILTER_N + 1])
{
	enum { GRID = 8192 };
	double sigma = cam->psf_sigma_px > 0 ? cam->psf_sigma_px : 0;
	double split = cam->olpf ? 0.5 : 0;
	double half = 0.5 + split + 5 * sigma;
	int j = 0;

	/* Walk the distribution on a fine grid and read off each
	 * quantile, interpolated between the grid's points. */
	double x0 = -half, f0 = 0;
	table[0] = (float)(0.5 - half);
	for (int g = 1; g <= GRID && j < GLINT_PIXEL_FILTER_N; g++) {
		double x1 = -half + 2 * half * g / GRID;
		double f1 = split > 0
				    ? 0.5 * (box_gauss_cdf(sigma, x1 - split) +
					     box_gauss_cdf(sigma, x1 + split))
				    : box_gauss_cdf(sigma, x1);
		while (j + 1 < GLINT_PIXEL_FILTER_N &&
		       f1 >= (double)(j + 1) / GLINT_PIXEL_FILTER_N) {
			double q = (double)(j + 1) / GLINT_PIXEL_FILTER_N;
			double t = f1 > f0 ? (q - f0) / (f1 - f0) : 0;
			table[++j] = (float)(0.5 + x0 + t * (x1 - x0));
		}
		x0 = x1;
		f0 = f1;
	}
	while (j < GLINT_PIXEL_FILTER_N)
		table[++j] = (float)(0.5 + half);
}

/* Shirley-Chiu concentric map of the unit square onto the unit disk. */
static void concentric_disk(double u, double v, double *x, double *y)
{
	double a = 2 * u - 1, b = 2 * v - 1, r, phi;

	if (a == 0 && b == 0) {
		*x = *y = 0;
		return;
	}
	if (fabs(a) > fabs(b)) {
		r = a;
		phi = (M_PI / 4) * (b / a);
	} else {
		r = b;
		phi = M_PI / 2 - (M_PI / 4) * (a / b);
	}
	*x = r * cos(phi);
	*y = r * sin(phi);
}

void glint_pinhole_ray(const struct glint_pinhole *cam, double px, double py,
		       double lu, double lv, struct vec3 *org, struct vec3 *dir)
{
	double x = (px - cam->cx) / cam->fpx, y = -(py - cam->cy) / cam->fpx;
	struct vec3 d = v3_add(cam->fwd, v3_add(v3_scale(cam->right, x),
						v3_scale(cam->up, y)));

	if (cam->aperture_radius <= 0) {
		*org = cam->pos;
		*dir = v3_norm(d);
		return;
	}
	/* d has unit length along fwd, so the focus point is at t = focus. */
	struct vec3 focus = v3_add(cam->pos, v3_scale(d, cam->focus_distance));
	double lx, ly;
	concentric_disk(lu, lv, &lx, &ly);
	*org = v3_add(cam->pos,
		      v3_add(v3_scale(cam->right, lx * cam->aperture_radius),
			     v3_scale(cam->up, ly * cam->aperture_radius)));
	*dir = v3_norm(v3_sub(focus, *org));
}

int glint_pinhole_project(const struct glint_pinhole *cam, struct vec3 p,
			  double *px, double *py)
{
	struct vec3 q = v3_sub(p, cam->pos);
	double z = v3_dot(q, cam->fwd);

	if (!(z > 0))
		return -EINVAL;
	*px = cam->cx + cam->fpx * v3_dot(q, cam->right) / z;
	*py = cam->cy - cam->fpx * v3_dot(q, cam->up) / z;
	return 0;
}

/*
 * The tangent cone of a sphere seen from the pinhole has half-angle alpha
 * (sin alpha = R / D) and an axis at angle beta from the optical axis.  Its
 * section by the image plane z = f is an ellipse with, along the radial
 * direction, centre f sin(b) cos(b) / k and semi-axis f sin(a) cos(a) / k,
 * and tangential semi-axis f sin(a) / sqrt(k), where
 * k = cos^2(beta) - sin^2(alpha).
 */
int glint_pinhole_sphere_ellipse(const struct glint_pinhole *cam,
				 struct vec3 centre, double radius,
				 struct glint_ellipse *out)
{
	struct vec3 q = v3_sub(centre, cam->pos);
	double d = v3_len(q);

	if (!(d > radius))
		return glint_error_set(EINVAL,
				       "sphere of radius %g m encloses the "
				       "camera (distance %g m)",
				       radius, d);
	double xc = v3_dot(q, cam->right), yc = v3_dot(q, cam->up);
	double zc = v3_dot(q, cam->fwd);
	double sa = radius / d, ca = sqrt(1 - sa * sa);
	double cb = zc / d, sb = sqrt(fmax(0, 1 - cb * cb));
	double k = cb * cb - sa * sa;

	if (!(k > 0))
		return glint_error_set(EINVAL,
				       "sphere is not wholly in front of the "
				       "camera: its silhouette is not an "
				       "ellipse");
	double rho = cam->fpx * sb * cb / k;
	double dirx = 1, diry = 0, rl = hypot(xc, yc);
	if (rl > 0) {
		dirx = xc / rl;
		diry = -yc / rl; /* image y grows downwards */
	}
	out->cx = cam->cx + rho * dirx;
	out->cy = cam->cy + rho * diry;
	out->a = cam->fpx * sa * ca / k;
	out->b = cam->fpx * sa / sqrt(k);
	out->angle = atan2(diry, dirx);
	return 0;
}

int glint_pinhole_sphere_from_circle(const struct glint_pinhole *cam, double cx,
				     double cy, double b, double radius,
				     struct vec3 *centre)
{
	double f = cam->fpx;
	double dx = cx - cam->cx, dy = cy - cam->cy;
	double rho = hypot(dx, dy);

	if (!(b > 0) || !(radius > 0))
		return glint_error_set(EINVAL,
				       "sphere circle radius %g px and "
				       "diameter %g m: expected both > 0",
				       b, 2 * radius);
	/* From the relations above: tan(beta) = rho f / (f^2 + b^2) and
	 * sin(alpha) = b cos(beta) / sqrt(f^2 + b^2). */
	double beta = atan(rho * f / (f * f + b * b));
	double sa = b * cos(beta) / sqrt(f * f + b * b);
	double dist = radius / sa;
	double ux = rho > 0 ? dx / rho : 0, uy = rho > 0 ? -dy / rho : 0;
	struct vec3 axis = v3_add(v3_scale(cam->fwd, cos(beta)),
				  v3_scale(v3_add(v3_scale(cam->right, ux),
						  v3_scale(cam->up, uy)),
					   sin(beta)));

	*centre = v3_add(cam->pos, v3_scale(axis, dist));
	return 0;
}
