/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_QUADRATURE_H
#define GLINT_TESTS_QUADRATURE_H

/*
 * Independent numerical integration of a BRDF for the furnace tests:
 * directional albedo a(wo) = integral of f(wo, wi) cos(theta_i) dwi, by the
 * midpoint rule over half-vector space (dwi = 4 |wo.h| dwh).  Every lobe
 * peaks at theta_h = 0, so theta_h = (pi/2) u^2 spends the steps there: a
 * lobe of RMS slope 0.05 spans 110 of the 600 steps in u (64 of 2000
 * uniform ones).  It shares no code with the renderer's Monte Carlo
 * estimator.
 */

#include "fit/brdf/model.h"

static inline void albedo_quadrature(const struct glint_model *m,
				     const double *p, struct vec3 wo,
				     double out[3])
{
	const int nt = 600, np = 180;
	out[0] = out[1] = out[2] = 0;
	for (int j = 0; j < nt; j++) {
		double u = (j + 0.5) / nt, th = (M_PI / 2) * u * u;
		double dth = M_PI * u / nt; /* d theta / du times du */
		double st = sin(th), ct = cos(th);
		for (int i = 0; i < np; i++) {
			double ph = (i + 0.5) * 2 * M_PI / np;
			struct vec3 h = v3(st * cos(ph), st * sin(ph), ct);
			double oh = v3_dot(wo, h);
			if (oh <= 0)
				continue;
			struct vec3 wi = v3_sub(v3_scale(h, 2 * oh), wo);
			if (wi.z <= 0)
				continue;
			double f[3];
			m->bxdf->eval(p, wo, wi, f);
			double w = wi.z * 4 * oh * st * dth * (2 * M_PI / np);
			for (int c = 0; c < 3; c++)
				out[c] += f[c] * w;
		}
	}
}

#endif
