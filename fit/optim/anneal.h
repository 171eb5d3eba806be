/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_OPTIM_ANNEAL_H
#define GLINT_FIT_OPTIM_ANNEAL_H

/*
 * Adaptive simulated annealing (Ingber's ASA, re-implemented: GSL's
 * gsl_siman is plain fixed-schedule annealing, and Ingber's ASA code is not
 * packaged for Debian), bounded and reproducible from a seed:
 *   - each parameter i has its own temperature T_i(k_i) = T_0 exp(-c
 *     k_i^(1/D)) (D parameters) and draws its step from ASA's fat-tailed
 *     generating distribution  y = sgn(u - 1/2) T_i ((1 + 1/T_i)^|2u-1| - 1)
 *     times its range, redrawn until inside the bounds;
 *   - a move is accepted with probability min(1, exp(-dC / T_a)), with its
 *     own acceptance temperature on the same schedule, starting at the
 *     first cost;
 *   - re-annealing every `reanneal_every` accepted moves: the cost's
 *     sensitivity s_i to each parameter at the best point is measured
 *     (a difference over 1e-3 of its range), and each T_i rescaled by
 *     max(s) / s_i - parameters the cost barely depends on keep searching
 *     widely, sensitive ones narrow down - with k_i reset to match; the
 *     acceptance temperature restarts from the best cost;
 *   - stop after max_evals evaluations, or when the best cost has not
 *     improved by a relative ftol over stall_evals evaluations.
 * The caller polishes the best point with Levenberg-Marquardt.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected from the objective.  Threads: calls the objective
 * from the calling thread.  Who frees: nothing (the caller's arrays).
 */

#include <stdint.h>

struct glint_anneal_opts {
	uint64_t seed;
	int max_evals;	    /* default 3000 */
	int stall_evals;    /* default 600 */
	double ftol;	    /* default 1e-6 */
	int reanneal_every; /* accepted moves, default 50 */
	double t_final;	    /* parameter temperature reached at max_evals,
			       default 1e-6 (T_0 = 1) */
};

void glint_anneal_default_opts(struct glint_anneal_opts *o);

struct glint_anneal_result {
	int evals, accepted, reanneals;
	double cost0, cost;
	const char *reason;
};

/* Minimise cost(ctx, p, &c) (0, or a negative errno that stops it) over
 * lo <= p <= hi from p (clamped); p receives the best point. */
int glint_anneal(int n, const double *lo, const double *hi,
		 int (*cost)(void *ctx, const double *p, double *c), void *ctx,
		 const struct glint_anneal_opts *o, double *p,
		 struct glint_anneal_result *res);

#endif
