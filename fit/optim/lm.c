/* SPDX-License-Identifier: MIT */
#include "lm.h"

#include "core/error.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

void glint_lm_default_opts(struct glint_lm_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->max_iter = 100;
	o->ftol = 1e-9;
	o->xtol = 1e-8;
	o->gtol = 1e-12;
	o->fd_step = 1e-4;
}

static double half_sq(const double *r, int m)
{
	double s = 0;
	for (int i = 0; i < m; i++)
		s += r[i] * r[i];
	return 0.5 * s;
}

static double clampd(double v, double lo, double hi)
{
	return v < lo ? lo : v > hi ? hi : v;
}

/* Forward differences, stepping inwards at an upper bound. */
static int fd_jacobian(const struct glint_lm_problem *pr, double step,
		       const double *p, const double *r, double *jac,
		       double *rtmp, int *evals)
{
	double q[GLINT_LM_MAX_N];

	memcpy(q, p, (size_t)pr->n * sizeof(double));
	for (int k = 0; k < pr->n; k++) {
		double h = step * fmax(fabs(p[k]), 1e-2);
		if (p[k] + h > pr->hi[k])
			h = -h;
		q[k] = p[k] + h;
		int ret = pr->residuals(pr->ctx, q, rtmp);
		(*evals)++;
		if (ret < 0)
			return ret;
		for (int i = 0; i < pr->m; i++)
			jac[(size_t)i * pr->n + k] = (rtmp[i] - r[i]) / h;
		q[k] = p[k];
	}
	return 0;
}

/* A = J^T J and g = J^T r. */
static void normal_eq(const double *jac, const double *r, int m, int n,
		      double *a, double *g)
{
	memset(a, 0, (size_t)n * n * sizeof(double));
	memset(g, 0, (size_t)n * sizeof(double));
	for (int i = 0; i < m; i++) {
		const double *row = jac + (size_t)i * n;
		for (int j = 0; j < n; j++) {
			g[j] += row[j] * r[i];
			for (int k = j; k < n; k++)
				a[j * n + k] += row[j] * row[k];
		}
	}
	for (int j = 0; j < n; j++)
		for (int k = 0; k < j; k++)
			a[j * n + k] = a[k * n + j];
}

/* Solve the damped system over the free set; 0 or -1 if singular. */
static int damped_step(const double *a, const double *g, const int *freev,
		       int n, double lambda, double *d)
{
	int idx[GLINT_LM_MAX_N], nf = 0;
	double buf[GLINT_LM_MAX_N * GLINT_LM_MAX_N], rhs[GLINT_LM_MAX_N];

	for (int j = 0; j < n; j++) {
		d[j] = 0;
		if (freev[j])
			idx[nf++] = j;
	}
	if (!nf)
		return 0;
	for (int u = 0; u < nf; u++) {
		for (int v = 0; v < nf; v++)
			buf[u * nf + v] = a[idx[u] * n + idx[v]];
		double dg = a[idx[u] * n + idx[u]];
		buf[u * nf + u] += lambda * fmax(dg, 1e-12);
		rhs[u] = -g[idx[u]];
	}
	gsl_matrix_view mv = gsl_matrix_view_array(buf, (size_t)nf, (size_t)nf);
	gsl_vector_view bv = gsl_vector_view_array(rhs, (size_t)nf);
	gsl_error_handler_t *old = gsl_set_error_handler_off();
	int st = gsl_linalg_cholesky_decomp1(&mv.matrix);
	if (!st)
		st = gsl_linalg_cholesky_svx(&mv.matrix, &bv.vector);
	gsl_set_error_handler(old);
	if (st)
		return -1;
	for (int u = 0; u < nf; u++)
		d[idx[u]] = rhs[u];
	return 0;
}

static void standard_errors(const double *a, int n, int m, double cost,
			    const int *freev, struct glint_lm_result *res)
{
	int idx[GLINT_LM_MAX_N], nf = 0;
	double buf[GLINT_LM_MAX_N * GLINT_LM_MAX_N];

	for (int j = 0; j < n; j++) {
		res->se[j] = 0;
		if (freev[j])
			idx[nf++] = j;
	}
	if (!nf)
		return;
	double s2 = m > nf ? 2 * cost / (m - nf) : NAN;
	for (int u = 0; u < nf; u++)
		for (int v = 0; v < nf; v++)
			buf[u * nf + v] = a[idx[u] * n + idx[v]];
	gsl_matrix_view mv = gsl_matrix_view_array(buf, (size_t)nf, (size_t)nf);
	gsl_error_handler_t *old = gsl_set_error_handler_off();
	int st = gsl_linalg_cholesky_decomp1(&mv.matrix);
	if (!st)
		st = gsl_linalg_cholesky_invert(&mv.matrix);
	gsl_set_error_handler(old);
	for (int u = 0; u < nf; u++)
		res->se[idx[u]] =
			st ? NAN : sqrt(fmax(0, s2 * buf[u * nf + u]));
}

/* Every |q - p| below tol standard errors (from s^2 (J^T J)^-1)? */
static int step_insignificant(const double *a, const int *freev, int n, int m,
			      double cost, const double *p, const double *q,
			      double tol)
{
	struct glint_lm_result tmp;

	standard_errors(a, n, m, cost, freev, &tmp);
	for (int j = 0; j < n; j++) {
		if (!freev[j])
			continue;
		if (!isfinite(tmp.se[j]) ||
		    fabs(q[j] - p[j]) >= tol * tmp.se[j])
			return 0;
	}
	return 1;
}

int glint_lm_solve(const struct glint_lm_problem *pr,
		   const struct glint_lm_opts *o, double *p,
		   struct glint_lm_result *res)
{
	int n = pr->n, m = pr->m, ret = 0;
	double *r = NULL, *rn = NULL, *jac = NULL, *a = NULL;
	double g[GLINT_LM_MAX_N], d[GLINT_LM_MAX_N], q[GLINT_LM_MAX_N];
	int freev[GLINT_LM_MAX_N];
	double lambda = 1e-3, nu = 2;

	memset(res, 0, sizeof(*res));
	if (n < 1 || n > GLINT_LM_MAX_N || m < 1)
		return glint_error_set(EINVAL,
				       "least squares with %d parameters and "
				       "%d residuals: expected 1..%d and >= 1",
				       n, m, GLINT_LM_MAX_N);
	r = malloc((size_t)m * sizeof(double));
	rn = malloc((size_t)m * sizeof(double));
	jac = malloc((size_t)m * n * sizeof(double));
	a = malloc((size_t)n * n * sizeof(double));
	if (!r || !rn || !jac || !a) {
		ret = glint_error_set(ENOMEM, "out of memory for %d residuals",
				      m);
		goto out;
	}
	for (int j = 0; j < n; j++)
		p[j] = clampd(p[j], pr->lo[j], pr->hi[j]);
	ret = pr->residuals(pr->ctx, p, r);
	res->evaluations++;
	if (ret < 0)
		goto out;
	double cost = half_sq(r, m);
	res->cost0 = cost;
	int need_jac = 1, small_drops = 0, rejects = 0;
	res->reason = "iteration limit";
	for (int it = 0; it < o->max_iter; it++) {
		res->iterations = it + 1;
		if (need_jac) {
			ret = pr->jacobian
				      ? pr->jacobian(pr->ctx, p, r, jac)
				      : fd_jacobian(pr, o->fd_step, p, r, jac,
						    rn, &res->evaluations);
			res->jacobians++;
			if (ret < 0)
				goto out;
			normal_eq(jac, r, m, n, a, g);
			need_jac = 0;
		}
		/* Active set: on a bound with the gradient pushing out. */
		double pg = 0;
		for (int j = 0; j < n; j++) {
			int lo = p[j] <= pr->lo[j] && g[j] > 0;
			int hi = p[j] >= pr->hi[j] && g[j] < 0;
			freev[j] = !(lo || hi);
			if (freev[j])
				pg = fmax(pg, fabs(g[j]));
		}
		if (pg <= o->gtol * fmax(1, cost)) {
			res->converged = 1;
			res->reason = "projected gradient ~ 0";
			break;
		}
		if (damped_step(a, g, freev, n, lambda, d) < 0) {
			lambda *= nu;
			nu *= 2;
			continue;
		}
		double step = 0, size = 0;
		for (int j = 0; j < n; j++) {
			q[j] = clampd(p[j] + d[j], pr->lo[j], pr->hi[j]);
			step = fmax(step, fabs(q[j] - p[j]));
			size = fmax(size, fabs(p[j]));
		}
		if (step <= o->xtol * (size + o->xtol)) {
			res->converged = 1;
			res->reason = "step ~ 0";
			break;
		}
		ret = pr->residuals(pr->ctx, q, rn);
		res->evaluations++;
		if (ret < 0)
			goto out;
		double cn = half_sq(rn, m);
		/* Predicted drop of the (projected) linear model. */
		double pred = 0;
		for (int j = 0; j < n; j++) {
			double dj = q[j] - p[j];
			pred -= g[j] * dj;
			for (int k = 0; k < n; k++)
				pred -= 0.5 * dj * a[j * n + k] * (q[k] - p[k]);
		}
		double rho = pred > 0 ? (cost - cn) / pred : -1;
		if (cn < cost && o->se_tol > 0 &&
		    step_insignificant(a, freev, n, m, cost, p, q, o->se_tol)) {
			memcpy(p, q, (size_t)n * sizeof(double));
			memcpy(r, rn, (size_t)m * sizeof(double));
			cost = cn;
			need_jac = 1;
			res->converged = 1;
			res->reason = "steps below the standard errors";
			break;
		}
		if (cn < cost) {
			rejects = 0;
			double drop = (cost - cn) / fmax(cost, 1e-300);
			memcpy(p, q, (size_t)n * sizeof(double));
			memcpy(r, rn, (size_t)m * sizeof(double));
			cost = cn;
			need_jac = 1;
			double t = 2 * rho - 1;
			lambda *= fmax(1.0 / 3, 1 - t * t * t);
			nu = 2;
			small_drops = drop < o->ftol ? small_drops + 1 : 0;
			if (small_drops >= 2) {
				res->converged = 1;
				res->reason = "cost no longer drops";
				break;
			}
		} else {
			lambda *= nu;
			nu *= 2;
			/* Rejected again and again, or damped hard and the
			 * linear model promises next to nothing: this is the
			 * minimum (each rejection costs an evaluation). */
			if (++rejects >= 4 ||
			    (lambda > 1 && pred <= o->ftol * cost)) {
				res->converged = 1;
				res->reason = "no acceptable step";
				break;
			}
			if (lambda > 1e16) {
				res->converged = 1;
				res->reason = "no descent left";
				break;
			}
		}
		if (o->progress)
			o->progress(o->progress_ctx, it + 1, cost, p);
	}
	res->cost = cost;
	/* Standard errors from a Jacobian at the final point. */
	if (need_jac) {
		ret = pr->jacobian ? pr->jacobian(pr->ctx, p, r, jac)
				   : fd_jacobian(pr, o->fd_step, p, r, jac, rn,
						 &res->evaluations);
		res->jacobians++;
		if (ret < 0)
			goto out;
		normal_eq(jac, r, m, n, a, g);
	}
	for (int j = 0; j < n; j++) {
		int lo = p[j] <= pr->lo[j] && g[j] >= 0;
		int hi = p[j] >= pr->hi[j] && g[j] <= 0;
		res->at_bound[j] = lo || hi;
		freev[j] = !res->at_bound[j];
	}
	standard_errors(a, n, m, cost, freev, res);
	ret = 0;
out:
	free(r);
	free(rn);
	free(jac);
	free(a);
	return ret;
}
