/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_CHISQ_H
#define GLINT_TESTS_CHISQ_H

/*
 * Pearson chi-square goodness of fit, pooling bins with expected counts
 * below 5 (Cochran's rule), and its p-value through the regularised upper
 * incomplete gamma function (series / continued fraction, Numerical Recipes
 * 6.2).  GSL has gsl_cdf_chisq_Q, but this is the only use in the tests.
 */

#include <math.h>

static double gammq_series(double a, double x)
{
	double sum = 1 / a, del = sum, ap = a;
	for (int n = 0; n < 10000; n++) {
		ap += 1;
		del *= x / ap;
		sum += del;
		if (fabs(del) < fabs(sum) * 1e-15)
			break;
	}
	return 1 - sum * exp(-x + a * log(x) - lgamma(a));
}

static double gammq_cf(double a, double x)
{
	double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;
	for (int i = 1; i < 10000; i++) {
		double an = -i * (i - a);
		b += 2;
		d = an * d + b;
		if (fabs(d) < 1e-300)
			d = 1e-300;
		c = b + an / c;
		if (fabs(c) < 1e-300)
			c = 1e-300;
		d = 1 / d;
		double del = d * c;
		h *= del;
		if (fabs(del - 1) < 1e-15)
			break;
	}
	return exp(-x + a * log(x) - lgamma(a)) * h;
}

/* P(chi2 with dof degrees of freedom > x). */
static inline double chisq_pvalue(double x, int dof)
{
	double a = dof / 2.0, xx = x / 2;
	if (xx <= 0)
		return 1;
	return xx < a + 1 ? gammq_series(a, xx) : gammq_cf(a, xx);
}

/* Chi-square p-value of observed vs expected counts over n bins. */
static inline double chisq_test(const double *obs, const double *exp_, int n,
				int *dof_out)
{
	double chi = 0, po = 0, pe = 0;
	int dof = 0;
	for (int i = 0; i < n; i++) {
		po += obs[i];
		pe += exp_[i];
		if (pe < 5)
			continue;
		chi += (po - pe) * (po - pe) / pe;
		dof++;
		po = pe = 0;
	}
	if (pe > 0) {
		chi += (po - pe) * (po - pe) / pe;
		dof++;
	}
	*dof_out = dof - 1;
	return chisq_pvalue(chi, dof - 1);
}

#endif
