/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_OPTIM_UNCERTAINTY_H
#define GLINT_FIT_OPTIM_UNCERTAINTY_H

/*
 * Uncertainty of a weighted least-squares estimate that a measurement can
 * stand on.  The textbook covariance s^2 (J^T J)^-1 assumes independent
 * residuals and an exact model evaluation; a photo of a sphere breaks
 * both: a model too small for the material leaves residuals that are
 * correlated over whole regions of the sphere, and the fitter's own
 * Monte Carlo estimate of the render has an error that moves the optimum.
 * So the reported covariance is the sum of two parts:
 *
 *   noise: a cluster-robust ("sandwich") covariance over spatial blocks of
 *     pixels, A^-1 (sum_b g_b g_b^T) A^-1 with A = J^T J and g_b = J_b^T
 *     r_b, scaled by G / (G - 1) (m - 1) / (m - n) (CR1); it equals the
 *     textbook one when residuals are independent and grows when they are
 *     not.  Never below the textbook one, s^2 A^-1 with s^2 = |r|^2 /
 *     (m - n) (the chi^2/dof scaling: a misfit inflates it);
 *   Monte Carlo: the fitter's estimate of the render is the average of
 *     K independent sample sets, r = (r_1 + ... + r_K) / K.  Each set's
 *     Gauss-Newton step from the optimum, d_k = -A^-1 J^T r_k (clamped to
 *     the bounds), is the optimum that set alone would give; the sample
 *     covariance of the d_k over K is the Monte Carlo covariance of the
 *     optimum of their average.
 *
 *   model error (optional, when the model misses the photo with
 *     structure): a delete-one-region jackknife over regions of the
 *     sphere that see the light differently (bands of the angle from the
 *     mirror direction to the brightest light and from the view
 *     direction: fit/misfit.h).  Dropping region g moves the optimum by
 *     d_g = (A - A_g)^-1 J_g^T r_g (linearised); the covariance
 *     (G - 1) / G sum_g (d_g - d)(d_g - d)^T is how much the answer
 *     depends on which light and geometry the pixels see, which for a
 *     model too small for the material is how much it would move under
 *     another light.  The noise part is never below it either (G - 1
 *     degrees of freedom where it is the larger).
 *
 *   systematic (optional): a standard uncertainty per parameter that the
 *     fit's residuals and sample sets cannot show, known from validation
 *     (the fast render against an independent renderer), added to the
 *     diagonal with infinite degrees of freedom; and one error source
 *     that moves several parameters together (s, signed), whose s s^T is
 *     added whole, so the correlations keep a ridge it runs along.
 *
 * Intervals are p +- t se, clipped to the bounds, with t Student's
 * quantile at the Welch-Satterthwaite degrees of freedom of the two parts
 * (G - 1 and K).  Directions J cannot see (A singular: e.g. roughness when
 * the specular albedo is 0) get an infinite standard error.  Coverage of
 * these intervals is measured, not assumed: tests/sim/test_coverage.c and
 * the README's coverage table.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: nothing (the
 * caller's arrays).
 */

#define GLINT_UNC_MAX_N 16

struct glint_unc_problem {
	int n;		       /* parameters */
	int m;		       /* residuals */
	const double *jac;     /* m x n, row-major, weighted, at the optimum */
	const double *r;       /* m weighted residuals at the optimum */
	const int *block;      /* block of each residual, 0 .. nblocks - 1 */
	int nblocks;	       /* 0: no block part (textbook only) */
	const double *p;       /* the optimum, n */
	const double *lo, *hi; /* bounds, n each */
	/* ndraws x m: the residuals at p under each independent sample set
	 * of the fitter, r their mean (may be NULL with ndraws 0; needs 2
	 * or more) */
	const double *draws;
	int ndraws;
	/* nblocks x n, or NULL: per block of residuals, sum over its
	 * residuals i and the sets s of (r_s,i - r_i) J_s,ik, with J_s set
	 * s's own Jacobian (the sampling lean below) */
	const double *draws_jr;
	/* n systematic standard uncertainties, or NULL */
	const double *sys;
	double level; /* of the intervals, e.g. 0.95 */
	/* region of each residual, 0 .. nregions - 1 (-1: none), for the
	 * model-error jackknife; NULL or nregions < 3: no such part */
	const int *region;
	int nregions;
	/* n, or NULL: one systematic error source's signed standard
	 * uncertainty in each parameter (s s^T is added) */
	const double *sys_shared;
};

struct glint_uncertainty {
	int n;
	/* n x n, row-major */
	double cov[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];		/* reported */
	double cov_textbook[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N]; /* s^2 A^-1 */
	double cov_blocks[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];	/* sandwich */
	double cov_mc[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N]; /* sample sets */
	/* the regions' jackknife (0 without regions) */
	double cov_regions[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];
	/* the systematic standard uncertainties, the shared source's part
	 * with the rest, and the shared source's (0 without one) */
	double sys[GLINT_UNC_MAX_N], sys_shared[GLINT_UNC_MAX_N];
	/* The sampling lean (with draws_jr): the expected offset of the
	 * optimum of the sets' mean from the optimum of the exact render,
	 * and its standard error (over the blocks); 0 for a parameter at
	 * its bound or unseen, or without draws_jr */
	double lean[GLINT_UNC_MAX_N], lean_se[GLINT_UNC_MAX_N];
	double corr[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];
	double se[GLINT_UNC_MAX_N]; /* sqrt(diag cov); INFINITY: unseen */
	double se_textbook[GLINT_UNC_MAX_N];		 /* for comparison */
	double lo[GLINT_UNC_MAX_N], hi[GLINT_UNC_MAX_N]; /* the interval */
	double dof[GLINT_UNC_MAX_N];			 /* of t */
	double t[GLINT_UNC_MAX_N];			 /* the quantile used */
	double chi2_dof;				 /* |r|^2 / (m - n) */
	double level;
	int nblocks, ndraws, nregions;
};

/* The inverse of the normal matrix a (n x n, symmetric), through its
 * eigen-decomposition scaled to a unit diagonal, eigenvalues below 1e-12
 * of the largest dropped; unseen[k] is 1 where a's diagonal is 0.
 * Returns 0 or a negative errno. */
int glint_unc_normal_inverse(const double *a, int n, double *ainv, int *unseen);

/* Fill u from pr.  Returns 0 or a negative errno with the message set
 * (bad sizes, out of memory). */
int glint_uncertainty_compute(const struct glint_unc_problem *pr,
			      struct glint_uncertainty *u);

/*
 * The sampling lean.  Each set's residuals are r_s(p) = rho(p) + e_s(p),
 * rho those of the exact render and e_s the set's Monte Carlo error; the
 * fit minimises |mean_s r_s|^2, whose expectation carries |e|^2 / K, a
 * function of p: the optimum leans to where the render's error is small
 * (errors in variables; for a lobe's albedo, regression dilution).  To
 * first order the lean is
 *   -A^-1 sum_i Cov(e_i, de_i/dp) / K,
 * and the covariance is estimated from the sets' own residuals and
 * Jacobians, sum_s (r_s,i - r_i) J_s,ik / (K - 1) (draws_jr), with its
 * standard error from the spread over the blocks.  Over the parameters
 * not at a bound.
 */

/* The correlation of parameters i and j without the shared systematic
 * source's part (pr.sys_shared): what the photos and the independent
 * terms say of the two, for a choice the photos must make (a reduced
 * model), where the shared source would decide it.  0 for an unseen
 * parameter. */
double glint_uncertainty_corr_without_shared(const struct glint_uncertainty *u,
					     int i, int j);

/* Standard error of a function f of the parameters, from its gradient
 * grad (n) by the delta method: sqrt(grad^T cov grad). */
double glint_uncertainty_delta(const struct glint_uncertainty *u,
			       const double *grad);

#endif
