/* SPDX-License-Identifier: MIT */
#define _DEFAULT_SOURCE /* getentropy */
#include "atomic_file.h"

#include "error.h"

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

int glint_atomic_tmpname(const char *path, char *tmp, size_t n)
{
	int fd;

	if ((size_t)snprintf(tmp, n, "%s.tmp.XXXXXX", path) >= n)
		return glint_error_set(ENAMETOOLONG, "%s: path too long", path);
	fd = mkstemp(tmp);
	if (fd < 0)
		return glint_error_set(errno,
				       "%s: cannot create a file here: %s",
				       path, strerror(errno));
	/* mkstemp makes 0600; give the file the mode open() would. */
	mode_t mask = umask(0);
	umask(mask);
	fchmod(fd, 0666 & ~mask);
	close(fd);
	return 0;
}

static int fsync_dir_of(const char *path)
{
	char buf[4096];
	int fd, ret = 0;

	snprintf(buf, sizeof(buf), "%s", path);
	fd = open(dirname(buf), O_RDONLY | O_DIRECTORY);
	if (fd < 0)
		return 0; /* nothing to sync against; rename already done */
	if (fsync(fd) < 0 && errno != EINVAL)
		ret = glint_error_set(errno, "%s: fsync of directory: %s", path,
				      strerror(errno));
	close(fd);
	return ret;
}

int glint_atomic_rename(const char *tmp, const char *path)
{
	int fd = open(tmp, O_RDONLY);

	if (fd < 0 || fsync(fd) < 0) {
		int e = errno;
		if (fd >= 0)
			close(fd);
		unlink(tmp);
		return glint_error_set(e, "%s: fsync: %s", tmp, strerror(e));
	}
	close(fd);
	if (rename(tmp, path) < 0) {
		int e = errno;
		unlink(tmp);
		return glint_error_set(e, "%s: rename into place: %s", path,
				       strerror(e));
	}
	return fsync_dir_of(path);
}

int glint_atomic_open(struct glint_atomic_file *af, const char *path)
{
	int ret;

	memset(af, 0, sizeof(*af));
	if ((size_t)snprintf(af->final_path, sizeof(af->final_path), "%s",
			     path) >= sizeof(af->final_path))
		return glint_error_set(ENAMETOOLONG, "%s: path too long", path);
	ret = glint_atomic_tmpname(path, af->tmp_path, sizeof(af->tmp_path));
	if (ret < 0)
		return ret;
	af->fp = fopen(af->tmp_path, "wb");
	if (!af->fp) {
		int e = errno;
		unlink(af->tmp_path);
		return glint_error_set(e, "%s: %s", af->tmp_path, strerror(e));
	}
	return 0;
}

int glint_atomic_commit(struct glint_atomic_file *af)
{
	int failed = ferror(af->fp);
	int e = errno;

	if (fclose(af->fp) != 0 && !failed) {
		failed = 1;
		e = errno;
	}
	af->fp = NULL;
	if (failed) {
		unlink(af->tmp_path);
		return glint_error_set(e ? e : EIO, "%s: write failed: %s",
				       af->final_path, strerror(e ? e : EIO));
	}
	return glint_atomic_rename(af->tmp_path, af->final_path);
}

void glint_atomic_abort(struct glint_atomic_file *af)
{
	if (af->fp)
		fclose(af->fp);
	af->fp = NULL;
	if (af->tmp_path[0])
		unlink(af->tmp_path);
}

int glint_atomic_write_file(const char *path, const void *data, size_t n)
{
	struct glint_atomic_file af;
	int ret = glint_atomic_open(&af, path);

	if (ret < 0)
		return ret;
	if (fwrite(data, 1, n, af.fp) != n) {
		int e = errno;
		glint_atomic_abort(&af);
		return glint_error_set(e ? e : EIO, "%s: write failed", path);
	}
	return glint_atomic_commit(&af);
}

int glint_atomic_write_fileat(int dirfd, const char *name, const void *data,
			      size_t n, int mode)
{
	char tmp[512];
	int fd = -1, e;

	for (int tries = 0; fd < 0 && tries < 16; tries++) {
		unsigned r = 0;
		if (getentropy(&r, sizeof(r)) < 0)
			r = (unsigned)getpid() * 2654435761u + (unsigned)tries;
		if ((size_t)snprintf(tmp, sizeof(tmp), "%s.tmp.%08x", name,
				     r) >= sizeof(tmp))
			return glint_error_set(ENAMETOOLONG,
					       "%s: name too long", name);
		fd = openat(dirfd, tmp,
			    O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW |
				    O_CLOEXEC,
			    0666);
		if (fd < 0 && errno != EEXIST)
			break;
	}
	if (fd < 0)
		return glint_error_set(errno, "%s: cannot create a file: %s",
				       name, strerror(errno));
	const char *p = data;
	size_t left = n;
	while (left > 0) {
		ssize_t w = write(fd, p, left);
		if (w < 0 && errno == EINTR)
			continue;
		if (w <= 0)
			goto fail;
		p += w;
		left -= (size_t)w;
	}
	if ((mode >= 0 && fchmod(fd, (mode_t)mode) < 0) || fsync(fd) < 0)
		goto fail;
	close(fd);
	fd = -1;
	if (renameat(dirfd, tmp, dirfd, name) < 0)
		goto fail;
	if (fsync(dirfd) < 0 && errno != EINVAL)
		return glint_error_set(errno, "%s: fsync of its folder: %s",
				       name, strerror(errno));
	return 0;
fail:
	e = errno ? errno : EIO;
	if (fd >= 0)
		close(fd);
	unlinkat(dirfd, tmp, 0);
	return glint_error_set(e, "%s: write failed: %s", name, strerror(e));
}
