/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_PATH_H
#define GLINT_CORE_PATH_H

/*
 * Paths built into caller-owned buffers.  Every function either writes the
 * whole path or fails with -ENAMETOOLONG and a message naming the start of
 * the path that did not fit: a path is never silently cut short.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (a path too long is refused, never cut).  Threads:
 * re-entrant; the data folder is set once at start.  Who frees: nothing
 * (buffers are the caller's; the data folder is static).
 */

#include "error.h"

#include <stddef.h>
#include <stdio.h>

/* GLINT_PATH_MAX: the buffer size glint uses for paths (PATH_MAX). */
#define GLINT_PATH_MAX 4096

/* buf = "dir/name" (just name when dir is NULL or "", or name is
 * absolute).  Returns 0 or -ENAMETOOLONG. */
int glint_path_join(char *buf, size_t n, const char *dir, const char *name);

/* buf = printf(fmt, ...); 0 or -ENAMETOOLONG. */
int glint_path_fmt(char *buf, size_t n, const char *fmt, ...)
	GLINT_PRINTF(3, 4);

/* A path given relative to the file `base` (a rig or scene file): `rel`
 * itself when absolute, else base's folder joined with rel. */
int glint_path_resolve(char *buf, size_t n, const char *base, const char *rel);

/* buf = path with its extension replaced by suffix ("env.exr",
 * "-mask.png" -> "env-mask.png"; a path without extension gets suffix
 * appended). */
int glint_path_sibling(char *buf, size_t n, const char *path,
		       const char *suffix);

/*
 * An input file opened for reading only if it is a regular file: opened
 * with O_NONBLOCK (a FIFO, a terminal or a device would otherwise block
 * the open or the reads forever), checked with fstat, then set blocking
 * again.  Returns the descriptor, or a negative errno with a message that
 * names the file and what it is ("a FIFO, not a regular file").  *size
 * (may be NULL) gets its size.
 */
int glint_open_regular(const char *path, long long *size);

/* glint_open_regular as a stdio stream (mode "r" or "rb"): NULL with
 * errno set and the message naming the file and what it is. */
FILE *glint_fopen_regular(const char *path, const char *mode);

/* The same check alone, for readers a library opens by path: 0 or a
 * negative errno naming the file. */
int glint_check_regular(const char *path);

/* 1 when path does not exist or is a folder with no entries; 0 when it
 * holds any (or is not a folder). */
int glint_path_is_empty_dir(const char *path);

/* The folder part of `path` ("." when it has none) into buf. */
int glint_path_dirname(char *buf, size_t n, const char *path);

/* This program's own executable (to run glint again, as a worker or a
 * job): 0, or -ENAMETOOLONG / -errno with a message. */
int glint_path_self(char *buf, size_t n);

/*
 * The folder of glint's own data (the sim rig's map, Table 1, rig files):
 * $GLINT_DATA_DIR when set; else the source tree's data/ for a binary run
 * from its build folder (tests, benches, a checkout), else the installed
 * one (meson's datadir/glint) found relative to the installed binary: a
 * tree installed under another root (a DESTDIR, an image being built)
 * finds its own.  Static storage; no trailing slash.
 */
const char *glint_data_dir(void);

/* 1 for a binary run from its build folder, 0 for an installed one. */
int glint_in_build_tree(void);

/*
 * The rig file every rig command takes without --config: the simulated
 * rig (data/rig-sim.json) for a binary run from its build folder, the
 * installed appliance's (meson's sysconfdir/glint/rig.json, relative to
 * the installed binary as above) otherwise.  Static storage.
 */
const char *glint_rig_config_default(void);

/* Into buf: glint_data_dir() joined with name. */
int glint_data_path(char *buf, size_t n, const char *name);

#endif
