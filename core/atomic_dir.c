/* SPDX-License-Identifier: MIT */
#define _GNU_SOURCE /* renameat2 */
#include "atomic_dir.h"

#include "atomic_file.h"
#include "error.h"
#include "path.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int listed(const char *name, const char *const *names)
{
	for (int i = 0; names[i]; i++)
		if (!strcmp(name, names[i]))
			return 1;
	return 0;
}

/* Is `path` the current folder or one of its ancestors? */
static int holds_cwd(const char *path)
{
	char cwd[GLINT_PATH_MAX], real[GLINT_PATH_MAX];
	size_t n;

	if (!getcwd(cwd, sizeof(cwd)) || !realpath(path, real))
		return 0;
	n = strlen(real);
	if (n == 1) /* "/" */
		return 1;
	return !strncmp(cwd, real, n) && (cwd[n] == '/' || cwd[n] == 0);
}

int glint_atomic_dir_open(struct glint_atomic_dir *ad, const char *path)
{
	memset(ad, 0, sizeof(*ad));
	/* Room for the siblings (".tmp.XXXXXX", ".old.PID") and the files
	 * inside: every path derived below then fits whole. */
	if (strlen(path) >= GLINT_ATOMIC_DIR_PATH_MAX)
		return glint_error_set(ENAMETOOLONG,
				       "%.64s...: an output folder's path must "
				       "be shorter than %d bytes",
				       path, GLINT_ATOMIC_DIR_PATH_MAX);
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
	/* A name that does not fit yields a path that cannot be opened
	 * (the folder itself), never a cut one naming another file. */
	if (glint_path_join(buf, n, ad->tmp_path, name) < 0)
		snprintf(buf, n, "%s/", ad->tmp_path);
	return buf;
}

/* Remove a folder glint made and the files in it.  A symbolic link in
 * its place is not followed (its target is someone else's), and the
 * files are unlinked relative to the folder opened, so nothing outside
 * it is reached. */
static void remove_tree(const char *path)
{
	int fd = open(path, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
	DIR *d = fd >= 0 ? fdopendir(fd) : NULL;
	struct dirent *e;

	if (!d) {
		if (fd >= 0)
			close(fd);
		return;
	}
	while ((e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		unlinkat(fd, e->d_name, 0);
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

/* The manifest of folder `dir` as a NULL-terminated list of names (one
 * allocation; free() it), or NULL when it has none. */
static char **read_manifest(const char *dir)
{
	char path[GLINT_PATH_MAX];
	if (glint_path_join(path, sizeof(path), dir,
			    GLINT_ATOMIC_DIR_MANIFEST) < 0) {
		glint_error_clear();
		return NULL;
	}
	FILE *f = fopen(path, "r");
	if (!f)
		return NULL;
	/* At most 256 names of up to 255 bytes: a manifest is glint's. */
	enum { MAXN = 256, NAMELEN = 256 };
	char **list = calloc(1, (MAXN + 1) * sizeof(char *) + MAXN * NAMELEN);
	char *store = list ? (char *)(list + MAXN + 1) : NULL;
	int n = 0;
	char line[NAMELEN + 2];
	while (list && n < MAXN && fgets(line, sizeof(line), f)) {
		line[strcspn(line, "\n")] = '\0';
		if (!line[0] || strchr(line, '/') || !strcmp(line, ".") ||
		    !strcmp(line, ".."))
			continue;
		size_t len = strlen(line);
		if (len >= NAMELEN)
			continue; /* no file name of glint's is that long */
		list[n] = store + (size_t)n * NAMELEN;
		memcpy(list[n], line, len + 1);
		n++;
	}
	fclose(f);
	return list;
}

/* Is `name` in folder `dir` glint's: listed in its manifest (or, with
 * none, in `names`), or the manifest itself? */
static int is_ours(const char *name, char **manifest, const char *const *names)
{
	if (!strcmp(name, GLINT_ATOMIC_DIR_MANIFEST))
		return 1;
	return manifest ? listed(name, (const char *const *)manifest)
			: listed(name, names);
}

/* Is the file `dir`/`name` one of the paths in `inputs`? */
static int is_input(int dfd, const char *name, const char *const *inputs)
{
	struct stat a, b;
	if (!inputs || fstatat(dfd, name, &a, AT_SYMLINK_NOFOLLOW) < 0)
		return 0;
	for (int i = 0; inputs[i]; i++)
		if (stat(inputs[i], &b) == 0 && a.st_dev == b.st_dev &&
		    a.st_ino == b.st_ino)
			return 1;
	return 0;
}

/* The manifest: every file written into the temporary folder. */
static int write_manifest(const struct glint_atomic_dir *ad)
{
	char path[GLINT_PATH_MAX], *text = NULL;
	size_t len = 0;
	DIR *d = opendir(ad->tmp_path);
	struct dirent *e;
	FILE *mem = open_memstream(&text, &len);
	int ret;

	if (!d || !mem) {
		if (d)
			closedir(d);
		if (mem)
			fclose(mem);
		free(text);
		return glint_error_set(errno ? errno : ENOMEM,
				       "%s: cannot list it: %s", ad->tmp_path,
				       strerror(errno));
	}
	while ((e = readdir(d)))
		if (e->d_name[0] != '.' &&
		    strcmp(e->d_name, GLINT_ATOMIC_DIR_MANIFEST))
			fprintf(mem, "%s\n", e->d_name);
	closedir(d);
	fclose(mem);
	ret = glint_path_join(path, sizeof(path), ad->tmp_path,
			      GLINT_ATOMIC_DIR_MANIFEST);
	if (ret == 0)
		ret = glint_atomic_write_file(path, text, len);
	free(text);
	return ret;
}

/* The target's files that are not glint's, hard-linked into the
 * temporary folder (the same file system: it is the target's sibling). */
static int carry_others(const struct glint_atomic_dir *ad)
{
	int sfd = open(ad->final_path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	int tfd = open(ad->tmp_path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	DIR *d = sfd >= 0 ? fdopendir(sfd) : NULL;
	struct dirent *e;
	struct stat st;
	int ret = 0;

	if (!d || tfd < 0) {
		ret = glint_error_set(errno, "%s: %s", ad->final_path,
				      strerror(errno));
		goto out;
	}
	char **manifest = read_manifest(ad->final_path);
	while (ret == 0 && (e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..") ||
		    is_ours(e->d_name, manifest, ad->names))
			continue;
		if (fstatat(sfd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) < 0 ||
		    !S_ISREG(st.st_mode))
			ret = glint_error_set(EEXIST,
					      "%s/%s is not glint's and not a "
					      "plain file: it cannot be "
					      "carried into the new result; "
					      "nothing replaced",
					      ad->final_path, e->d_name);
		else if (linkat(sfd, e->d_name, tfd, e->d_name, 0) < 0)
			ret = glint_error_set(errno,
					      "%s/%s: cannot keep it in the "
					      "new result (%s); nothing "
					      "replaced",
					      ad->final_path, e->d_name,
					      strerror(errno));
	}
	free(manifest);
out:
	if (d)
		closedir(d);
	else if (sfd >= 0)
		close(sfd);
	if (tfd >= 0)
		close(tfd);
	return ret;
}

int glint_atomic_dir_commit(struct glint_atomic_dir *ad)
{
	char old[GLINT_PATH_MAX], parent[GLINT_PATH_MAX];
	struct stat st;
	int had_old = 0;

	int ret = write_manifest(ad);
	if (ret == 0 && ad->keep_others && lstat(ad->final_path, &st) == 0 &&
	    S_ISDIR(st.st_mode))
		ret = carry_others(ad);
	if (ret < 0) {
		glint_atomic_dir_abort(ad);
		return ret;
	}
	fsync_path(ad->tmp_path);
	/* lstat: a symbolic link in the target's place is not a folder of
	 * results, and moving it aside would have its target emptied. */
	if (lstat(ad->final_path, &st) == 0) {
		if (!S_ISDIR(st.st_mode)) {
			glint_atomic_dir_abort(ad);
			return glint_error_set(EEXIST,
					       "%s exists and is not a folder",
					       ad->final_path);
		}
		/* Swap the two folders in one step: a complete result is
		 * visible at every instant, and a crash after the swap
		 * leaves the old one under the temporary name, which the
		 * next sweep removes. */
		if (renameat2(AT_FDCWD, ad->tmp_path, AT_FDCWD, ad->final_path,
			      RENAME_EXCHANGE) == 0) {
			glint_path_fmt(parent, sizeof(parent), "%s",
				       ad->final_path);
			fsync_path(dirname(parent));
			remove_tree(ad->tmp_path);
			ad->tmp_path[0] = '\0';
			return 0;
		}
		/* A file system without the exchange (EINVAL): move the old
		 * result aside first.  A crash between the two renames
		 * leaves no result until glint_atomic_dir_sweep puts the old
		 * one back. */
		if (errno != EINVAL && errno != ENOSYS) {
			int e = errno;
			glint_atomic_dir_abort(ad);
			return glint_error_set(e,
					       "%s: cannot put results in "
					       "place: %s",
					       ad->final_path, strerror(e));
		}
		if (glint_path_fmt(old, sizeof(old), "%s.old.%ld",
				   ad->final_path, (long)getpid()) < 0) {
			glint_atomic_dir_abort(ad);
			return -ENAMETOOLONG;
		}
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

int glint_atomic_dir_check(const char *path, const char *const *names,
			   const char *const *writes, const char *const *inputs,
			   int force)
{
	struct stat st;
	struct dirent *e;
	char other[256] = "";
	int others = 0, ret = 0;

	if (!writes)
		writes = names;
	if (lstat(path, &st) < 0)
		return errno == ENOENT ? 0
				       : glint_error_set(errno, "%s: %s", path,
							 strerror(errno));
	if (S_ISLNK(st.st_mode))
		return glint_error_set(EEXIST,
				       "%s is a symbolic link: a result "
				       "replaces its folder whole, so name "
				       "the folder itself or a new one",
				       path);
	if (!S_ISDIR(st.st_mode))
		return glint_error_set(EEXIST,
				       "%s exists and is not a folder: choose "
				       "another output folder",
				       path);
	if (holds_cwd(path))
		return glint_error_set(EBUSY,
				       "%s is the current folder or holds it: "
				       "results replace their folder whole, so "
				       "name a new one (e.g. -o fit-out)",
				       path);
	int dfd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	DIR *d = dfd >= 0 ? fdopendir(dfd) : NULL;
	if (!d) {
		ret = glint_error_set(errno, "%s: %s", path, strerror(errno));
		if (dfd >= 0)
			close(dfd);
		return ret;
	}
	char **manifest = read_manifest(path);
	while (ret == 0 && (e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		int input = is_input(dfd, e->d_name, inputs);
		if (!input && is_ours(e->d_name, manifest, names))
			continue;
		/* Someone else's file (or this run's input). */
		if (listed(e->d_name, writes))
			ret = glint_error_set(
				EEXIST,
				"%s/%s is %s, and the result writes a file "
				"of that name: refused (even with --force); "
				"choose another output folder",
				path, e->d_name,
				input ? "an input of this run"
				      : "not a file glint wrote there");
		else if (fstatat(dfd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) ==
				 0 &&
			 !S_ISREG(st.st_mode) && force)
			ret = glint_error_set(
				EEXIST,
				"%s/%s is not glint's and not a plain file: "
				"a result cannot carry it across, so the "
				"folder is refused (even with --force); "
				"choose another output folder",
				path, e->d_name);
		else if (!others++)
			glint_text(other, sizeof(other), "%s", e->d_name);
	}
	closedir(d);
	free(manifest);
	if (ret == 0 && others && !force)
		ret = glint_error_set(
			EEXIST,
			"%s holds files glint did not write ('%s'%s): "
			"refused; choose another output folder, or --force "
			"to write glint's results there beside them (only "
			"glint's own files are replaced)",
			path, other, others > 1 ? " and more" : "");
	return ret;
}

int glint_atomic_dir_sweep(const char *path)
{
	char dir[GLINT_PATH_MAX], base[GLINT_PATH_MAX], buf[GLINT_PATH_MAX];
	struct stat st;
	int restored = 0, removed = 0;

	if (strlen(path) >= GLINT_ATOMIC_DIR_PATH_MAX)
		return 0; /* never opened, so nothing to sweep */
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
		if (glint_path_join(buf, sizeof(buf), parent, e->d_name) < 0)
			continue;
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
