/* SPDX-License-Identifier: MIT */
#include "error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define GLINT_ERROR_MAX 1024

static _Thread_local char error_buf[GLINT_ERROR_MAX];

int glint_error_set(int code, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(error_buf, sizeof(error_buf), fmt, ap);
	va_end(ap);
	return code > 0 ? -code : code;
}

int glint_error_prefix(int code, const char *fmt, ...)
{
	char prefix[GLINT_ERROR_MAX];
	char old[GLINT_ERROR_MAX];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(prefix, sizeof(prefix), fmt, ap);
	va_end(ap);
	memcpy(old, error_buf, sizeof(old));
	glint_text(error_buf, sizeof(error_buf), "%s: %s", prefix, old);
	return code > 0 ? -code : code;
}

char *glint_text(char *buf, size_t n, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	int len = vsnprintf(buf, n, fmt, ap);
	va_end(ap);
	if (len >= 0 && (size_t)len >= n && n > 4)
		memcpy(buf + n - 4, "...", 4);
	return buf;
}

const char *glint_error_msg(void)
{
	return error_buf;
}

void glint_error_clear(void)
{
	error_buf[0] = '\0';
}
