/* SPDX-License-Identifier: MIT */
#define _XOPEN_SOURCE 700
#include "atomic_dir.h"

#include "error.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int glint_atomic_dir_open(struct glint_atomic_dir *ad, const char *path)
{
	memset(ad, 0, sizeof(*ad));
	snprintf(ad->final_path, sizeof(ad->final_path), "%s", path);
	/* Drop trailing slashes so the sibling is next to the folder. */
	size_t l = strlen(ad->final_path);
	while (l > 1 && ad->final_path[l - 1] == '/')
		ad->final_path[--l] = '\0';
	snprintf(ad->tmp_path, sizeof(ad->tmp_path), "%s.tmp.XXXXXX",
		 ad->final_path);
	if (!mkdtemp(ad->tmp_path))
		return glint_error_set(errno,
				       "%s: cannot create a folder beside it: "
				       "%s",
				       ad->final_path, strerror(errno));
	chmod(ad->tmp_path, 0777 & ~(mode_t)0022);
	return 0;
}

const char *glint_atomic_dir_file(const struct glint_atomic_dir *ad,
				  const char *name, char *buf, unsigned n)
{
	snprintf(buf, n, "%s/%s", ad->tmp_path, name);
	return buf;
}

static void remove_tree(const char *path)
{
	DIR *d = opendir(path);
	struct dirent *e;
	char buf[4096];

	if (!d)
		return;
	while ((e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		snprintf(buf, sizeof(buf), "%s/%s", path, e->d_name);
		unlink(buf);
	}
	closedir(d);
	rmdir(path);
}

static void fsync_path(const char *path)
{
	int fd = open(path, O_RDONLY | O_DIRECTORY);
	if (fd >= 0) {
		fsync(fd);
		close(fd);
	}
}

int glint_atomic_dir_commit(struct glint_atomic_dir *ad)
{
	char old[4200], parent[4096];
	struct stat st;
	int had_old = 0;

	fsync_path(ad->tmp_path);
	if (stat(ad->final_path, &st) == 0) {
		if (!S_ISDIR(st.st_mode)) {
			glint_atomic_dir_abort(ad);
			return glint_error_set(EEXIST,
					       "%s exists and is not a folder",
					       ad->final_path);
		}
		snprintf(old, sizeof(old), "%s.old.%ld", ad->final_path,
			 (long)getpid());
		if (rename(ad->final_path, old) < 0) {
			int e = errno;
			glint_atomic_dir_abort(ad);
			return glint_error_set(e, "%s: cannot move aside: %s",
					       ad->final_path, strerror(e));
		}
		had_old = 1;
	}
	if (rename(ad->tmp_path, ad->final_path) < 0) {
		int e = errno;
		if (had_old)
			rename(old, ad->final_path);
		glint_atomic_dir_abort(ad);
		return glint_error_set(e, "%s: cannot put results in place: %s",
				       ad->final_path, strerror(e));
	}
	snprintf(parent, sizeof(parent), "%s", ad->final_path);
	fsync_path(dirname(parent));
	if (had_old)
		remove_tree(old);
	return 0;
}

void glint_atomic_dir_abort(struct glint_atomic_dir *ad)
{
	if (ad->tmp_path[0])
		remove_tree(ad->tmp_path);
	ad->tmp_path[0] = '\0';
}

int glint_atomic_dir_sweep(const char *path)
{
	char dir[4096], base[4096], buf[8400];
	struct stat st;
	int restored = 0, removed = 0;

	snprintf(dir, sizeof(dir), "%s", path);
	snprintf(base, sizeof(base), "%s", basename(dir));
	snprintf(dir, sizeof(dir), "%s", path);
	char *parent = dirname(dir);
	DIR *d = opendir(parent);
	struct dirent *e;
	size_t bl = strlen(base);
	int have_final = stat(path, &st) == 0;

	if (!d)
		return 0;
	while ((e = readdir(d))) {
		if (strncmp(e->d_name, base, bl) != 0)
			continue;
		const char *rest = e->d_name + bl;
		if (strncmp(rest, ".tmp.", 5) && strncmp(rest, ".old.", 5))
			continue;
		snprintf(buf, sizeof(buf), "%s/%s", parent, e->d_name);
		/* Cut between moving the old result aside and putting the
		 * new one in place: the old one is whole, bring it back. */
		if (!have_final && !strncmp(rest, ".old.", 5) &&
		    rename(buf, path) == 0) {
			have_final = 1;
			restored++;
			continue;
		}
		remove_tree(buf);
		removed++;
	}
	closedir(d);
	return restored + removed;
}
