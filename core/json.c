/* SPDX-License-Identifier: MIT */
#include "json.h"
#include "atomic_file.h"
#include "suggest.h"
#include "path.h"

#include "error.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <unistd.h>
#include <stdio.h>
#include <string.h>

int glint_json_load_fd(int fd, const char *name, size_t max, json_t **out)
{
	json_error_t err;
	size_t cap = 4096, n = 0;
	char *buf = malloc(cap);

	*out = NULL;
	if (!buf)
		return glint_error_set(ENOMEM, "%s: out of memory", name);
	/* in blocks, never past max (the size fstat gave may grow) */
	for (;;) {
		if (n == cap) {
			char *nb = cap > max ? NULL : realloc(buf, 2 * cap);
			if (!nb) {
				free(buf);
				return cap > max ? glint_error_set(
							   EFBIG,
							   "%s: more than %zu "
							   "bytes: expected a "
							   "JSON document of "
							   "at most that",
							   name, max)
						 : glint_error_set(
							   ENOMEM,
							   "%s: out of memory",
							   name);
			}
			buf = nb;
			cap *= 2;
		}
		ssize_t r = read(fd, buf + n, cap - n);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0) {
			int e = errno;
			free(buf);
			return glint_error_set(e, "%s: %s", name, strerror(e));
		}
		if (r == 0)
			break;
		n += (size_t)r;
	}
	if (n > max) {
		free(buf);
		return glint_error_set(EFBIG,
				       "%s: %zu bytes: expected a JSON "
				       "document of at most %zu",
				       name, n, max);
	}
	*out = json_loadb(buf, n, JSON_REJECT_DUPLICATES, &err);
	free(buf);
	if (!*out)
		return glint_error_set(EINVAL, "%s:%d:%d: %s", name, err.line,
				       err.column, err.text);
	if (!json_is_object(*out)) {
		json_decref(*out);
		*out = NULL;
		return glint_error_set(
			EINVAL, "%s: expected a JSON object at the top", name);
	}
	return 0;
}

int glint_json_load(const char *path, json_t **out)
{
	long long size = 0;
	int fd = glint_open_regular(path, &size);

	*out = NULL;
	if (fd < 0)
		return fd;
	int ret = size > GLINT_JSON_MAX_BYTES
			  ? glint_error_set(EFBIG,
					    "%s: %lld bytes: expected a JSON "
					    "document of at most %d",
					    path, size, GLINT_JSON_MAX_BYTES)
			  : glint_json_load_fd(fd, path, GLINT_JSON_MAX_BYTES,
					       out);
	close(fd);
	return ret;
}

json_t *glint_json_read_quiet(const char *path)
{
	json_t *doc = NULL;
	if (glint_json_load(path, &doc) < 0)
		glint_error_clear();
	return doc;
}

static void key_path(char *buf, size_t n, const char *where, const char *key)
{
	if (where && where[0])
		snprintf(buf, n, "%s.%s", where, key);
	else
		snprintf(buf, n, "%s", key);
}

int glint_json_bool(const char *file, const char *where, json_t *obj,
		    const char *key, int *out)
{
	json_t *v = json_object_get(obj, key);
	char kp[256];

	if (!v)
		return 0;
	if (!json_is_boolean(v)) {
		key_path(kp, sizeof(kp), where, key);
		return glint_error_set(EINVAL, "%s: %s: expected true or false",
				       file, kp);
	}
	*out = json_is_true(v);
	return 0;
}

static void range_text(char *buf, size_t n, struct glint_range r)
{
	if (isinf(r.hi) && isinf(r.lo))
		snprintf(buf, n, "finite");
	else if (isinf(r.hi))
		snprintf(buf, n, "a number %s %g",
			 r.lo_open ? ">" : ">=", r.lo);
	else
		snprintf(buf, n, "a number in %c%g, %g%c",
			 r.lo_open ? '(' : '[', r.lo, r.hi,
			 r.hi_open ? ')' : ']');
}

static int in_range(double v, struct glint_range r)
{
	if (!isfinite(v))
		return 0;
	if (r.lo_open ? !(v > r.lo) : !(v >= r.lo))
		return 0;
	return r.hi_open ? v < r.hi : v <= r.hi;
}

static int bad_value(const char *file, const char *kp, json_t *v,
		     const char *expected)
{
	char *s = v ? json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
	int ret = glint_error_set(EINVAL, "%s: %s = %s: expected %s", file, kp,
				  s ? s : "?", expected);
	free(s);
	return ret;
}

static int missing(const char *file, const char *kp, const char *expected)
{
	return glint_error_set(EINVAL, "%s: %s is missing: expected %s", file,
			       kp, expected);
}

int glint_json_number(const char *file, const char *where, json_t *obj,
		      const char *key, int required, struct glint_range range,
		      double *out)
{
	char kp[256], exp[96], r[80];
	json_t *v = json_object_get(obj, key);

	key_path(kp, sizeof(kp), where, key);
	range_text(r, sizeof(r), range);
	snprintf(exp, sizeof(exp), "%s",
		 strcmp(r, "finite") ? r : "a finite number");
	if (!v)
		return required ? missing(file, kp, exp) : 0;
	if (!json_is_number(v) || !in_range(json_number_value(v), range))
		return bad_value(file, kp, v, exp);
	*out = json_number_value(v);
	return 0;
}

int glint_json_int(const char *file, const char *where, json_t *obj,
		   const char *key, int required, int lo, int hi, int *out)
{
	char kp[256], exp[96];
	json_t *v = json_object_get(obj, key);

	key_path(kp, sizeof(kp), where, key);
	snprintf(exp, sizeof(exp), "an integer in [%d, %d]", lo, hi);
	if (!v)
		return required ? missing(file, kp, exp) : 0;
	if (!json_is_integer(v) || json_integer_value(v) < lo ||
	    json_integer_value(v) > hi)
		return bad_value(file, kp, v, exp);
	*out = (int)json_integer_value(v);
	return 0;
}

int glint_json_numbers(const char *file, const char *where, json_t *obj,
		       const char *key, int required, int n,
		       struct glint_range range, double *out)
{
	char kp[256], exp[160], r[96];
	json_t *v = json_object_get(obj, key);

	key_path(kp, sizeof(kp), where, key);
	range_text(r, sizeof(r), range);
	if (!strcmp(r, "finite"))
		snprintf(exp, sizeof(exp), "an array of %d finite numbers", n);
	else
		snprintf(exp, sizeof(exp), "an array of %d numbers, each %s", n,
			 r);
	if (!v)
		return required ? missing(file, kp, exp) : 0;
	if (!json_is_array(v) || (int)json_array_size(v) != n)
		return bad_value(file, kp, v, exp);
	for (int i = 0; i < n; i++) {
		json_t *e = json_array_get(v, (size_t)i);
		if (!json_is_number(e) ||
		    !in_range(json_number_value(e), range))
			return bad_value(file, kp, v, exp);
	}
	for (int i = 0; i < n; i++)
		out[i] = json_number_value(json_array_get(v, (size_t)i));
	return 0;
}

int glint_json_string(const char *file, const char *where, json_t *obj,
		      const char *key, int required, const char **out)
{
	char kp[256];
	json_t *v = json_object_get(obj, key);

	key_path(kp, sizeof(kp), where, key);
	if (!v)
		return required ? missing(file, kp, "a string") : 0;
	if (!json_is_string(v) || json_string_length(v) == 0)
		return bad_value(file, kp, v, "a non-empty string");
	*out = json_string_value(v);
	return 0;
}

int glint_json_object(const char *file, const char *where, json_t *obj,
		      const char *key, int required, json_t **out)
{
	char kp[256];
	json_t *v = json_object_get(obj, key);

	key_path(kp, sizeof(kp), where, key);
	*out = NULL;
	if (!v)
		return required ? missing(file, kp, "an object") : 0;
	if (!json_is_object(v))
		return bad_value(file, kp, v, "an object");
	*out = v;
	return 0;
}

int glint_json_known_keys(const char *file, const char *where, json_t *obj,
			  const char *const *known)
{
	const char *key;
	json_t *v;

	json_object_foreach(obj, key, v)
	{
		int ok = 0;
		for (const char *const *k = known; *k; k++)
			ok |= !strcmp(*k, key);
		if (!ok) {
			char kp[256], list[512] = "";
			key_path(kp, sizeof(kp), where, key);
			for (const char *const *k = known; *k; k++) {
				strncat(list, *k,
					sizeof(list) - strlen(list) - 1);
				if (k[1])
					strncat(list, ", ",
						sizeof(list) - strlen(list) -
							1);
			}
			const char *hint = glint_suggest_hint(key, known);
			return glint_error_set(EINVAL,
					       "%s: %s: unknown key%s: "
					       "expected one of %s",
					       file, kp, hint, list);
		}
	}
	return 0;
}

json_t *glint_json_real_or_null(double v)
{
	return isfinite(v) ? json_real(v) : json_null();
}

json_t *glint_json_reals(const double *v, int n)
{
	json_t *a = json_array();
	for (int i = 0; i < n; i++)
		json_array_append_new(a, glint_json_real_or_null(v[i]));
	return a;
}

int glint_json_write_file(const char *path, json_t *doc)
{
	char *text =
		doc ? json_dumps(doc, JSON_INDENT(2) | JSON_REAL_PRECISION(9))
		    : NULL;
	json_decref(doc);
	if (!text)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	size_t n = strlen(text);
	text[n] = '\n'; /* over the terminator: n + 1 bytes written */
	int ret = glint_atomic_write_file(path, text, n + 1);
	free(text);
	return ret;
}
