/* SPDX-License-Identifier: MIT */
#include "core/optics.h"

#include <math.h>

double glint_fresnel_dielectric(double c, double n)
{
	c = fabs(c);
	if (c > 1)
		c = 1;
	double g2 = n * n - 1 + c * c;
	if (g2 < 0)
		return 1; /* total internal reflection (n < 1) */
	double g = sqrt(g2);
	double a = (g - c) / (g + c);
	double b = (c * (g + c) - 1) / (c * (g - c) + 1);
	return 0.5 * a * a * (1 + b * b);
}

double glint_fresnel_dielectric_dlog(double c, double n, double *dlog)
{
	c = fabs(c);
	if (c > 1)
		c = 1;
	double n2m1 = n * n - 1, g2 = n2m1 + c * c;
	*dlog = 0;
	if (g2 < 0)
		return 1; /* total internal reflection (n < 1) */
	double g = sqrt(g2);
	double a = (g - c) / (g + c);
	double nb = c * (g + c) - 1, db = c * (g - c) + 1;
	double b = nb / db;
	/* F = a^2 (1 + b^2) / 2 as a function of g = sqrt(n^2 - 1 + c^2):
	 * d log a / dg = 2c / (g^2 - c^2) = 2c / (n^2 - 1),
	 * db/dg = 2c (1 - c^2) / db^2, dg/dn = n / g, so
	 * d log F / dn = (n / g) 4c [1 / (n^2 - 1) +
	 *                (1 - c^2) nb / (db (db^2 + nb^2))]. */
	if (n2m1 > 0 && c > 0)
		*dlog = 4 * c * n / g *
			(1 / n2m1 +
			 (1 - c * c) * nb / (db * (db * db + nb * nb)));
	return 0.5 * a * a * (1 + b * b);
}

double glint_fresnel_interface(double cos_i, double eta, double *cos_t)
{
	double sin2_t = (1 - cos_i * cos_i) / (eta * eta);
	if (sin2_t >= 1) {
		if (cos_t)
			*cos_t = 0;
		return 1;
	}
	double ct = sqrt(1 - sin2_t);
	double rs = (cos_i - eta * ct) / (cos_i + eta * ct);
	double rp = (eta * cos_i - ct) / (eta * cos_i + ct);
	if (cos_t)
		*cos_t = ct;
	return 0.5 * (rs * rs + rp * rp);
}

double glint_fresnel_conductor(double n, double k, double c)
{
	c = fmin(fmax(c, 0), 1);
	double c2 = c * c, s2 = 1 - c2;
	double t0 = n * n - k * k - s2;
	double a2b2 = sqrt(t0 * t0 + 4 * n * n * k * k);
	double a = sqrt(fmax(0, 0.5 * (a2b2 + t0)));
	double rs = (a2b2 + c2 - 2 * a * c) / (a2b2 + c2 + 2 * a * c);
	double t1 = c2 * a2b2 + s2 * s2, t2 = 2 * a * c * s2;
	double rp = rs * (t1 - t2) / (t1 + t2);
	return 0.5 * (rs + rp);
}

struct vec3 glint_reflect(struct vec3 d, struct vec3 n)
{
	return v3_sub(d, v3_scale(n, 2 * v3_dot(d, n)));
}

int glint_refract(struct vec3 d, struct vec3 n, double eta, struct vec3 *t)
{
	double ci = -v3_dot(d, n), ct;
	if (glint_fresnel_interface(ci, eta, &ct) >= 1)
		return 0;
	*t = v3_norm(v3_add(v3_scale(d, 1 / eta), v3_scale(n, ci / eta - ct)));
	return 1;
}
