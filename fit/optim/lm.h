/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_OPTIM_LM_H
#define GLINT_FIT_OPTIM_LM_H

/*
 * Bounded Levenberg-Marquardt for small problems (a few to a few dozen
 * parameters, any number of residuals): minimise 1/2 |r(p)|^2 subject to
 * lo <= p <= hi.
 *
 * Projected LM with an active set: each iteration, parameters on a bound
 * whose gradient pushes outward are held; the damped Gauss-Newton step
 * (J^T J + lambda diag(J^T J)) d = -J^T r on the others is projected onto
 * the box, accepted if it lowers the cost (Nielsen's damping update).  So
 * optima on a bound (a diffuse albedo of 0) are reached exactly, not
 * approached as with a transformed parameter.  Why not a library: GSL's
 * multifit_nlinear and cminpack have no bounds, levmar (which has) is not
 * packaged for Debian, and Ceres would bring Eigen, glog and SuiteSparse to
 * solve 8 parameters; GSL does the linear algebra here.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected from the objective (GSL's errors are turned into
 * them).  Threads: calls the objective from the calling thread;
 * re-entrant.  Who frees: nothing (the caller's arrays).
 */

struct glint_lm_problem {
	int n;		  /* parameters */
	int m;		  /* residuals */
	const double *lo; /* bounds, n each */
	const double *hi;
	/* r[m] at p; returns 0 or a negative errno (stops the solve). */
	int (*residuals)(void *ctx, const double *p, double *r);
	/* J[m * n] (row-major) at p given r = r(p), or NULL for forward
	 * differences. */
	int (*jacobian)(void *ctx, const double *p, const double *r,
			double *jac);
	void *ctx;
};

struct glint_lm_opts {
	int max_iter;	/* iterations (accepted or not) */
	double ftol;	/* stop when the relative cost drop is below */
	double xtol;	/* stop when the relative step is below */
	double gtol;	/* stop when the projected gradient is below */
	double fd_step; /* relative forward-difference step */
	/* Stop when every accepted step is below se_tol standard errors
	 * (statistically meaningless moves), and before evaluating a
	 * lightly damped step (damping at most 1) that is below them;
	 * 0 disables. */
	double se_tol;
	/* No Jacobian at the final point when the last step moved there
	 * (the caller wants the point alone): se is then NaN, at_bound
	 * from the last one's gradient. */
	int no_final_jacobian;
	/* Called after every iteration (may be NULL). */
	void (*progress)(void *ctx, int iter, double cost, const double *p);
	void *progress_ctx;
};

#define GLINT_LM_MAX_N 32

struct glint_lm_result {
	int iterations;
	int evaluations; /* residual evaluations, Jacobians excluded */
	int jacobians;
	double cost0, cost; /* 1/2 |r|^2 at start and end */
	int converged;
	const char *reason;
	/* Standard errors from s^2 (J^T J)^-1 at the optimum, s^2 =
	 * |r|^2 / (m - n_free); 0 for parameters on a bound, NaN when the
	 * free parameters are not identifiable (singular J^T J). */
	double se[GLINT_LM_MAX_N];
	int at_bound[GLINT_LM_MAX_N];
};

void glint_lm_default_opts(struct glint_lm_opts *o);

/* Solve from p (clamped into the bounds first); p receives the result. */
int glint_lm_solve(const struct glint_lm_problem *pr,
		   const struct glint_lm_opts *o, double *p,
		   struct glint_lm_result *res);

#endif
