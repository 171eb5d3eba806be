/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_TEST_H
#define GLINT_TESTS_TEST_H

/*
 * Minimal test helpers: each CHECK prints the numbers it saw and counts a
 * failure; a test program returns 1 if any check failed, 77 to skip.
 */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static int test_failures;
static int test_checks;

#define CHECK(cond, ...)                                                       \
	do {                                                                   \
		test_checks++;                                                 \
		if (!(cond)) {                                                 \
			fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, \
				__LINE__, #cond);                              \
			fprintf(stderr, __VA_ARGS__);                          \
			fputc('\n', stderr);                                   \
			test_failures++;                                       \
		}                                                              \
	} while (0)

#define CHECK_NEAR(a, b, tol, what)                                            \
	CHECK(fabs((double)(a) - (double)(b)) <= (tol),                        \
	      "%s: got %.9g, expected %.9g +- %.3g", what, (double)(a),        \
	      (double)(b), (double)(tol))

/* An error message must contain each of the given fragments. */
#define CHECK_MSG(msg, frag)                                                   \
	CHECK(strstr((msg), (frag)) != NULL, "message '%s' lacks '%s'", (msg), \
	      (frag))

/* Seconds of wall time since an arbitrary start, for RUN's report. */
static inline double test_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Each test's verdict and wall time: the unit suite is meant to stay fast,
 * and CI runs it under qemu-user and the sanitizers too. */
#define RUN_REPORT(name, before, t0)                                           \
	fprintf(stderr, "%s %s (%.2f s)\n",                                    \
		test_failures == (before) ? "ok  " : "FAIL", name,             \
		test_now() - (t0))

#define RUN(fn)                                                                \
	do {                                                                   \
		int before = test_failures;                                    \
		double t0 = test_now();                                        \
		fn();                                                          \
		RUN_REPORT(#fn, before, t0);                                   \
	} while (0)

#define RUN_ARG(fn, arg)                                                       \
	do {                                                                   \
		int before = test_failures;                                    \
		double t0 = test_now();                                        \
		fn(arg);                                                       \
		RUN_REPORT(#fn, before, t0);                                   \
	} while (0)

static inline int test_result(void)
{
	fprintf(stderr, "%d checks, %d failed\n", test_checks, test_failures);
	return test_failures ? 1 : 0;
}

/* Path of a file in ../shared/data, or NULL (and a note) if absent. */
static inline const char *shared_file(const char *rel)
{
	static char buf[4096];
	snprintf(buf, sizeof(buf), "%s/%s", GLINT_SHARED_DATA, rel);
	if (access(buf, R_OK) != 0)
		return NULL;
	return buf;
}

/* Removes a scratch directory the test made (mkdtemp), with its files. */
static inline void test_remove_dir(const char *dir)
{
	char cmd[600];
	snprintf(cmd, sizeof(cmd), "rm -rf '%s'", dir);
	if (system(cmd) != 0)
		fprintf(stderr, "could not remove %s\n", dir);
}

static char test_tmpdir_path[256];
static pid_t test_tmpdir_owner;

/* At the test's exit: its scratch directory goes, unless
 * GLINT_TEST_KEEP is set (to look at what a failed test wrote); a child
 * the test forked leaves it to the test. */
static inline void test_tmpdir_remove(void)
{
	if (test_tmpdir_path[0] && getpid() == test_tmpdir_owner &&
	    !getenv("GLINT_TEST_KEEP"))
		test_remove_dir(test_tmpdir_path);
}

/* A scratch directory for the test's files, removed when it exits. */
static inline const char *test_tmpdir(void)
{
	if (!test_tmpdir_path[0]) {
		snprintf(test_tmpdir_path, sizeof(test_tmpdir_path),
			 "%s/glint-test-XXXXXX",
			 getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
		if (!mkdtemp(test_tmpdir_path)) {
			perror("mkdtemp");
			exit(1);
		}
		test_tmpdir_owner = getpid();
		atexit(test_tmpdir_remove);
	}
	return test_tmpdir_path;
}

static inline const char *tmp_path(const char *name)
{
	static char buf[8][512];
	static int k;
	k = (k + 1) % 8;
	snprintf(buf[k], sizeof(buf[k]), "%s/%s", test_tmpdir(), name);
	return buf[k];
}

#endif
