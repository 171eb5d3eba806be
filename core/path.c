/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "path.h"
#include "error.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <unistd.h>
#include <stdio.h>
#include <string.h>

static int too_long(const char *start, size_t n)
{
	return glint_error_set(ENAMETOOLONG,
			       "path too long (over %zu bytes): %.60s...", n,
			       start);
}

int glint_path_fmt(char *buf, size_t n, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int len = vsnprintf(buf, n, fmt, ap);
	va_end(ap);
	if (len < 0 || (size_t)len >= n)
		return too_long(buf, n);
	return 0;
}

int glint_path_join(char *buf, size_t n, const char *dir, const char *name)
{
	if (!dir || !dir[0] || name[0] == '/')
		return glint_path_fmt(buf, n, "%s", name);
	size_t d = strlen(dir);
	const char *sep = dir[d - 1] == '/' ? "" : "/";
	return glint_path_fmt(buf, n, "%s%s%s", dir, sep, name);
}

int glint_path_sibling(char *buf, size_t n, const char *path,
		       const char *suffix)
{
	const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
	size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - path)
						     : strlen(path);
	return glint_path_fmt(buf, n, "%.*s%s", (int)stem, path, suffix);
}

int glint_path_dirname(char *buf, size_t n, const char *path)
{
	const char *slash = strrchr(path, '/');
	if (!slash)
		return glint_path_fmt(buf, n, ".");
	if (slash == path)
		return glint_path_fmt(buf, n, "/");
	return glint_path_fmt(buf, n, "%.*s", (int)(slash - path), path);
}

int glint_path_resolve(char *buf, size_t n, const char *base, const char *rel)
{
	char dir[GLINT_PATH_MAX];
	if (rel[0] == '/')
		return glint_path_fmt(buf, n, "%s", rel);
	int ret = glint_path_dirname(dir, sizeof(dir), base);
	return ret < 0 ? ret : glint_path_join(buf, n, dir, rel);
}

int glint_path_self(char *buf, size_t n)
{
	ssize_t len = readlink("/proc/self/exe", buf, n);

	if (len < 0)
		return glint_error_set(errno, "/proc/self/exe: %s",
				       strerror(errno));
	if ((size_t)len >= n)
		return glint_error_set(ENAMETOOLONG,
				       "/proc/self/exe: the path of glint's "
				       "executable is longer than %zu bytes",
				       n - 1);
	buf[len] = 0;
	return 0;
}

int glint_in_build_tree(void)
{
	char exe[GLINT_PATH_MAX];
	size_t root = strlen(GLINT_BUILD_ROOT);

	return glint_path_self(exe, sizeof(exe)) == 0 && strlen(exe) > root &&
	       !strncmp(exe, GLINT_BUILD_ROOT, root) && exe[root] == '/';
}

/* An installed path (absolute, as configured) under the root the binary
 * runs from: the binary at ROOT + the configured bindir puts it at ROOT +
 * path (ROOT empty for an ordinary install). */
static void installed(char *buf, size_t n, const char *path)
{
	char exe[GLINT_PATH_MAX], dir[GLINT_PATH_MAX];
	size_t lb = strlen(GLINT_INSTALL_BIN_DIR), ld;

	snprintf(buf, n, "%s", path);
	if (glint_path_self(exe, sizeof(exe)) < 0 ||
	    glint_path_dirname(dir, sizeof(dir), exe) < 0)
		return;
	ld = strlen(dir);
	if (ld > lb && !strcmp(dir + ld - lb, GLINT_INSTALL_BIN_DIR))
		snprintf(buf, n, "%.*s%s", (int)(ld - lb), dir, path);
}

/* The installed data folder, found once: threads ask for it at once
 * (the simulated camera renders a view on a thread of its own). */
static char installed_data[GLINT_PATH_MAX];

static void find_installed_data(void)
{
	installed(installed_data, sizeof(installed_data),
		  GLINT_INSTALL_DATA_DIR);
}

const char *glint_data_dir(void)
{
	static pthread_once_t once = PTHREAD_ONCE_INIT;
	const char *env = getenv("GLINT_DATA_DIR");

	if (env && env[0])
		return env;
	if (glint_in_build_tree())
		return GLINT_SOURCE_DATA_DIR;
	pthread_once(&once, find_installed_data);
	return installed_data;
}

const char *glint_rig_config_default(void)
{
	static char conf[GLINT_PATH_MAX];

	if (glint_in_build_tree())
		return GLINT_SOURCE_DATA_DIR "/rig-sim.json";
	installed(conf, sizeof(conf), GLINT_INSTALL_CONF_DIR "/rig.json");
	return conf;
}

int glint_data_path(char *buf, size_t n, const char *name)
{
	return glint_path_join(buf, n, glint_data_dir(), name);
}

static const char *file_kind(mode_t m)
{
	return S_ISFIFO(m)   ? "a FIFO"
	       : S_ISDIR(m)  ? "a folder"
	       : S_ISCHR(m)  ? "a character device"
	       : S_ISBLK(m)  ? "a block device"
	       : S_ISSOCK(m) ? "a socket"
			     : "not a plain file";
}

int glint_open_regular(const char *path, long long *size)
{
	struct stat st;
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);

	if (fd < 0)
		return glint_error_set(errno, "%s: cannot open: %s", path,
				       strerror(errno));
	if (fstat(fd, &st) < 0) {
		int e = errno;
		close(fd);
		return glint_error_set(e, "%s: %s", path, strerror(e));
	}
	if (!S_ISREG(st.st_mode)) {
		close(fd);
		return glint_error_set(EINVAL,
				       "%s: %s, not a regular file: expected "
				       "a file to read",
				       path, file_kind(st.st_mode));
	}
	int fl = fcntl(fd, F_GETFL);
	if (fl >= 0)
		fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
	if (size)
		*size = (long long)st.st_size;
	return fd;
}

FILE *glint_fopen_regular(const char *path, const char *mode)
{
	int fd = glint_open_regular(path, NULL);
	if (fd < 0) {
		errno = -fd;
		return NULL;
	}
	FILE *fp = fdopen(fd, mode);
	if (!fp) {
		int e = errno;
		close(fd);
		glint_error_set(e, "%s: %s", path, strerror(e));
		errno = e;
	}
	return fp;
}

int glint_check_regular(const char *path)
{
	int fd = glint_open_regular(path, NULL);
	if (fd < 0)
		return fd;
	close(fd);
	return 0;
}

int glint_path_is_empty_dir(const char *path)
{
	DIR *d = opendir(path);
	struct dirent *e;
	int empty = 1;

	if (!d)
		return errno == ENOENT;
	while (empty && (e = readdir(d)))
		empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
	closedir(d);
	return empty;
}
