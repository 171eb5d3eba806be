/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "core/clock.h"

#include <errno.h>
#include <time.h>

double glint_clock_monotonic(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double real_now(void *ctx)
{
	(void)ctx;
	return glint_clock_monotonic();
}

static void real_sleep_until(void *ctx, double t)
{
	struct timespec ts;
	ts.tv_sec = (time_t)t;
	ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
	(void)ctx;
	while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) ==
	       EINTR)
		;
}

const struct glint_clock glint_clock_real = { real_now, real_sleep_until,
					      NULL };

static double fake_now(void *ctx)
{
	return ((struct glint_fake_clock *)ctx)->t;
}

static void fake_sleep_until(void *ctx, double t)
{
	struct glint_fake_clock *fc = ctx;
	if (t > fc->t)
		fc->t = t;
}

struct glint_clock glint_clock_fake(struct glint_fake_clock *fc)
{
	struct glint_clock c = { fake_now, fake_sleep_until, fc };
	return c;
}

double glint_clock_now(const struct glint_clock *c)
{
	if (!c)
		c = &glint_clock_real;
	return c->now(c->ctx);
}

void glint_clock_sleep(const struct glint_clock *c, double s)
{
	if (!(s > 0))
		return;
	if (!c)
		c = &glint_clock_real;
	c->sleep_until(c->ctx, c->now(c->ctx) + s);
}
