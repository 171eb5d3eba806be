/* SPDX-License-Identifier: MIT */
#include "uncertainty.h"

#include "core/error.h"

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N GLINT_UNC_MAX_N

/*
 * The pseudo-inverse of the normal matrix A = J^T J (n x n) into ainv,
 * computed on A scaled to unit diagonal (so parameters of very different
 * scales do not hide a null direction); unseen[k] is set for parameters
 * with a component along a direction J does not see.
 */
int glint_unc_normal_inverse(const double *a, int n, double *ainv, int *unseen)
{
	double as[N * N], d[N];
	int ret = 0;

	for (int k = 0; k < n; k++) {
		d[k] = a[k * n + k] > 0 ? 1 / sqrt(a[k * n + k]) : 0;
		unseen[k] = !(a[k * n + k] > 0);
	}
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			as[i * n + j] = a[i * n + j] * d[i] * d[j];
	gsl_matrix_view mv = gsl_matrix_view_array(as, (size_t)n, (size_t)n);
	gsl_vector *eval = gsl_vector_alloc((size_t)n);
	gsl_matrix *evec = gsl_matrix_alloc((size_t)n, (size_t)n);
	gsl_eigen_symmv_workspace *ws = gsl_eigen_symmv_alloc((size_t)n);
	if (!eval || !evec || !ws) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	gsl_error_handler_t *old = gsl_set_error_handler_off();
	int st = gsl_eigen_symmv(&mv.matrix, eval, evec, ws);
	gsl_set_error_handler(old);
	if (st) {
		ret = glint_error_set(EDOM, "uncertainty: eigen decomposition "
					    "of J^T J failed");
		goto out;
	}
	double lmax = 0;
	for (int e = 0; e < n; e++)
		lmax = fmax(lmax, gsl_vector_get(eval, (size_t)e));
	memset(ainv, 0, sizeof(double) * (size_t)(n * n));
	for (int e = 0; e < n; e++) {
		double l = gsl_vector_get(eval, (size_t)e);
		int null = !(l > 1e-12 * lmax);
		for (int i = 0; i < n; i++) {
			double vi = gsl_matrix_get(evec, (size_t)i, (size_t)e);
			if (null) {
				if (vi * vi > 1e-6)
					unseen[i] = 1;
				continue;
			}
			for (int j = 0; j < n; j++)
				ainv[i * n + j] +=
					vi *
					gsl_matrix_get(evec, (size_t)j,
						       (size_t)e) /
					l;
		}
	}
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			ainv[i * n + j] *= d[i] * d[j];
out:
	gsl_vector_free(eval);
	gsl_matrix_free(evec);
	gsl_eigen_symmv_free(ws);
	return ret;
}

/* out = ainv m ainv (n x n). */
static void sandwich(const double *ainv, const double *m, int n, double *out)
{
	double t[N * N];
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			double s = 0;
			for (int k = 0; k < n; k++)
				s += ainv[i * n + k] * m[k * n + j];
			t[i * n + j] = s;
		}
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			double s = 0;
			for (int k = 0; k < n; k++)
				s += t[i * n + k] * ainv[k * n + j];
			out[i * n + j] = s;
		}
}

/* The cluster-robust covariance over the blocks (CR1). */
static int block_covariance(const struct glint_unc_problem *pr,
			    const double *ainv, double *out)
{
	int n = pr->n, g = pr->nblocks;
	double *score = calloc((size_t)g * n, sizeof(double));
	double meat[N * N] = { 0 };
	int used = 0;

	if (!score)
		return glint_error_set(ENOMEM, "out of memory");
	for (int i = 0; i < pr->m; i++) {
		int b = pr->block[i];
		if (b < 0 || b >= g)
			continue;
		for (int k = 0; k < n; k++)
			score[(size_t)b * n + k] +=
				pr->jac[(size_t)i * n + k] * pr->r[i];
	}
	for (int b = 0; b < g; b++) {
		const double *s = score + (size_t)b * n;
		int any = 0;
		for (int k = 0; k < n; k++)
			any |= s[k] != 0;
		used += any;
		for (int i = 0; i < n; i++)
			for (int j = 0; j < n; j++)
				meat[i * n + j] += s[i] * s[j];
	}
	free(score);
	double f = used > 1 && pr->m > n ? (double)used / (used - 1) *
						   (pr->m - 1.0) / (pr->m - n)
					 : 1;
	for (int k = 0; k < n * n; k++)
		meat[k] *= f;
	sandwich(ainv, meat, n, out);
	return used;
}

/* The delete-one-region jackknife, linearised (uncertainty.h); returns
 * the number of regions holding residuals. */
static int region_covariance(const struct glint_unc_problem *pr,
			     const double *a, double *out)
{
	int n = pr->n, g = pr->nregions, used = 0, ret = 0;
	double *ag = calloc((size_t)g * n * n, sizeof(double));
	double *sg = calloc((size_t)g * n, sizeof(double));
	double *d = calloc((size_t)g * n, sizeof(double));
	double mean[N] = { 0 };

	memset(out, 0, sizeof(double) * (size_t)(n * n));
	if (!ag || !sg || !d) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	for (int i = 0; i < pr->m; i++) {
		int b = pr->region[i];
		if (b < 0 || b >= g)
			continue;
		const double *ji = pr->jac + (size_t)i * n;
		for (int k = 0; k < n; k++) {
			sg[(size_t)b * n + k] += ji[k] * pr->r[i];
			for (int l = 0; l < n; l++)
				ag[((size_t)b * n + k) * n + l] +=
					ji[k] * ji[l];
		}
	}
	for (int b = 0; b < g; b++) {
		double rest[N * N], rinv[N * N];
		int unseen[N], any = 0;
		for (int k = 0; k < n; k++)
			any |= ag[((size_t)b * n + k) * n + k] != 0;
		if (!any)
			continue;
		for (int k = 0; k < n * n; k++)
			rest[k] = a[k] - ag[(size_t)b * n * n + k];
		ret = glint_unc_normal_inverse(rest, n, rinv, unseen);
		if (ret < 0)
			goto out;
		double *db = d + (size_t)used * n;
		for (int k = 0; k < n; k++) {
			for (int l = 0; l < n; l++)
				db[k] +=
					rinv[k * n + l] * sg[(size_t)b * n + l];
			/* clamped to the bounds, as a refit would be */
			db[k] = fmin(pr->hi[k],
				     fmax(pr->lo[k], pr->p[k] + db[k])) -
				pr->p[k];
		}
		used++;
	}
	for (int b = 0; b < used; b++)
		for (int k = 0; k < n; k++)
			mean[k] += d[(size_t)b * n + k] / used;
	for (int b = 0; used > 2 && b < used; b++)
		for (int i = 0; i < n; i++)
			for (int j = 0; j < n; j++)
				out[i * n + j] +=
					(used - 1.0) / used *
					(d[(size_t)b * n + i] - mean[i]) *
					(d[(size_t)b * n + j] - mean[j]);
	ret = used > 2 ? used : 0;
out:
	free(ag);
	free(sg);
	free(d);
	return ret;
}

/* The Monte Carlo covariance of the optimum of the sample sets' mean:
 * the sample covariance of each set's Gauss-Newton step over K. */
static void mc_covariance(const struct glint_unc_problem *pr,
			  const double *ainv, double *out)
{
	int n = pr->n, k1 = pr->ndraws;
	double d[GLINT_UNC_MAX_N * 64], mean[N] = { 0 };

	memset(out, 0, sizeof(double) * (size_t)(n * n));
	if (k1 < 2 || k1 > 64)
		return;
	for (int k = 0; k < k1; k++) {
		const double *r = pr->draws + (size_t)k * pr->m;
		double g[N] = { 0 };
		for (int i = 0; i < pr->m; i++)
			for (int j = 0; j < n; j++)
				g[j] += pr->jac[(size_t)i * n + j] * r[i];
		for (int j = 0; j < n; j++) {
			double s = 0;
			for (int l = 0; l < n; l++)
				s -= ainv[j * n + l] * g[l];
			double q =
				fmin(pr->hi[j], fmax(pr->lo[j], pr->p[j] + s));
			d[k * n + j] = q - pr->p[j];
			mean[j] += d[k * n + j] / k1;
		}
	}
	for (int k = 0; k < k1; k++)
		for (int i = 0; i < n; i++)
			for (int j = 0; j < n; j++)
				out[i * n + j] += (d[k * n + i] - mean[i]) *
						  (d[k * n + j] - mean[j]) /
						  ((k1 - 1.0) * k1);
}

/* The sampling lean and its standard error (uncertainty.h) over the
 * parameters off their bounds, from the normal matrix a (n x n). */
static int sampling_lean(const struct glint_unc_problem *pr, const double *a,
			 struct glint_uncertainty *u)
{
	int n = pr->n, g = pr->nblocks, k1 = pr->ndraws, f[N], nf = 0;
	double af[N * N], ainv[N * N], c[N] = { 0 }, vc[N * N] = { 0 };
	int unseen[N];

	if (!pr->draws_jr || k1 < 2 || g < 2)
		return 0;
	for (int k = 0; k < n; k++) {
		double tol = 1e-9 * (pr->hi[k] - pr->lo[k]);
		if (pr->p[k] > pr->lo[k] + tol && pr->p[k] < pr->hi[k] - tol)
			f[nf++] = k;
	}
	if (nf == 0)
		return 0;
	for (int i = 0; i < nf; i++)
		for (int j = 0; j < nf; j++)
			af[i * nf + j] = a[f[i] * n + f[j]];
	int ret = glint_unc_normal_inverse(af, nf, ainv, unseen);
	if (ret < 0)
		return ret;
	for (int b = 0; b < g; b++)
		for (int i = 0; i < nf; i++)
			c[i] += pr->draws_jr[(size_t)b * n + f[i]];
	/* The blocks' spread about their mean: the variance of the sum. */
	for (int b = 0; b < g; b++) {
		const double *x = pr->draws_jr + (size_t)b * n;
		for (int i = 0; i < nf; i++)
			for (int j = 0; j < nf; j++)
				vc[i * nf + j] += (x[f[i]] - c[i] / g) *
						  (x[f[j]] - c[j] / g) * g /
						  (g - 1.0);
	}
	double cl[N * N], sc = 1 / (k1 * (k1 - 1.0));
	sandwich(ainv, vc, nf, cl);
	for (int i = 0; i < nf; i++) {
		if (unseen[i])
			continue;
		double s = 0;
		for (int j = 0; j < nf; j++)
			s -= ainv[i * nf + j] * c[j];
		u->lean[f[i]] = s * sc;
		u->lean_se[f[i]] = sqrt(fmax(0, cl[i * nf + i])) * sc;
	}
	return 0;
}

int glint_uncertainty_compute(const struct glint_unc_problem *pr,
			      struct glint_uncertainty *u)
{
	int n = pr->n, m = pr->m, unseen[N];
	double a[N * N] = { 0 }, ainv[N * N];

	memset(u, 0, sizeof(*u));
	if (n < 1 || n > N || m <= n || pr->ndraws < 0 || pr->ndraws > 64)
		return glint_error_set(
			EINVAL,
			"uncertainty: %d parameters, %d "
			"residuals, %d sample sets: out of range",
			n, m, pr->ndraws);
	u->n = n;
	u->level = pr->level > 0 && pr->level < 1 ? pr->level : 0.95;
	u->ndraws = pr->ndraws;
	double rr = 0;
	for (int i = 0; i < m; i++) {
		const double *ji = pr->jac + (size_t)i * n;
		for (int k = 0; k < n; k++)
			for (int l = 0; l < n; l++)
				a[k * n + l] += ji[k] * ji[l];
		rr += pr->r[i] * pr->r[i];
	}
	u->chi2_dof = rr / (m - n);
	int ret = glint_unc_normal_inverse(a, n, ainv, unseen);
	if (ret < 0)
		return ret;
	for (int k = 0; k < n * n; k++)
		u->cov_textbook[k] = u->chi2_dof * ainv[k];
	memcpy(u->cov_blocks, u->cov_textbook, sizeof(u->cov_blocks));
	if (pr->nblocks > 1 && pr->block) {
		ret = block_covariance(pr, ainv, u->cov_blocks);
		if (ret < 0)
			return ret;
		u->nblocks = ret;
	}
	if (pr->region && pr->nregions >= 3) {
		ret = region_covariance(pr, a, u->cov_regions);
		if (ret < 0)
			return ret;
		u->nregions = ret;
	}
	/* The noise part never below the textbook one nor the regions'
	 * jackknife: scale each parameter's row and column up (keeps it
	 * positive semi-definite). */
	double sc[N];
	int by_regions[N];
	for (int k = 0; k < n; k++) {
		double b = u->cov_blocks[k * n + k],
		       t = u->cov_textbook[k * n + k],
		       g = u->cov_regions[k * n + k];
		by_regions[k] = g > t && g > b;
		t = fmax(t, g);
		sc[k] = b > 0 && t > b ? sqrt(t / b) : 1;
	}
	mc_covariance(pr, ainv, u->cov_mc);
	ret = sampling_lean(pr, a, u);
	if (ret < 0)
		return ret;
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			u->cov[i * n + j] =
				sc[i] * sc[j] * u->cov_blocks[i * n + j] +
				u->cov_mc[i * n + j];
	for (int k = 0; k < n; k++) {
		u->sys[k] = pr->sys && pr->sys[k] > 0 ? pr->sys[k] : 0;
		u->sys_shared[k] = pr->sys_shared ? pr->sys_shared[k] : 0;
		u->sys[k] = hypot(u->sys[k], u->sys_shared[k]);
		u->cov[k * n + k] += u->sys[k] * u->sys[k];
		for (int j = 0; j < n && pr->sys_shared; j++)
			if (j != k)
				u->cov[k * n + j] +=
					pr->sys_shared[k] * pr->sys_shared[j];
	}
	for (int k = 0; k < n; k++) {
		double vb = sc[k] * sc[k] * u->cov_blocks[k * n + k],
		       vm = u->cov_mc[k * n + k],
		       v = vb + vm + u->sys[k] * u->sys[k];
		double nb = by_regions[k]    ? u->nregions - 1.0
			    : u->nblocks > 1 ? u->nblocks - 1.0
					     : m - n;
		double den =
			(vb > 0 ? vb * vb / nb : 0) +
			(vm > 0 && u->ndraws > 1 ? vm * vm / (u->ndraws - 1)
						 : 0);
		u->dof[k] = den > 0 ? v * v / den : m - n;
		u->t[k] = gsl_cdf_tdist_Pinv(0.5 + 0.5 * u->level, u->dof[k]);
		u->se[k] = unseen[k] ? INFINITY : sqrt(fmax(0, v));
		u->se_textbook[k] =
			unseen[k] ? INFINITY
				  : sqrt(fmax(0, u->cov_textbook[k * n + k]));
		u->lo[k] = unseen[k] ? pr->lo[k]
				     : fmax(pr->lo[k],
					    pr->p[k] - u->t[k] * u->se[k]);
		u->hi[k] = unseen[k] ? pr->hi[k]
				     : fmin(pr->hi[k],
					    pr->p[k] + u->t[k] * u->se[k]);
	}
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			double d = u->se[i] * u->se[j];
			u->corr[i * n + j] =
				i == j ? 1
				: unseen[i] || unseen[j] || !(d > 0)
					? 0
					: u->cov[i * n + j] / d;
			if (unseen[i] || unseen[j])
				u->cov[i * n + j] = i == j ? INFINITY : 0;
		}
	return 0;
}

double glint_uncertainty_corr_without_shared(const struct glint_uncertainty *u,
					     int i, int j)
{
	int n = u->n;
	const double *s = u->sys_shared;

	if (i == j)
		return 1;
	if (!isfinite(u->se[i]) || !isfinite(u->se[j]))
		return 0;
	double d = (u->cov[i * n + i] - s[i] * s[i]) *
		   (u->cov[j * n + j] - s[j] * s[j]);
	return d > 0 ? (u->cov[i * n + j] - s[i] * s[j]) / sqrt(d) : 0;
}

double glint_uncertainty_delta(const struct glint_uncertainty *u,
			       const double *grad)
{
	double s = 0;
	for (int i = 0; i < u->n; i++) {
		if (grad[i] == 0)
			continue;
		if (!isfinite(u->se[i]))
			return INFINITY;
		for (int j = 0; j < u->n; j++)
			if (grad[j] != 0)
				s += grad[i] * u->cov[i * u->n + j] * grad[j];
	}
	return sqrt(fmax(0, s));
}
