/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "core/clock.h"
#include "log.h"

#include <jansson.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static enum glint_log_mode log_mode = GLINT_LOG_HUMAN;
static int verbosity;

void glint_log_set_verbosity(int level)
{
	verbosity = level;
}

int glint_log_get_verbosity(void)
{
	return log_mode == GLINT_LOG_QUIET ? -1 : verbosity;
}

void glint_log_set_mode(enum glint_log_mode mode)
{
	log_mode = mode;
}

enum glint_log_mode glint_log_get_mode(void)
{
	return log_mode;
}

static void log_v(const char *level, const char *fmt, va_list ap)
	GLINT_PRINTF(2, 0);

/* Wall-clock time as RFC 3339 UTC with milliseconds. */
static void utc_now(char *buf, size_t n)
{
	struct timespec ts;
	struct tm tm;

	clock_gettime(CLOCK_REALTIME, &ts);
	gmtime_r(&ts.tv_sec, &tm);
	size_t k = strftime(buf, n, "%Y-%m-%dT%H:%M:%S", &tm);
	snprintf(buf + k, n - k, ".%03ldZ", ts.tv_nsec / 1000000);
}

/*
 * Is stderr the systemd journal?  systemd sets JOURNAL_STREAM to the
 * "device:inode" of the stream it connects a service's output to
 * (systemd.exec(5)); then each line's priority goes in front of it as
 * "<N>", which journald reads (sd-daemon(3)).  Checked once.
 */
static int to_journal(void)
{
	static int known = -1;

	if (known < 0) {
		const char *js = getenv("JOURNAL_STREAM");
		unsigned long long dev, ino;
		struct stat st;
		known = js && sscanf(js, "%llu:%llu", &dev, &ino) == 2 &&
			fstat(STDERR_FILENO, &st) == 0 &&
			(unsigned long long)st.st_dev == dev &&
			(unsigned long long)st.st_ino == ino;
	}
	return known;
}

/* The syslog priority of a level: err 3, warning 4, info 6, debug 7. */
static int priority(const char *level)
{
	return level[0] == 'e'	 ? 3
	       : level[0] == 'w' ? 4
	       : level[0] == 'd' ? 7
				 : 6;
}

static void log_v(const char *level, const char *fmt, va_list ap)
{
	char msg[2048], now[40], prio[8] = "";

	vsnprintf(msg, sizeof(msg), fmt, ap);
	if (to_journal())
		snprintf(prio, sizeof(prio), "<%d>", priority(level));
	if (log_mode == GLINT_LOG_JSON) {
		utc_now(now, sizeof(now));
		json_t *o = json_pack("{s:s,s:s,s:s}", "time", now, "level",
				      level, "msg", msg);
		char *s = json_dumps(o, JSON_COMPACT);
		fprintf(stderr, "%s%s\n", prio, s);
		free(s);
		json_decref(o);
	} else {
		fprintf(stderr, "%sglint: %s%s\n", prio,
			level[0] == 'e'	  ? "error: "
			: level[0] == 'w' ? "warning: "
			: level[0] == 'd' ? "debug: "
					  : "",
			msg);
	}
}

void glint_log_info(const char *fmt, ...)
{
	va_list ap;

	if (glint_log_get_verbosity() < 0)
		return;
	va_start(ap, fmt);
	log_v("info", fmt, ap);
	va_end(ap);
}

void glint_log_debug(const char *fmt, ...)
{
	va_list ap;

	if (glint_log_get_verbosity() < 1)
		return;
	va_start(ap, fmt);
	log_v("debug", fmt, ap);
	va_end(ap);
}

void glint_log_warn(const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	log_v("warning", fmt, ap);
	va_end(ap);
}

void glint_log_error(const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	log_v("error", fmt, ap);
	va_end(ap);
}

static void progress_draw(struct glint_progress *p, long done)
{
	double t = glint_clock_monotonic() - p->t0;
	double frac = p->total > 0 ? (double)done / (double)p->total : 1;
	int bar = (int)(frac * 30);
	char b[31];

	for (int i = 0; i < 30; i++)
		b[i] = i < bar ? '#' : '.';
	b[30] = '\0';
	double eta = frac > 0.01 ? t / frac - t : 0;
	fprintf(stderr, "\r%-10s [%s] %5.1f%%  %5.1fs  eta %5.1fs ", p->label,
		b, 100 * frac, t, eta);
	fflush(stderr);
}

void glint_progress_start(struct glint_progress *p, const char *label,
			  long total)
{
	p->label = label;
	p->total = total;
	atomic_init(&p->done, 0);
	atomic_init(&p->drawing, 0);
	p->t0 = glint_clock_monotonic();
	p->last_draw = 0;
	p->enabled = log_mode == GLINT_LOG_HUMAN && isatty(STDERR_FILENO);
}

void glint_progress_add(struct glint_progress *p, long n)
{
	long done = atomic_fetch_add(&p->done, n) + n;

	if (!p->enabled)
		return;
	/* One thread draws at a time, at most ten times a second. */
	if (atomic_exchange(&p->drawing, 1))
		return;
	double t = glint_clock_monotonic();
	if (t - p->last_draw > 0.1 || done == p->total) {
		p->last_draw = t;
		progress_draw(p, done);
	}
	atomic_store(&p->drawing, 0);
}

void glint_progress_finish(struct glint_progress *p)
{
	if (!p->enabled)
		return;
	fprintf(stderr, "\r%*s\r", 72, "");
	fflush(stderr);
}

/* The length of the valid UTF-8 sequence at p that is not a C1 control
 * (U+0080..U+009F), or 0. */
static int utf8_ok(const unsigned char *p)
{
	int len = p[0] >= 0xf0 && p[0] <= 0xf4	 ? 4
		  : p[0] >= 0xe0 && p[0] <= 0xef ? 3
		  : p[0] >= 0xc2 && p[0] <= 0xdf ? 2
						 : 0;
	for (int k = 1; k < len; k++)
		if ((p[k] & 0xc0) != 0x80)
			return 0;
	if (len == 2 && p[0] == 0xc2 && p[1] < 0xa0)
		return 0; /* C1 */
	if (len == 3 &&
	    ((p[0] == 0xe0 && p[1] < 0xa0) || (p[0] == 0xed && p[1] >= 0xa0)))
		return 0; /* overlong, surrogate */
	if (len == 4 &&
	    ((p[0] == 0xf0 && p[1] < 0x90) || (p[0] == 0xf4 && p[1] >= 0x90)))
		return 0; /* overlong, beyond U+10FFFF */
	return len;
}

const char *glint_text_printable(const char *in, char *out, size_t n)
{
	const unsigned char *p = (const unsigned char *)in;
	size_t o = 0;

	if (!n)
		return out;
	while (*p) {
		int len = *p >= 0x20 && *p < 0x7f ? 1
			  : *p >= 0x80		  ? utf8_ok(p)
						  : 0;
		if (len) {
			if (o + (size_t)len >= n)
				break;
			memcpy(out + o, p, (size_t)len);
			o += (size_t)len;
			p += len;
			continue;
		}
		if (o + 4 >= n)
			break;
		snprintf(out + o, 5, "\\x%02x", *p);
		o += 4;
		p++;
	}
	out[o] = '\0';
	return out;
}
