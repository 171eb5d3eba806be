/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_ATOMIC_DIR_H
#define GLINT_CORE_ATOMIC_DIR_H

/*
 * A result folder that appears whole or not at all: files are written into
 * a temporary sibling folder, which is renamed over the target when
 * complete (an existing target is moved aside first and removed after).
 */

struct glint_atomic_dir {
	char final_path[4096];
	char tmp_path[4096];
};

/* Create the temporary folder for `path`. */
int glint_atomic_dir_open(struct glint_atomic_dir *ad, const char *path);
/* Path of file `name` inside the temporary folder (static storage per
 * call site is the caller's: buf of size n). */
const char *glint_atomic_dir_file(const struct glint_atomic_dir *ad,
				  const char *name, char *buf, unsigned n);
/* Put the folder in place of the target. */
int glint_atomic_dir_commit(struct glint_atomic_dir *ad);
/* Remove the temporary folder and its files. */
void glint_atomic_dir_abort(struct glint_atomic_dir *ad);
/* Clean up after writers that died (SIGKILL, power cut) while writing
 * `path`: their temporary folders are removed, and an old result moved
 * aside but never replaced is put back.  Only for a caller that knows no
 * writer is running (it holds the lock that writers take).  Returns the
 * number of leftovers handled. */
int glint_atomic_dir_sweep(const char *path);

#endif
