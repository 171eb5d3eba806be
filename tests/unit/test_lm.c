/* SPDX-License-Identifier: MIT */
/* Bounded Levenberg-Marquardt on problems with known answers. */
#include "test.h"

#include "core/error.h"
#include "fit/optim/lm.h"

static int rosenbrock(void *ctx, const double *p, double *r)
{
	(void)ctx;
	r[0] = 10 * (p[1] - p[0] * p[0]);
	r[1] = 1 - p[0];
	return 0;
}

static void test_rosenbrock(void)
{
	double lo[2] = { -5, -5 }, hi[2] = { 5, 5 }, p[2] = { -1.2, 1 };
	struct glint_lm_problem pr = { 2, 2, lo, hi, rosenbrock, NULL, NULL };
	struct glint_lm_opts o;
	struct glint_lm_result res;
	glint_lm_default_opts(&o);
	CHECK(glint_lm_solve(&pr, &o, p, &res) == 0, "%s", glint_error_msg());
	CHECK(fabs(p[0] - 1) < 1e-6 && fabs(p[1] - 1) < 1e-6,
	      "Rosenbrock minimum at (%g, %g) after %d iterations (%s)", p[0],
	      p[1], res.iterations, res.reason);
	/* The same with a bound cutting off the minimum: x <= 0.5 gives
	 * the constrained optimum (0.5, 0.25). */
	hi[0] = 0.5;
	p[0] = -1.2;
	p[1] = 1;
	glint_lm_solve(&pr, &o, p, &res);
	CHECK(p[0] == 0.5 && fabs(p[1] - 0.25) < 1e-6 && res.at_bound[0] &&
		      !res.at_bound[1],
	      "bounded Rosenbrock at (%.9g, %.9g), at_bound %d %d", p[0], p[1],
	      res.at_bound[0], res.at_bound[1]);
}

/* no_final_jacobian: the same point, one Jacobian fewer (the last step
 * moved, so the full run linearises once more there), no standard
 * errors. */
static void test_no_final_jacobian(void)
{
	double lo[2] = { -5, -5 }, hi[2] = { 5, 5 };
	double p[2] = { -1.2, 1 }, q[2] = { -1.2, 1 };
	struct glint_lm_problem pr = { 2, 2, lo, hi, rosenbrock, NULL, NULL };
	struct glint_lm_opts o;
	struct glint_lm_result full, brief;
	glint_lm_default_opts(&o);
	o.max_iter = 8; /* stops mid-way, after a step */
	CHECK(glint_lm_solve(&pr, &o, p, &full) == 0, "%s", glint_error_msg());
	o.no_final_jacobian = 1;
	CHECK(glint_lm_solve(&pr, &o, q, &brief) == 0, "%s", glint_error_msg());
	CHECK(p[0] == q[0] && p[1] == q[1], "(%g, %g) against (%g, %g)", q[0],
	      q[1], p[0], p[1]);
	CHECK(brief.jacobians == full.jacobians - 1, "%d Jacobians against %d",
	      brief.jacobians, full.jacobians);
	CHECK(isnan(brief.se[0]) && isnan(brief.se[1]) && isfinite(full.se[0]),
	      "standard errors %g %g (full %g)", brief.se[0], brief.se[1],
	      full.se[0]);
}

/* y = a exp(-b x) + c, data made with c slightly negative: with c >= 0
 * the optimum is exactly on the bound. */
struct expdata {
	double x[40], y[40];
};

static int expfit(void *ctx, const double *p, double *r)
{
	struct expdata *d = ctx;
	for (int i = 0; i < 40; i++)
		r[i] = p[0] * exp(-p[1] * d->x[i]) + p[2] - d->y[i];
	return 0;
}

static void test_optimum_on_bound(void)
{
	struct expdata d;
	for (int i = 0; i < 40; i++) {
		d.x[i] = i * 0.1;
		d.y[i] = 0.8 * exp(-1.3 * d.x[i]) - 0.02;
	}
	double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 10, 1 };
	double p[3] = { 0.5, 0.5, 0.5 };
	struct glint_lm_problem pr = { 3, 40, lo, hi, expfit, NULL, &d };
	struct glint_lm_opts o;
	struct glint_lm_result res;
	glint_lm_default_opts(&o);
	glint_lm_solve(&pr, &o, p, &res);
	CHECK(p[2] == 0 && res.at_bound[2],
	      "c = %g (at bound %d): expected exactly 0", p[2],
	      res.at_bound[2]);
	CHECK(res.cost < res.cost0, "cost %g from %g", res.cost, res.cost0);
	CHECK(res.se[2] == 0 && isfinite(res.se[0]) && res.se[0] > 0,
	      "standard errors %g %g %g", res.se[0], res.se[1], res.se[2]);
}

/* Standard errors of a straight-line fit equal the textbook formula. */
struct line {
	double x[20], y[20];
};

static int linefit(void *ctx, const double *p, double *r)
{
	struct line *l = ctx;
	for (int i = 0; i < 20; i++)
		r[i] = p[0] + p[1] * l->x[i] - l->y[i];
	return 0;
}

static void test_standard_errors(void)
{
	struct line l;
	double sx = 0, sxx = 0;
	for (int i = 0; i < 20; i++) {
		l.x[i] = i;
		l.y[i] = 2 + 0.5 * i + 0.1 * sin(7.3 * i);
		sx += i;
		sxx += (double)i * i;
	}
	double lo[2] = { -100, -100 }, hi[2] = { 100, 100 }, p[2] = { 0, 0 };
	struct glint_lm_problem pr = { 2, 20, lo, hi, linefit, NULL, &l };
	struct glint_lm_opts o;
	struct glint_lm_result res;
	glint_lm_default_opts(&o);
	glint_lm_solve(&pr, &o, p, &res);
	double s2 = 2 * res.cost / 18, det = 20 * sxx - sx * sx;
	CHECK_NEAR(res.se[1], sqrt(s2 * 20 / det), 1e-6 * res.se[1],
		   "slope standard error");
	CHECK_NEAR(res.se[0], sqrt(s2 * sxx / det), 1e-6 * res.se[0],
		   "intercept standard error");
}

/* se_tol: a lightly damped step below se_tol standard errors is not
 * evaluated; the solve ends where it stands.  From 10 standard errors
 * off, the solve still reaches the optimum. */
static void test_se_tol_unevaluated(void)
{
	struct line l;
	for (int i = 0; i < 20; i++) {
		l.x[i] = i;
		l.y[i] = 2 + 0.5 * i + 0.1 * sin(7.3 * i);
	}
	double lo[2] = { -100, -100 }, hi[2] = { 100, 100 }, p[2] = { 0, 0 };
	struct glint_lm_problem pr = { 2, 20, lo, hi, linefit, NULL, &l };
	struct glint_lm_opts o;
	struct glint_lm_result best, near, far;
	glint_lm_default_opts(&o);
	glint_lm_solve(&pr, &o, p, &best);
	double opt[2] = { p[0], p[1] };

	o.se_tol = 0.1;
	p[0] = opt[0] + 0.05 * best.se[0];
	p[1] = opt[1];
	double start0 = p[0];
	CHECK(glint_lm_solve(&pr, &o, p, &near) == 0, "%s", glint_error_msg());
	CHECK(p[0] == start0 && p[1] == opt[1],
	      "moved from (%.9g, %.9g) to (%.9g, %.9g)", start0, opt[1], p[0],
	      p[1]);
	/* the start's residuals and its forward-difference Jacobian's two */
	CHECK(near.evaluations == 3 && near.converged &&
		      !strcmp(near.reason, "steps below the standard errors"),
	      "%d evaluations (%s): the step below 0.1 standard errors "
	      "was evaluated",
	      near.evaluations, near.reason);

	p[0] = opt[0] + 10 * best.se[0];
	p[1] = opt[1] - 10 * best.se[1];
	CHECK(glint_lm_solve(&pr, &o, p, &far) == 0, "%s", glint_error_msg());
	CHECK(fabs(p[0] - opt[0]) < 0.1 * best.se[0] &&
		      fabs(p[1] - opt[1]) < 0.1 * best.se[1],
	      "from 10 standard errors off: (%.9g, %.9g), the optimum "
	      "(%.9g, %.9g)",
	      p[0], p[1], opt[0], opt[1]);
}

static int failing(void *ctx, const double *p, double *r)
{
	(void)ctx;
	(void)p;
	(void)r;
	return glint_error_set(EIO, "render failed");
}

static void test_errors(void)
{
	double lo[1] = { 0 }, hi[1] = { 1 }, p[1] = { 0.5 };
	struct glint_lm_problem pr = { 1, 3, lo, hi, failing, NULL, NULL };
	struct glint_lm_opts o;
	struct glint_lm_result res;
	glint_lm_default_opts(&o);
	CHECK(glint_lm_solve(&pr, &o, p, &res) == -EIO,
	      "a failing residual function must stop the solve");
	pr.n = 0;
	CHECK(glint_lm_solve(&pr, &o, p, &res) == -EINVAL, "n = 0 accepted");
}

int main(void)
{
	RUN(test_rosenbrock);
	RUN(test_no_final_jacobian);
	RUN(test_optimum_on_bound);
	RUN(test_standard_errors);
	RUN(test_se_tol_unevaluated);
	RUN(test_errors);
	return test_result();
}
