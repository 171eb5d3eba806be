/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_ATOMIC_FILE_H
#define GLINT_CORE_ATOMIC_FILE_H

/*
 * Files that are either wholly old or wholly new after a power cut: write to
 * a temporary file beside the target, fsync it, rename it over the target,
 * fsync the directory.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected; the target is never left half written.  Threads:
 * re-entrant; one writer per file.  Who frees: commit or abort ends a
 * write.
 */

#include <stdio.h>

struct glint_atomic_file {
	char final_path[4096];
	char tmp_path[4096];
	FILE *fp; /* open for writing until commit/abort */
};

/* Create the temporary file for `path`; af->fp is ready for writing. */
int glint_atomic_open(struct glint_atomic_file *af, const char *path);

/* Flush, fsync, close, rename over the target, fsync the directory. */
int glint_atomic_commit(struct glint_atomic_file *af);

/* Close and remove the temporary file; the target is left untouched. */
void glint_atomic_abort(struct glint_atomic_file *af);

/*
 * For libraries that write a named file themselves: reserve a temporary
 * name next to `path` (the file exists, empty) in tmp (size n).
 */
int glint_atomic_tmpname(const char *path, char *tmp, size_t n);

/* fsync tmp, rename it to path and fsync the directory; unlinks on error. */
int glint_atomic_rename(const char *tmp, const char *path);

/* Write a whole buffer atomically. */
int glint_atomic_write_file(const char *path, const void *data, size_t n);

/* The same, as `name` in the folder open as dirfd, never following a
 * link (for shared folders: the temporary file is new, O_EXCL); mode
 * (e.g. 0640) is set on it before it takes the name, or -1 for the
 * umask's. */
int glint_atomic_write_fileat(int dirfd, const char *name, const void *data,
			      size_t n, int mode);

#endif
