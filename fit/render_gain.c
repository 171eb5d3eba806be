/* SPDX-License-Identifier: MIT */
/*
 * The fast render's error as a gain per region: what the shade cache gets
 * wrong about a varying lobe under this light (its quadrature of the hot
 * texels, a highlight a few pixels across) is taken as a relative error
 * e_g of the varying lobes' part of the render in each misfit region g
 * (a mirror-angle band x a third of the view angle, per photo:
 * fit_misfit_regions()), independent between regions.  Region g's error
 * moves the weighted residuals by e_g c (c: the varying lobes' weighted
 * render over its rows) and the least-squares optimum by A^-1 J^T c e_g to
 * first order, A = J^T J; the sum of the squares over the regions at
 * e = 1 is each parameter's sensitivity.  Where regions pull along a
 * ridge of the objective (a metal's specular against its ior, separated
 * only at grazing angles) the sensitivity is large by itself.
 *
 * The size of e for this photo: the gain each region's residual shows
 * (least squares of its residuals on c), less what the noise gives it
 * (its spread about that gain), pooled over the regions by their weight
 * sum c^2 and scaled by R / (R - n), since the n parameters take up that
 * share of the regions' gains.
 */
#include "fit/internal.h"

#include "core/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int fit_render_gain(struct objective *ob, const double *jac, const double *r,
		    const int *region, double *sens, double *eps)
{
	const struct glint_model *m = ob->m;
	int n = m->nparams, nj = m->bxdf->nlobes, rows = 3 * ob->nsel, nr = 0;
	double a[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];
	double ainv[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];
	int unseen[GLINT_UNC_MAX_N], ret;

	memset(sens, 0, sizeof(double) * (size_t)n);
	*eps = 0;
	if (!ob->cache || n > GLINT_UNC_MAX_N || ob->nfree != n)
		return 0;
	for (int i = 0; i < rows; i++)
		if (region[i] + 1 > nr)
			nr = region[i] + 1;
	if (nr < 2)
		return 0;
	for (int i = 0; i < n; i++)
		for (int j = 0; j <= i; j++) {
			double s = 0;
			for (int k = 0; k < rows; k++)
				s += jac[(size_t)k * n + i] *
				     jac[(size_t)k * n + j];
			a[i * n + j] = a[j * n + i] = s;
		}
	ret = glint_unc_normal_inverse(a, n, ainv, unseen);
	if (ret < 0)
		return ret;
	size_t nb = (size_t)nr * (n + 4);
	double *lobes = malloc(sizeof(double) * 3 * (size_t)nj * ob->nsel);
	double *c = malloc(sizeof(double) * (size_t)rows);
	double *b = calloc(nb, sizeof(double));
	if (!lobes || !c || !b) {
		free(lobes);
		free(c);
		free(b);
		return glint_error_set(ENOMEM, "out of memory");
	}
	glint_shade_cache_lobes_sel(ob->cache, ob->p, ob->sel, ob->nsel, lobes);
	/* per region: J^T c (n), then sum c^2, sum r c, sum r^2, rows */
	for (int t = 0; t < ob->nsel; t++) {
		int s = ob->sel[t];
		for (int ch = 0; ch < 3; ch++) {
			int i = 3 * t + ch, g = region[i];
			if (g < 0)
				continue;
			double v = 0;
			for (int j = 0; j < nj; j++)
				if (m->lobes->varies[j])
					v += ob->p[m->lobes->param[j] + ch] *
					     lobes[((size_t)t * nj + j) * 3 +
						   ch];
			c[i] = ob->d->sw[3 * s + ch] * v;
			double *x = b + (size_t)g * (n + 4);
			for (int k = 0; k < n; k++)
				x[k] += jac[(size_t)i * n + k] * c[i];
			x[n] += c[i] * c[i];
			x[n + 1] += r[i] * c[i];
			x[n + 2] += r[i] * r[i];
			x[n + 3] += 1;
		}
	}
	double se2 = 0, sw = 0;
	for (int g = 0; g < nr; g++) {
		const double *x = b + (size_t)g * (n + 4);
		for (int k = 0; k < n; k++) {
			double d = 0;
			for (int j = 0; j < n; j++)
				d += ainv[k * n + j] * x[j];
			if (!unseen[k])
				sens[k] += d * d;
		}
		double cc = x[n], rows_g = x[n + 3];
		if (!(cc > 0) || rows_g < 3)
			continue;
		double e = x[n + 1] / cc;
		double left = fmax(0, x[n + 2] - e * x[n + 1]);
		double noise = left / (rows_g - 1) / cc; /* var of e */
		se2 += cc * (e * e - noise);
		sw += cc;
	}
	for (int k = 0; k < n; k++)
		sens[k] = sqrt(sens[k]);
	if (sw > 0 && nr > n && se2 > 0)
		*eps = sqrt(se2 / sw * nr / (nr - n));
	free(lobes);
	free(c);
	free(b);
	return 0;
}
