/* SPDX-License-Identifier: MIT */
/*
 * The board over libgpiod 1.6 (the v1 API: Debian 12 packages no 2.x).
 * Every libgpiod call is in this file, so a 2.x port touches only it.
 * Lines are requested with a consumer name ("glint rig"); active-low lines
 * are requested with GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW, so values here are
 * logical, and a rising edge event is a logical 0 -> 1.
 */
#define _POSIX_C_SOURCE 200809L
#include "board.h"

#include <gpiod.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_CHIPS GLINT_ROLE_COUNT

struct gpiod_board {
	struct gpiod_chip *chips[MAX_CHIPS];
	char chip_names[MAX_CHIPS][64];
	int nchips;
	struct gpiod_line *lines[GLINT_ROLE_COUNT];
	int requested[GLINT_ROLE_COUNT];
	struct glint_board_cfg cfg;
};

static void describe(const struct glint_board_cfg *c, enum glint_role r,
		     char *buf, size_t n)
{
	const struct glint_line_cfg *l = &c->lines[r];
	if (l->name[0])
		snprintf(buf, n, "board.lines.%s (chip %s, line \"%s\")",
			 glint_role_name(r), l->chip, l->name);
	else
		snprintf(buf, n, "board.lines.%s (chip %s, line %d)",
			 glint_role_name(r), l->chip, l->offset);
}

static void gpiod_close_board(void *priv)
{
	struct gpiod_board *b = priv;
	if (!b)
		return;
	for (int r = 0; r < GLINT_ROLE_COUNT; r++)
		if (b->requested[r])
			gpiod_line_release(b->lines[r]);
	for (int i = 0; i < b->nchips; i++)
		gpiod_chip_close(b->chips[i]);
	free(b);
}

static struct gpiod_chip *chip_for(struct gpiod_board *b, const char *name)
{
	for (int i = 0; i < b->nchips; i++)
		if (!strcmp(b->chip_names[i], name))
			return b->chips[i];
	struct gpiod_chip *c = gpiod_chip_open_lookup(name);
	if (!c || b->nchips == MAX_CHIPS)
		return c;
	b->chips[b->nchips] = c;
	snprintf(b->chip_names[b->nchips], sizeof(b->chip_names[0]), "%s",
		 name);
	b->nchips++;
	return c;
}

/* Find every line and check it is free before requesting any: a bad
 * configuration touches no output. */
static int find_lines(struct gpiod_board *b)
{
	const struct glint_board_cfg *c = &b->cfg;
	char what[200];

	for (int r = 0; r < GLINT_ROLE_COUNT; r++) {
		const struct glint_line_cfg *l = &c->lines[r];
		if (!l->used)
			continue;
		describe(c, r, what, sizeof(what));
		errno = 0;
		struct gpiod_chip *chip = chip_for(b, l->chip);
		if (!chip)
			return glint_error_set(
				ENODEV,
				"%s: no such GPIO chip: %s "
				"(gpiodetect lists them)",
				what, strerror(errno ? errno : ENODEV));
		unsigned n = gpiod_chip_num_lines(chip);
		if (l->name[0]) {
			b->lines[r] = gpiod_chip_find_line(chip, l->name);
			if (!b->lines[r])
				return glint_error_set(ENOENT,
						       "%s: chip %s (%s) has "
						       "no line of that name "
						       "(gpioinfo lists them)",
						       what,
						       gpiod_chip_name(chip),
						       gpiod_chip_label(chip));
		} else {
			if (l->offset < 0 || (unsigned)l->offset >= n)
				return glint_error_set(
					ERANGE,
					"%s: out of range: chip "
					"%s has lines 0..%u",
					what, gpiod_chip_name(chip), n - 1);
			b->lines[r] =
				gpiod_chip_get_line(chip, (unsigned)l->offset);
			if (!b->lines[r])
				return glint_error_set(errno, "%s: %s", what,
						       strerror(errno));
		}
		if (gpiod_line_is_used(b->lines[r])) {
			const char *who = gpiod_line_consumer(b->lines[r]);
			return glint_error_set(EBUSY,
					       "%s: busy: in use by \"%s\"",
					       what, who ? who : "the kernel");
		}
	}
	return 0;
}

static int request(struct gpiod_board *b, enum glint_role r,
		   const char *consumer)
{
	const struct glint_line_cfg *l = &b->cfg.lines[r];
	int flags = l->active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
	struct gpiod_line *line = b->lines[r];
	int ret;

	if (r == GLINT_ROLE_BUTTON)
		ret = gpiod_line_request_both_edges_events_flags(line, consumer,
								 flags);
	else if (glint_role_is_input(r))
		ret = gpiod_line_request_input_flags(line, consumer, flags);
	else
		ret = gpiod_line_request_output_flags(line, consumer, flags, 0);
	if (ret < 0) {
		int e = errno;
		char what[200];
		describe(&b->cfg, r, what, sizeof(what));
		if (e == EBUSY && gpiod_line_update(line) == 0 &&
		    gpiod_line_consumer(line))
			return glint_error_set(EBUSY,
					       "%s: busy: in use by \"%s\"",
					       what, gpiod_line_consumer(line));
		return glint_error_set(e, "%s: cannot request: %s", what,
				       strerror(e));
	}
	b->requested[r] = 1;
	return 0;
}

static int gpiod_open_board(const struct glint_board_cfg *cfg,
			    const char *consumer, void **priv)
{
	struct gpiod_board *b = calloc(1, sizeof(*b));
	int ret;

	*priv = NULL;
	if (!b)
		return glint_error_set(ENOMEM, "out of memory");
	b->cfg = *cfg;
	ret = find_lines(b);
	for (int r = 0; r < GLINT_ROLE_COUNT && !ret; r++)
		if (cfg->lines[r].used)
			ret = request(b, r, consumer);
	if (ret < 0) {
		gpiod_close_board(b);
		return ret;
	}
	*priv = b;
	return 0;
}

static int line_error(struct gpiod_board *b, enum glint_role r, const char *op)
{
	int e = errno;
	char what[200];
	describe(&b->cfg, r, what, sizeof(what));
	if (e == ENODEV)
		return glint_error_set(e, "%s: the GPIO chip disappeared",
				       what);
	return glint_error_set(e, "%s: cannot %s: %s", what, op, strerror(e));
}

static int gpiod_set(void *priv, enum glint_role r, int v)
{
	struct gpiod_board *b = priv;
	if (!b->requested[r])
		return 0;
	if (gpiod_line_set_value(b->lines[r], v) < 0)
		return line_error(b, r, "set it");
	return 0;
}

static int gpiod_get(void *priv, enum glint_role r, int *v)
{
	struct gpiod_board *b = priv;
	if (!b->requested[r])
		return glint_error_set(EINVAL, "board.lines.%s: not configured",
				       glint_role_name(r));
	int x = gpiod_line_get_value(b->lines[r]);
	if (x < 0)
		return line_error(b, r, "read it");
	*v = x;
	return 0;
}

static int gpiod_wait_edge(void *priv, enum glint_role r, double timeout_s,
			   struct glint_edge *e)
{
	struct gpiod_board *b = priv;
	struct gpiod_line_event ev;

	if (r != GLINT_ROLE_BUTTON || !b->requested[r])
		return glint_error_set(EINVAL,
				       "board.lines.%s: not an edge input",
				       glint_role_name(r));
	if (timeout_s < 0)
		timeout_s = 0;
	struct timespec ts = { (time_t)timeout_s,
			       (long)((timeout_s - floor(timeout_s)) * 1e9) };
	int ret = gpiod_line_event_wait(b->lines[r], &ts);
	if (ret < 0 && errno == EINTR)
		return 0; /* a signal: the caller looks at its cancel flag */
	if (ret < 0)
		return line_error(b, r, "wait for an edge");
	if (ret == 0) {
		/* The kernel waited on the real clock; an injected one (a
		 * test's) is moved by the same timeout, so that the board's
		 * deadlines on it pass. */
		if (b->cfg.clock && b->cfg.clock != &glint_clock_real)
			glint_clock_sleep(b->cfg.clock, timeout_s);
		return 0;
	}
	if (gpiod_line_event_read(b->lines[r], &ev) < 0)
		return line_error(b, r, "read its edge");
	e->value = ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
	e->t = (double)ev.ts.tv_sec + 1e-9 * (double)ev.ts.tv_nsec;
	return 1;
}

static int gpiod_chip_of(void *priv, enum glint_role r, char *name, size_t nn,
			 char *label, size_t nl)
{
	struct gpiod_board *b = priv;
	struct gpiod_chip *c =
		b->lines[r] ? gpiod_line_get_chip(b->lines[r]) : NULL;

	if (!c)
		return -ENOENT;
	snprintf(name, nn, "%s", gpiod_chip_name(c));
	snprintf(label, nl, "%s", gpiod_chip_label(c));
	return 0;
}

static void gpiod_locate(void *priv, enum glint_role r, char *buf, size_t n)
{
	struct gpiod_board *b = priv;
	struct gpiod_line *l = b->lines[r];
	struct gpiod_chip *c = l ? gpiod_line_get_chip(l) : NULL;
	const char *name = l ? gpiod_line_name(l) : NULL;

	if (!c) {
		snprintf(buf, n, "not found");
		return;
	}
	snprintf(buf, n, "%s (%s) line %u%s%s%s", gpiod_chip_name(c),
		 gpiod_chip_label(c), gpiod_line_offset(l), name ? " \"" : "",
		 name ? name : "", name ? "\"" : "");
}

const struct glint_board_ops glint_board_gpiod_ops = {
	.name = "gpiod",
	.open = gpiod_open_board,
	.close = gpiod_close_board,
	.set = gpiod_set,
	.get = gpiod_get,
	.wait_edge = gpiod_wait_edge,
	.locate = gpiod_locate,
	.chip = gpiod_chip_of,
};
