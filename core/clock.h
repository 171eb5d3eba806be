/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_CLOCK_H
#define GLINT_CORE_CLOCK_H

/*
 * Time, injected.  Everything that waits or measures an interval (the
 * camera and its bracket, the board's settle times and relay pulses, the
 * simulated camera's frame times) takes a struct glint_clock, so that a
 * test can run hours of rig time in no time and a simulated frame's
 * exposure is the clock's, not the host's.
 *
 * Errors: none (the real clock's calls cannot fail on Linux).  NULL for a
 * clock means the real one.  Threads: glint_clock_real is safe from any
 * thread; a fake clock is not (one thread owns it).  Nothing to free.
 */

#ifdef __cplusplus
extern "C" {
#endif

/* Time source: seconds on a monotonic clock, and a sleep until then. */
struct glint_clock {
	double (*now)(void *ctx);
	void (*sleep_until)(void *ctx, double t);
	void *ctx;
};

/* The real clock (CLOCK_MONOTONIC, clock_nanosleep to an absolute time,
 * resumed after signals). */
extern const struct glint_clock glint_clock_real;

/* A fake clock for tests: time only moves when someone sleeps. */
struct glint_fake_clock {
	double t;
};
struct glint_clock glint_clock_fake(struct glint_fake_clock *fc);

/* CLOCK_MONOTONIC in seconds: the kernel's buffer timestamps and the log's
 * elapsed times (never a wall clock). */
double glint_clock_monotonic(void);

/* The clock's time (c NULL: the real clock). */
double glint_clock_now(const struct glint_clock *c);

/* Sleep s seconds on the clock (c NULL: the real clock); s <= 0 returns
 * at once. */
void glint_clock_sleep(const struct glint_clock *c, double s);

#ifdef __cplusplus
}
#endif

#endif
