/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_OUTPUT_H
#define GLINT_CORE_OUTPUT_H

/*
 * One overwrite rule for every file a command writes (OUT of convert,
 * render, export, probe unwrap; the files hdr writes into its folder):
 * a path that does not exist is written; an existing one is refused
 * unless force; with force it is replaced only when glint wrote it and
 * it is none of the command's inputs.  (A result folder has its own
 * manifest: core/atomic_dir.h.)
 *
 * glint's files say so: an EXR's "software" attribute, a PNG's
 * "Software" text, a TIFF's Software tag, a Radiance header's "# written
 * by glint" line, a JSON document's "glint" key or "generator", an
 * export's "glint export" heading.  A PFM holds no record of its writer,
 * so glint cannot tell its own from another's: one is never replaced.
 *
 * Errors: a negative errno with glint_error_msg() naming the file and
 * why.  Threads: re-entrant.  Who frees: nothing is allocated.
 */

/* The writer glint names in the files it writes. */
#define GLINT_OUTPUT_SOFTWARE "glint"

/* 1 when path is a regular file glint wrote (its marker, above), 0 when
 * not or when that cannot be told; *why (may be NULL) says which. */
int glint_output_is_glints(const char *path, const char **why);

/* May path be written as an output?  0 when it does not exist, or (with
 * force) is a regular file glint wrote that is none of inputs (by device
 * and inode; NULL-terminated, may be NULL).  Else -EEXIST (or the error
 * met) naming the file and what to do. */
int glint_output_check(const char *path, int force, const char *const *inputs);

#endif
