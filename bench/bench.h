/* SPDX-License-Identifier: MIT */
#ifndef GLINT_BENCH_BENCH_H
#define GLINT_BENCH_BENCH_H

/* Shared helpers of the benchmark programs: arguments, medians, peak
 * memory. */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* -h or --help anywhere: print `usage` and exit 0, before any work (a
 * benchmark can run for minutes). */
static inline void bench_help(int argc, char **argv, const char *usage)
{
	for (int i = 1; i < argc; i++)
		if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
			printf("usage: %s\n", usage);
			exit(0);
		}
}

/* A whole number in [lo, hi] (lo >= 0), or -1. */
static inline int bench_count(const char *s, int lo, int hi)
{
	char *end;
	long v = strtol(s, &end, 10);
	return *s && !*end && v >= lo && v <= hi ? (int)v : -1;
}

/* An argument the program does not take: say so with the usage, exit 2. */
static inline _Noreturn void bench_refuse(const char *arg, const char *usage)
{
	fprintf(stderr, "%s: not an argument of this benchmark\nusage: %s\n",
		arg, usage);
	exit(2);
}

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
