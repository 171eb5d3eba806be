/* SPDX-License-Identifier: MIT */
#include "anneal.h"

#include "lm.h" /* GLINT_LM_MAX_N */

#include "core/error.h"

#include <math.h>
#include <string.h>

void glint_anneal_default_opts(struct glint_anneal_opts *o)
{
	o->seed = 1;
	o->max_evals = 3000;
	o->stall_evals = 600;
	o->ftol = 1e-6;
	o->reanneal_every = 50;
	o->t_final = 1e-6;
}

/* splitmix64: small, fast, reproducible across platforms. */
static double u01(uint64_t *s)
{
	uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	z ^= z >> 31;
	return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* ASA's generating distribution on [-1, 1] at temperature t. */
static double asa_step(double t, uint64_t *s)
{
	double u = u01(s);
	double a = fabs(2 * u - 1);
	return (u < 0.5 ? -1 : 1) * t * (pow(1 + 1 / t, a) - 1);
}

int glint_anneal(int n, const double *lo, const double *hi,
		 int (*cost)(void *ctx, const double *p, double *c), void *ctx,
		 const struct glint_anneal_opts *o, double *p,
		 struct glint_anneal_result *res)
{
	struct glint_anneal_opts def;
	double cur[GLINT_LM_MAX_N], best[GLINT_LM_MAX_N], trial[GLINT_LM_MAX_N];
	double k[GLINT_LM_MAX_N], ka = 0, t0a;
	double c_cur, c_best, c_trial;
	uint64_t s;
	int ret, since_best = 0, since_reanneal = 0;

	memset(res, 0, sizeof(*res));
	if (!o) {
		glint_anneal_default_opts(&def);
		o = &def;
	}
	if (n < 1 || n > GLINT_LM_MAX_N)
		return glint_error_set(EINVAL, "anneal: %d parameters", n);
	s = o->seed * 0x2545f4914f6cdd1dull + 1;
	double D = n;
	/* T(k) = exp(-c k^(1/D)) reaches t_final at max_evals. */
	double c = -log(o->t_final) / pow((double)o->max_evals, 1 / D);
	for (int i = 0; i < n; i++) {
		cur[i] = fmin(hi[i], fmax(lo[i], p[i]));
		k[i] = 0;
	}
	ret = cost(ctx, cur, &c_cur);
	if (ret < 0)
		return ret;
	res->evals = 1;
	res->cost0 = c_cur;
	c_best = c_cur;
	memcpy(best, cur, sizeof(double) * (size_t)n);
	t0a = c_cur > 0 ? c_cur : 1;
	res->reason = "evaluation budget used";
	while (res->evals < o->max_evals) {
		for (int i = 0; i < n; i++) {
			double ti = exp(-c * pow(k[i], 1 / D));
			double r = hi[i] - lo[i], v;
			int tries = 0;
			do {
				v = cur[i] + asa_step(ti, &s) * r;
			} while ((v < lo[i] || v > hi[i]) && ++tries < 100);
			trial[i] = fmin(hi[i], fmax(lo[i], v));
			k[i] += 1;
		}
		ret = cost(ctx, trial, &c_trial);
		if (ret < 0)
			return ret;
		res->evals++;
		ka += 1;
		double ta = t0a * exp(-c * pow(ka, 1 / D));
		double dc = c_trial - c_cur;
		if (dc <= 0 || u01(&s) < exp(-dc / fmax(ta, 1e-300))) {
			memcpy(cur, trial, sizeof(double) * (size_t)n);
			c_cur = c_trial;
			res->accepted++;
			since_reanneal++;
		}
		if (c_cur < c_best * (1 - o->ftol)) {
			c_best = c_cur;
			memcpy(best, cur, sizeof(double) * (size_t)n);
			since_best = 0;
		} else if (++since_best >= o->stall_evals) {
			res->reason = "no improvement";
			break;
		}
		if (since_reanneal >= o->reanneal_every &&
		    res->evals + n < o->max_evals) {
			/* Sensitivities at the best point. */
			double sens[GLINT_LM_MAX_N], smax = 0;
			for (int i = 0; i < n; i++) {
				double q[GLINT_LM_MAX_N], cq;
				memcpy(q, best, sizeof(double) * (size_t)n);
				double h = 1e-3 * (hi[i] - lo[i]);
				q[i] = best[i] + h <= hi[i] ? best[i] + h
							    : best[i] - h;
				ret = cost(ctx, q, &cq);
				if (ret < 0)
					return ret;
				res->evals++;
				sens[i] = fabs(cq - c_best) / h;
				smax = fmax(smax, sens[i]);
			}
			for (int i = 0; i < n && smax > 0; i++) {
				double ti = exp(-c * pow(k[i], 1 / D));
				double tn =
					ti * smax / fmax(sens[i], 1e-12 * smax);
				tn = fmin(tn, 1.0);
				k[i] = pow(fmax(0, -log(tn) / c), D);
			}
			t0a = c_best > 0 ? c_best : t0a;
			ka = 0;
			memcpy(cur, best, sizeof(double) * (size_t)n);
			c_cur = c_best;
			since_reanneal = 0;
			res->reanneals++;
		}
	}
	memcpy(p, best, sizeof(double) * (size_t)n);
	res->cost = c_best;
	return 0;
}
