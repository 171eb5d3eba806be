/* SPDX-License-Identifier: MIT */
#ifndef GLINT_BENCH_BENCH_H
#define GLINT_BENCH_BENCH_H

/* Shared helpers of the benchmark programs: medians, peak memory. */

#include <stdlib.h>
#include <sys/resource.h>

static int bench_cmp(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Median of n values (sorts them). */
static inline double bench_median(double *v, int n)
{
	qsort(v, (size_t)n, sizeof(double), bench_cmp);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Peak resident memory of this process so far, MiB. */
static inline double bench_peak_mib(void)
{
	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	return ru.ru_maxrss / 1024.0;
}

#endif
