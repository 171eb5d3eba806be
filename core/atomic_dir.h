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
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected; the target is never left half written.  Threads:
 * a struct glint_atomic_dir belongs to one thread.  Who frees:
 * glint_atomic_dir_commit() or _abort() ends one, the temporary folder
 * removed on abort.
 */

/* The longest target path accepted (bytes, without the NUL): leaves room
 * for the siblings' suffixes and the names of the files inside. */
#define GLINT_ATOMIC_DIR_PATH_MAX 3840

struct glint_atomic_dir {
	char final_path[4096];
	char tmp_path[4096];
	/* Set before commit: the names glint writes into such a folder
	 * (NULL-terminated), which a folder without a manifest is taken to
	 * hold as glint's; and keep_others: files of the target that are
	 * not glint's (a user's notes, the inputs of the run) are carried
	 * into the new folder, so that only glint's own are replaced. */
	const char *const *names;
	int keep_others;
};

/* Each result folder lists the files glint wrote into it, one name a
 * line: what a later result may replace there, and nothing else. */
#define GLINT_ATOMIC_DIR_MANIFEST "glint-outputs.txt"

/* Create the temporary folder for `path`; -ENAMETOOLONG (and nothing
 * created) when path has GLINT_ATOMIC_DIR_PATH_MAX bytes or more. */
int glint_atomic_dir_open(struct glint_atomic_dir *ad, const char *path);
/* Path of file `name` inside the temporary folder (static storage per
 * call site is the caller's: buf of size n). */
const char *glint_atomic_dir_file(const struct glint_atomic_dir *ad,
				  const char *name, char *buf, unsigned n);
/* Put the folder in place of the target, with its manifest (every file
 * written into it); with keep_others, the target's files that are not
 * glint's are hard-linked into it first, so they stay whole at every
 * instant and the old folder's removal takes only glint's files.  A file
 * of the user's that cannot be carried (another file system, a folder)
 * stops the commit and nothing is replaced. */
int glint_atomic_dir_commit(struct glint_atomic_dir *ad);
/* Remove the temporary folder and its files. */
void glint_atomic_dir_abort(struct glint_atomic_dir *ad);
/*
 * May `path` take a result folder?  Yes when it does not exist, is an
 * empty folder, or is a previous result: a folder holding only glint's
 * files (those its manifest lists; without one, those named in `names`,
 * NULL-terminated).  Anything else (a user's notes, another program's
 * output, an input of this run) is refused with -EEXIST and a message,
 * unless force: then glint's files are replaced and the others kept,
 * carried into the new folder at commit (keep_others).  Even with force
 * it refuses a non-folder, a link, the current folder or one holding it,
 * a sub-folder or special file that is not glint's, and a file of
 * someone else's (or one of `inputs`, the run's input paths, may be
 * NULL) under a name the result writes (`writes`, NULL-terminated; NULL:
 * `names`).  Checked before any work, so a refusal costs nothing.
 */
int glint_atomic_dir_check(const char *path, const char *const *names,
			   const char *const *writes, const char *const *inputs,
			   int force);

/* Clean up after writers that died (SIGKILL, power cut) while writing
 * `path`: their temporary folders are removed, and an old result moved
 * aside but never replaced is put back.  Only for a caller that knows no
 * writer is running (it holds the lock that writers take).  Returns the
 * number of leftovers handled. */
int glint_atomic_dir_sweep(const char *path);

#endif
