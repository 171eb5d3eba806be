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

/* One solve's working state. */
struct lm_state {
	const struct glint_lm_problem *pr;
	const struct glint_lm_opts *o;
	struct glint_lm_result *res;
	int n, m;
	double *r, *rn, *jac, *a; /* residuals at p and at the trial q,
				   * Jacobian, JtJ */
	double g[GLINT_LM_MAX_N], d[GLINT_LM_MAX_N], q[GLINT_LM_MAX_N];
	int freev[GLINT_LM_MAX_N];
	double lambda, nu, cost;
	int small_drops, rejects;
	int stale; /* a, g are not at the final p (no_final_jacobian) */
};

/* The Jacobian at p and the normal equations (a = JtJ, g = Jt r). */
static int lm_linearise(struct lm_state *s, const double *p)
{
	const struct glint_lm_problem *pr = s->pr;
	int ret = pr->jacobian ? pr->jacobian(pr->ctx, p, s->r, s->jac)
			       : fd_jacobian(pr, s->o->fd_step, p, s->r, s->jac,
					     s->rn, &s->res->evaluations);
	s->res->jacobians++;
	if (ret == 0)
		normal_eq(s->jac, s->r, s->m, s->n, s->a, s->g);
	return ret;
}

/* The active set: a parameter on a bound with the gradient pushing out
 * is held; returns the largest free gradient component. */
static double lm_free_set(struct lm_state *s, const double *p)
{
	const struct glint_lm_problem *pr = s->pr;
	double pg = 0;
	for (int j = 0; j < s->n; j++) {
		int lo = p[j] <= pr->lo[j] && s->g[j] > 0;
		int hi = p[j] >= pr->hi[j] && s->g[j] < 0;
		s->freev[j] = !(lo || hi);
		if (s->freev[j])
			pg = fmax(pg, fabs(s->g[j]));
	}
	return pg;
}

/* The drop in cost the (projected) linear model predicts for p -> q. */
static double lm_predicted_drop(const struct lm_state *s, const double *p)
{
	double pred = 0;
	int n = s->n;
	for (int j = 0; j < n; j++) {
		double dj = s->q[j] - p[j];
		pred -= s->g[j] * dj;
		for (int k = 0; k < n; k++)
			pred -= 0.5 * dj * s->a[j * n + k] * (s->q[k] - p[k]);
	}
	return pred;
}

static void lm_take(struct lm_state *s, double *p, double cn)
{
	memcpy(p, s->q, (size_t)s->n * sizeof(double));
	memcpy(s->r, s->rn, (size_t)s->m * sizeof(double));
	s->cost = cn;
}

/*
 * Judge the trial point q (cost cn, predicted drop pred): take it or
 * raise the damping.  Returns 1 with res->reason when the solve has
 * converged, 0 to go on; *taken says whether p moved.
 */
static int lm_judge(struct lm_state *s, double *p, double cn, double pred,
		    int *taken)
{
	const struct glint_lm_opts *o = s->o;
	double rho = pred > 0 ? (s->cost - cn) / pred : -1;

	*taken = cn < s->cost;
	if (*taken && o->se_tol > 0 &&
	    step_insignificant(s->a, s->freev, s->n, s->m, s->cost, p, s->q,
			       o->se_tol)) {
		lm_take(s, p, cn);
		s->res->reason = "steps below the standard errors";
		return 1;
	}
	if (*taken) {
		s->rejects = 0;
		double drop = (s->cost - cn) / fmax(s->cost, 1e-300);
		lm_take(s, p, cn);
		double t = 2 * rho - 1;
		s->lambda *= fmax(1.0 / 3, 1 - t * t * t);
		s->nu = 2;
		s->small_drops = drop < o->ftol ? s->small_drops + 1 : 0;
		if (s->small_drops >= 2) {
			s->res->reason = "cost no longer drops";
			return 1;
		}
		return 0;
	}
	s->lambda *= s->nu;
	s->nu *= 2;
	/* Rejected again and again, or damped hard and the linear model
	 * promises next to nothing: this is the minimum (each rejection
	 * costs an evaluation). */
	if (++s->rejects >= 4 || (s->lambda > 1 && pred <= o->ftol * s->cost)) {
		s->res->reason = "no acceptable step";
		return 1;
	}
	if (s->lambda > 1e16) {
		s->res->reason = "no descent left";
		return 1;
	}
	return 0;
}

/* The damped iterations from p; res->reason says how they ended. */
static int lm_iterate(struct lm_state *s, double *p)
{
	const struct glint_lm_problem *pr = s->pr;
	const struct glint_lm_opts *o = s->o;
	struct glint_lm_result *res = s->res;
	int n = s->n, need_jac = 1, ret;

	res->reason = "iteration limit";
	for (int it = 0; it < o->max_iter; it++) {
		res->iterations = it + 1;
		if (need_jac) {
			ret = lm_linearise(s, p);
			if (ret < 0)
				return ret;
			need_jac = 0;
		}
		if (lm_free_set(s, p) <= o->gtol * fmax(1, s->cost)) {
			res->converged = 1;
			res->reason = "projected gradient ~ 0";
			break;
		}
		if (damped_step(s->a, s->g, s->freev, n, s->lambda, s->d) < 0) {
			s->lambda *= s->nu;
			s->nu *= 2;
			continue;
		}
		double step = 0, size = 0;
		for (int j = 0; j < n; j++) {
			s->q[j] = clampd(p[j] + s->d[j], pr->lo[j], pr->hi[j]);
			step = fmax(step, fabs(s->q[j] - p[j]));
			size = fmax(size, fabs(p[j]));
		}
		if (step <= o->xtol * (size + o->xtol)) {
			res->converged = 1;
			res->reason = "step ~ 0";
			break;
		}
		/* A lightly damped step below se_tol standard errors: the
		 * minimum is within them, and the step is not worth its
		 * evaluation (at the minimum of a Monte Carlo objective it is
		 * rejected as often as not, and each rejection costs one). */
		if (o->se_tol > 0 && s->lambda <= 1 &&
		    step_insignificant(s->a, s->freev, n, s->m, s->cost, p,
				       s->q, o->se_tol)) {
			res->converged = 1;
			res->reason = "steps below the standard errors";
			break;
		}
		ret = pr->residuals(pr->ctx, s->q, s->rn);
		res->evaluations++;
		if (ret < 0)
			return ret;
		int taken;
		double cn = half_sq(s->rn, s->m);
		if (lm_judge(s, p, cn, lm_predicted_drop(s, p), &taken)) {
			res->converged = 1;
			need_jac |= taken;
			break;
		}
		need_jac |= taken;
		if (o->progress)
			o->progress(o->progress_ctx, it + 1, s->cost, p);
	}
	/* Standard errors need a Jacobian at the final point. */
	if (need_jac && o->no_final_jacobian) {
		s->stale = 1;
		return 0;
	}
	return need_jac ? lm_linearise(s, p) : 0;
}

int glint_lm_solve(const struct glint_lm_problem *pr,
		   const struct glint_lm_opts *o, double *p,
		   struct glint_lm_result *res)
{
	struct lm_state s = { .pr = pr,
			      .o = o,
			      .res = res,
			      .n = pr->n,
			      .m = pr->m,
			      .lambda = 1e-3,
			      .nu = 2 };
	int n = pr->n, m = pr->m, ret = 0;

	memset(res, 0, sizeof(*res));
	if (n < 1 || n > GLINT_LM_MAX_N || m < 1)
		return glint_error_set(EINVAL,
				       "least squares with %d parameters and "
				       "%d residuals: expected 1..%d and >= 1",
				       n, m, GLINT_LM_MAX_N);
	s.r = malloc((size_t)m * sizeof(double));
	s.rn = malloc((size_t)m * sizeof(double));
	s.jac = malloc((size_t)m * n * sizeof(double));
	s.a = malloc((size_t)n * n * sizeof(double));
	if (!s.r || !s.rn || !s.jac || !s.a) {
		ret = glint_error_set(ENOMEM, "out of memory for %d residuals",
				      m);
		goto out;
	}
	for (int j = 0; j < n; j++)
		p[j] = clampd(p[j], pr->lo[j], pr->hi[j]);
	ret = pr->residuals(pr->ctx, p, s.r);
	res->evaluations++;
	if (ret < 0)
		goto out;
	s.cost = res->cost0 = half_sq(s.r, m);
	ret = lm_iterate(&s, p);
	if (ret < 0)
		goto out;
	res->cost = s.cost;
	for (int j = 0; j < n; j++) {
		int lo = p[j] <= pr->lo[j] && s.g[j] >= 0;
		int hi = p[j] >= pr->hi[j] && s.g[j] <= 0;
		res->at_bound[j] = lo || hi;
		s.freev[j] = !res->at_bound[j];
	}
	standard_errors(s.a, n, m, s.cost, s.freev, res);
	for (int j = 0; j < n && s.stale; j++)
		res->se[j] = NAN;
out:
	free(s.r);
	free(s.rn);
	free(s.jac);
	free(s.a);
	return ret;
}
