/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_ERROR_H
#define GLINT_CORE_ERROR_H

/*
 * Error reporting.  Library functions return 0 (or a count) on success and a
 * negative errno on failure; before returning an error they record one
 * human-readable message naming the file, the field or value seen and what
 * was expected.  The message lives in thread-local storage and stays valid
 * until the next glint_error_set() on the same thread.
 *
 * Errors: this is where they are kept.  Threads: the message is per
 * thread.  Who frees: nothing (the message is the thread's).
 */

#include <errno.h>
#include <stddef.h>

#if defined(__GNUC__)
#define GLINT_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define GLINT_PRINTF(a, b)
#endif

/* Record a message and return -code (code is a positive errno). */
int glint_error_set(int code, const char *fmt, ...) GLINT_PRINTF(2, 3);

/* Prefix the current message with "prefix: " (e.g. a file name). */
int glint_error_prefix(int code, const char *fmt, ...) GLINT_PRINTF(2, 3);

/*
 * Text for a message or a label into buf (n > 0): when it does not fit it is
 * cut and ends in "..." so a reader sees it was cut.  Not for paths, which
 * glint_path_*() refuse to cut.  Returns buf.
 */
char *glint_text(char *buf, size_t n, const char *fmt, ...) GLINT_PRINTF(3, 4);

/* The last message recorded on this thread ("" when none). */
const char *glint_error_msg(void);

/* Forget the last message. */
void glint_error_clear(void);

#endif
