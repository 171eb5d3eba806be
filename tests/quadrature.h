/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_QUADRATURE_H
#define GLINT_TESTS_QUADRATURE_H

/*
 * Independent numerical integration of a BRDF for the furnace tests:
 * directional albedo a(wo) = integral of f(wo, wi) cos(theta_i) dwi, by the
 * midpoint rule over half-vector space (dwi = 4 |wo.h| dwh), with theta_h
 * steps fine enough for a lobe of RMS slope 0.05.  It shares no code with
 * the renderer's Monte Carlo estimator.
 */

#include "fit/brdf/model.h"

static inline void albedo_quadrature(const struct glint_model_ops *m,
				     const double *p, struct vec3 wo,
				     double out[3])
{
	const int nt = 2000, np = 180;
	out[0] = out[1] = out[2] = 0;
	for (int j = 0; j < nt; j++) {
		double th = (j + 0.5) * (M_PI / 2) / nt;
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
			m->eval(p, wo, wi, f);
			double w = wi.z * 4 * oh * st * (M_PI / 2 / nt) *
				   (2 * M_PI / np);
			for (int c = 0; c < 3; c++)
				out[c] += f[c] * w;
		}
	}
}

#endif
