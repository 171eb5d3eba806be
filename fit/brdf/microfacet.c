/* SPDX-License-Identifier: MIT */
#include "microfacet.h"

#include "core/vec.h"

#include <math.h>

double glint_beckmann_d(double cos_h, double m)
{
	if (!(cos_h > 0))
		return 0;
	double c2 = cos_h * cos_h;
	double tan2 = (1 - c2) / c2;
	return exp(-tan2 / (m * m)) / (M_PI * m * m * c2 * c2);
}

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

double glint_vcavity_g(double nh, double no, double ni, double oh)
{
	if (!(oh > 0))
		return 0;
	double g = fmin(2 * nh * no / oh, 2 * nh * ni / oh);
	return g < 1 ? (g > 0 ? g : 0) : 1;
}
