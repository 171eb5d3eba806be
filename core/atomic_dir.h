/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_ATOMIC_DIR_H
#define GLINT_CORE_ATOMIC_DIR_H

/*
 * A result folder that appears whole or not at all: files are written into
 * a temporary sibling folder, which takes the target's place when complete.
 * An existing target is swapped with it in one renameat2(RENAME_EXCHANGE),
 * so a complete result (old or new) is visible at every instant, even
 * under SIGKILL or a power cut; the old one is then removed.  On a file
 * system without the exchange the old one is moved aside first, and
 * glint_atomic_dir_sweep() puts it back after a crash between the two.
 */

/* The longest target path accepted (bytes, without the NUL): leaves room
 * for the siblings' suffixes and the names of the files inside. */
#define GLINT_ATOMIC_DIR_PATH_MAX 3840

struct glint_atomic_dir {
	char final_path[4096];
	char tmp_path[4096];
};

/* Create the temporary folder for `path`; -ENAMETOOLONG (and nothing
 * created) when path has GLINT_ATOMIC_DIR_PATH_MAX bytes or more. */
int glint_atomic_dir_open(struct glint_atomic_dir *ad, const char *path);
/* Path of file `name` inside the temporary folder (static storage per
 * call site is the caller's: buf of size n). */
const char *glint_atomic_dir_file(const struct glint_atomic_dir *ad,
				  const char *name, char *buf, unsigned n);
/* Put the folder in place of the target. */
int glint_atomic_dir_commit(struct glint_atomic_dir *ad);
/* Remove the temporary folder and its files. */
void glint_atomic_dir_abort(struct glint_atomic_dir *ad);
/*
 * May `path` be replaced by a result folder?  Yes when it does not exist,
 * is an empty folder, or is a previous result: a folder holding only
 * files named in `names` (NULL-terminated).  A folder
 * holding anything else (a user's notes, another program's output), a
 * file, a symbolic link, or the current folder or one holding it is
 * refused with -EEXIST/-EBUSY and a message, unless force (which still
 * refuses a non-folder, a link and the current folder).  Checked before any
 * work, so a refusal costs nothing.
 */
int glint_atomic_dir_check(const char *path, const char *const *names,
			   int force);

/* Clean up after writers that died (SIGKILL, power cut) while writing
 * `path`: their temporary folders are removed, and an old result moved
 * aside but never replaced is put back.  Only for a caller that knows no
 * writer is running (it holds the lock that writers take).  Returns the
 * number of leftovers handled. */
int glint_atomic_dir_sweep(const char *path);

#endif
