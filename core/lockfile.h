/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_LOCKFILE_H
#define GLINT_CORE_LOCKFILE_H

/*
 * An advisory lock on a file (flock), for work that one process at a time
 * may do (a session's fit, the job queue).  The kernel drops it when its
 * holder dies, even by SIGKILL or a power cut, so it never goes stale.
 * The holder writes "pid what" into the file so that whoever is refused
 * can be told who holds it.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (-EBUSY naming the holder).  Threads: re-entrant;
 * a lock belongs to its process.  Who frees: glint_lockfile_release()
 * closes the descriptor and drops the lock.
 */

/* Take the lock at `path` (created if missing).  wait = 0: fail at once
 * with -EBUSY naming the holder; wait = 1: block until it is free.
 * *fd gets the descriptor to pass to glint_lockfile_release(). */
int glint_lockfile_acquire(const char *path, const char *what, int wait,
			   int *fd);
/* The same for `name` in the folder open as dirfd (never a link). */
int glint_lockfile_acquireat(int dirfd, const char *name, const char *what,
			     int wait, int *fd);
void glint_lockfile_release(int fd);

#endif
