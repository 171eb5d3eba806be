/* SPDX-License-Identifier: MIT */
/*
 * Adaptive simulated annealing (fit/optim/anneal.c): the global minimum of a
 * multimodal function (2-D Rastrigin: 120 local minima in the box) from
 * random starts, bounds respected, runs repeatable from a seed, a
 * badly-scaled parameter handled by re-annealing.
 */
#include "test.h"

#include "fit/optim/anneal.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static int evals;

static int rastrigin(void *ctx, const double *p, double *c)
{
	(void)ctx;
	evals++;
	*c = 20;
	for (int i = 0; i < 2; i++)
		*c += p[i] * p[i] - 10 * cos(2 * M_PI * p[i]);
	return 0;
}

/* One steep and one nearly flat direction (sensitivities 1e4 apart). */
static int skewed(void *ctx, const double *p, double *c)
{
	(void)ctx;
	*c = 1e4 * (p[0] - 0.3) * (p[0] - 0.3) + (p[1] - 0.7) * (p[1] - 0.7);
	return 0;
}

static void test_rastrigin(void)
{
	double lo[2] = { -5.12, -5.12 }, hi[2] = { 5.12, 5.12 };
	int found = 0, outside = 0, runs = 40;
	long total = 0;
	for (int s = 1; s <= runs; s++) {
		struct glint_anneal_opts o;
		struct glint_anneal_result r;
		glint_anneal_default_opts(&o);
		o.seed = (uint64_t)s;
		o.max_evals = 4000;
		o.stall_evals = 2000;
		double p[2] = { -5.12 + 10.24 * ((s * 37) % 100) / 100.0,
				5.12 - 10.24 * ((s * 61) % 100) / 100.0 };
		evals = 0;
		CHECK(glint_anneal(2, lo, hi, rastrigin, NULL, &o, p, &r) == 0,
		      "anneal failed");
		total += evals;
		found += fabs(p[0]) < 0.05 && fabs(p[1]) < 0.05;
		outside += p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] ||
			   p[1] > hi[1];
	}
	fprintf(stderr,
		"  Rastrigin 2-D: global minimum from %d of %d starts, %ld "
		"evaluations each\n",
		found, runs, total / runs);
	CHECK(found >= runs * 9 / 10, "global minimum in %d of %d", found,
	      runs);
	CHECK(outside == 0, "%d results outside the bounds", outside);
}

static void test_repeatable(void)
{
	double lo[2] = { -5.12, -5.12 }, hi[2] = { 5.12, 5.12 };
	double a[2] = { 3, -4 }, b[2] = { 3, -4 }, c[2] = { 3, -4 };
	struct glint_anneal_opts o;
	struct glint_anneal_result r;
	glint_anneal_default_opts(&o);
	o.max_evals = 300;
	o.seed = 7;
	glint_anneal(2, lo, hi, rastrigin, NULL, &o, a, &r);
	glint_anneal(2, lo, hi, rastrigin, NULL, &o, b, &r);
	o.seed = 8;
	glint_anneal(2, lo, hi, rastrigin, NULL, &o, c, &r);
	CHECK(a[0] == b[0] && a[1] == b[1], "same seed, same run");
	CHECK(a[0] != c[0] || a[1] != c[1], "another seed, another run");
}

static void test_reanneal(void)
{
	double lo[2] = { 0, 0 }, hi[2] = { 1, 1 }, p[2] = { 0.9, 0.1 };
	struct glint_anneal_opts o;
	struct glint_anneal_result r;
	glint_anneal_default_opts(&o);
	o.max_evals = 3000;
	CHECK(glint_anneal(2, lo, hi, skewed, NULL, &o, p, &r) == 0, "failed");
	fprintf(stderr, "  skewed: (%.4f, %.4f) after %d re-anneals\n", p[0],
		p[1], r.reanneals);
	CHECK(r.reanneals > 0, "no re-annealing happened");
	CHECK_NEAR(p[0], 0.3, 0.01, "steep parameter");
	CHECK_NEAR(p[1], 0.7, 0.1, "flat parameter");
}

int main(void)
{
	RUN(test_rastrigin);
	RUN(test_repeatable);
	RUN(test_reanneal);
	return test_result();
}
