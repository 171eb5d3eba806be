/* SPDX-License-Identifier: MIT */
#define _DEFAULT_SOURCE /* flock */
#include "lockfile.h"

#include "error.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

int glint_lockfile_acquire(const char *path, const char *what, int wait,
			   int *fd)
{
	return glint_lockfile_acquireat(AT_FDCWD, path, what, wait, fd);
}

int glint_lockfile_acquireat(int dirfd, const char *path, const char *what,
			     int wait, int *fd)
{
	int f = openat(dirfd, path, O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC,
		       0666);

	*fd = -1;
	if (f < 0)
		return glint_error_set(errno, "%s: cannot open the lock: %s",
				       path, strerror(errno));
	while (flock(f, LOCK_EX | (wait ? 0 : LOCK_NB)) < 0) {
		if (errno == EINTR && wait)
			continue;
		int e = errno;
		char holder[256] = "";
		ssize_t n = pread(f, holder, sizeof(holder) - 1, 0);
		close(f);
		if (e != EWOULDBLOCK)
			return glint_error_set(e, "%s: cannot lock: %s", path,
					       strerror(e));
		if (n > 0) {
			holder[n] = '\0';
			holder[strcspn(holder, "\n")] = '\0';
		}
		return glint_error_set(EBUSY, "%s: busy: held by %s", path,
				       holder[0] ? holder : "another process");
	}
	/* A lock file with other names (a hard link to someone's file,
	 * planted where the lock goes) is not ours to truncate. */
	struct stat st;
	if (fstat(f, &st) < 0 || !S_ISREG(st.st_mode) || st.st_nlink != 1) {
		int links = fstat(f, &st) < 0 ? 0 : (int)st.st_nlink;
		close(f);
		return glint_error_set(EPERM,
				       "%s: the lock file has %d names (a hard "
				       "link to another file?): refused",
				       path, links);
	}
	/* Ours: say who holds it. */
	char line[300];
	int n = snprintf(line, sizeof(line), "pid %ld: %s\n", (long)getpid(),
			 what);
	if (ftruncate(f, 0) == 0 && pwrite(f, line, (size_t)n, 0) < 0) {
		/* Only informative: the lock itself is held. */
	}
	*fd = f;
	return 0;
}

void glint_lockfile_release(int fd)
{
	if (fd < 0)
		return;
	/* Closing drops the flock; the file stays for the next holder. */
	close(fd);
}
