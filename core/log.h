/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_LOG_H
#define GLINT_CORE_LOG_H

#include <stddef.h>

/*
 * Logs and progress on stderr.  Human mode: plain lines, and a live progress
 * bar only when stderr is a terminal.  JSON mode: one JSON object per line
 * ({"time": RFC 3339 UTC, "level":.., "msg":..}), no progress bar; for
 * scripts.  Quiet: errors only.  When stderr is the systemd journal
 * (JOURNAL_STREAM names it), every line starts with its syslog priority,
 * "<3>" error, "<4>" warning, "<6>" info, "<7>" debug, for journald.
 *
 * Errors: none (a log line that cannot be written is dropped).  Threads:
 * the configuration is set once at start.  Who frees: nothing.
 */

#include "error.h"

#include <stdatomic.h>

enum glint_log_mode {
	GLINT_LOG_HUMAN,
	GLINT_LOG_JSON,
	GLINT_LOG_QUIET,
};

void glint_log_set_mode(enum glint_log_mode mode);
enum glint_log_mode glint_log_get_mode(void);

/* -1: errors and warnings only (as GLINT_LOG_QUIET, in either format);
 * 0: info too (the default); 1: debug messages too (-v). */
void glint_log_set_verbosity(int level);
int glint_log_get_verbosity(void);

void glint_log_info(const char *fmt, ...) GLINT_PRINTF(1, 2);
void glint_log_error(const char *fmt, ...) GLINT_PRINTF(1, 2);
/* Only with -v: what a user debugging a run wants to see. */
void glint_log_debug(const char *fmt, ...) GLINT_PRINTF(1, 2);
/* Shown even when quiet: something the user should act on. */
void glint_log_warn(const char *fmt, ...) GLINT_PRINTF(1, 2);

/* `in` made safe for a terminal, into out (n bytes, always terminated):
 * control characters (C0, DEL, C1) and bytes that are not valid UTF-8
 * become \xNN, so that text from a file another user wrote (a job's
 * session or error) cannot move the cursor, retitle or recolour the
 * reader's terminal.  Returns out. */
const char *glint_text_printable(const char *in, char *out, size_t n);

struct glint_progress {
	const char *label;
	long total;
	atomic_long done;
	atomic_int drawing;
	double t0;
	double last_draw;
	int enabled;
};

/* Start a progress indicator of `total` units (drawn only on a TTY). */
void glint_progress_start(struct glint_progress *p, const char *label,
			  long total);
/* Add n finished units; safe from any thread. */
void glint_progress_add(struct glint_progress *p, long n);
/* Clear the bar. */
void glint_progress_finish(struct glint_progress *p);

#endif
