/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_JSON_H
#define GLINT_CORE_JSON_H

/*
 * Validated reads from JSON documents parsed by jansson.  Every failure names
 * the file, the dotted key path, the value seen and what was expected, e.g.
 *   scene.json: camera.focal_length_mm = -5: expected a number in (0, 10000]
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (file, key path, expected type and range).
 * Threads: re-entrant.  Who frees: json_decref() what a loader returns;
 * strings out point into the document.
 */

#include <jansson.h>

/* The largest JSON document glint reads (rig, scene, session, job and
 * result files are kilobytes). */
#define GLINT_JSON_MAX_BYTES (16 * 1024 * 1024)

/* Parse a file; errors carry "file:line:column".  Only a regular file of
 * at most GLINT_JSON_MAX_BYTES is read (a FIFO or a device is refused by
 * name, core/path.h glint_open_regular), in blocks.  Caller
 * json_decref()s. */
int glint_json_load(const char *path, json_t **out);

/* The same from an open descriptor (`name` for messages), read in blocks
 * and refused past `max` bytes. */
int glint_json_load_fd(int fd, const char *name, size_t max, json_t **out);

/* glint_json_load() for a document whose absence or damage the caller
 * reports itself (a session's summary): the document or NULL, no error
 * left set. */
json_t *glint_json_read_quiet(const char *path);

/* Bounds for numbers: lo/hi inclusive unless the *_open flag is set. */
struct glint_range {
	double lo, hi;
	int lo_open, hi_open;
};

/*
 * Read obj[key] as a number inside range.  If the key is absent: when
 * `required` it is an error, else *out keeps its value.  `where` is the
 * dotted path of obj ("" for the root) and `file` the document's name.
 */
int glint_json_number(const char *file, const char *where, json_t *obj,
		      const char *key, int required, struct glint_range range,
		      double *out);
int glint_json_int(const char *file, const char *where, json_t *obj,
		   const char *key, int required, int lo, int hi, int *out);
/* An array of exactly n numbers, each inside range. */
int glint_json_numbers(const char *file, const char *where, json_t *obj,
		       const char *key, int required, int n,
		       struct glint_range range, double *out);
/* A string; *out points into obj and lives as long as obj. */
int glint_json_string(const char *file, const char *where, json_t *obj,
		      const char *key, int required, const char **out);
/* true or false into *out (1 or 0); absent: *out keeps its value. */
int glint_json_bool(const char *file, const char *where, json_t *obj,
		    const char *key, int *out);
/* An object; *out is borrowed (NULL if absent and not required). */
int glint_json_object(const char *file, const char *where, json_t *obj,
		      const char *key, int required, json_t **out);

/* Reject keys not in the NULL-terminated list `known` (catches typos). */
int glint_json_known_keys(const char *file, const char *where, json_t *obj,
			  const char *const *known);

/* A number for a document: JSON null when it is not finite (NaN,
 * infinity), which JSON cannot hold.  A new reference. */
json_t *glint_json_real_or_null(double v);

/* An array of n numbers (glint_json_real_or_null each).  A new
 * reference. */
json_t *glint_json_reals(const double *v, int n);

/* doc written to path whole or not at all (core/atomic_file.h), indented,
 * numbers to 9 digits, a newline at the end; doc's reference is taken
 * (decref'd) either way. */
int glint_json_write_file(const char *path, json_t *doc);

#endif
