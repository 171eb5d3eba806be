/* SPDX-License-Identifier: MIT */
#define _DEFAULT_SOURCE /* flock, scandir */
#include "queue.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/lockfile.h"
#include "core/log.h"
#include "core/path.h"

#include <dirent.h>
#include <errno.h>
#include <grp.h>
#include <libgen.h>
#include <pwd.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static const char *const states[] = { "pending", "running", "done", "failed",
				      "cancelled" };

/* QUEUE/STATE/IDEXT (IDEXT "" for the state's folder): whole or
 * -ENAMETOOLONG with a message. */
static int qpath(char *buf, const char *queue, const char *state,
		 const char *id, const char *ext)
{
	return glint_path_fmt(buf, GLINT_PATH_MAX, "%s/%s%s%s%s", queue, state,
			      id[0] ? "/" : "", id, ext);
}

int glint_queue_init(const char *queue)
{
	char path[GLINT_PATH_MAX];

	if (mkdir(queue, 0777) < 0 && errno != EEXIST)
		return glint_error_set(errno, "%s: cannot create the queue: %s",
				       queue, strerror(errno));
	for (int i = 0; i < 5; i++) {
		int ret = qpath(path, queue, states[i], "", "");
		if (ret < 0)
			return ret;
		if (mkdir(path, 0777) < 0 && errno != EEXIST)
			return glint_error_set(errno, "%s: %s", path,
					       strerror(errno));
		/* A link in a state folder's place would send job files
		 * and the worker's output elsewhere. */
		struct stat st;
		if (lstat(path, &st) < 0 || !S_ISDIR(st.st_mode))
			return glint_error_set(ENOTDIR,
					       "%s: not a folder (a link?): "
					       "the queue refuses it",
					       path);
	}
	return 0;
}

static int write_job(const char *path, json_t *doc)
{
	char *text = json_dumps(doc, JSON_INDENT(2) | JSON_SORT_KEYS);
	if (!text)
		return glint_error_set(ENOMEM, "out of memory");
	int ret = glint_atomic_write_file(path, text, strlen(text));
	free(text);
	return ret;
}

/* compact: 20261121T180000Z (IDs), else 2026-11-21T18:00:00Z. */
static void utc_now(char *buf, size_t n, int compact)
{
	time_t t = time(NULL);
	struct tm tm;
	gmtime_r(&t, &tm);
	if (compact)
		strftime(buf, n, "%Y%m%dT%H%M%SZ", &tm);
	else
		strftime(buf, n, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

int glint_queue_add(const char *queue, const char *kind, const char *session,
		    char *id_out)
{
	static int counter;
	char id[64], stamp[32], added[32], path[GLINT_PATH_MAX];
	char abs[GLINT_PATH_MAX];
	int ret;

	/* The worker runs in another folder, maybe as another user: the
	 * job names its session by its absolute, resolved path, inside the
	 * captures root. */
	struct glint_job me = { .uid = (unsigned)getuid() };
	snprintf(me.session, sizeof(me.session), "%s", session);
	ret = glint_job_session_allowed(queue, &me, abs, sizeof(abs));
	if (ret < 0)
		return ret;
	session = abs;
	ret = glint_queue_init(queue);
	if (ret < 0)
		return ret;
	utc_now(stamp, sizeof(stamp), 1);
	utc_now(added, sizeof(added), 0);
	snprintf(id, sizeof(id), "%s-%ld-%d", stamp, (long)getpid(), ++counter);
	json_t *doc = json_pack("{s:s, s:s, s:s, s:s, s:i}", "id", id, "kind",
				kind, "session", session, "added", added,
				"added_by_pid", (int)getpid());
	ret = qpath(path, queue, "pending", id, ".json");
	if (!ret)
		ret = doc ? write_job(path, doc)
			  : glint_error_set(ENOMEM, "out of memory");
	json_decref(doc);
	if (ret < 0)
		return ret;
	if (id_out)
		snprintf(id_out, 64, "%s", id);
	return 0;
}

/* Is uid in group gid (its primary group or a supplementary one)? */
static int in_group(unsigned uid, gid_t gid)
{
	struct passwd *pw = getpwuid((uid_t)uid);
	gid_t groups[256];
	int n = 256;
	if (!pw)
		return 0;
	if (pw->pw_gid == gid)
		return 1;
	if (getgrouplist(pw->pw_name, pw->pw_gid, groups, &n) < 0)
		return 0;
	for (int i = 0; i < n; i++)
		if (groups[i] == gid)
			return 1;
	return 0;
}

int glint_job_session_allowed(const char *queue, const struct glint_job *job,
			      char *real, size_t n)
{
	char root[GLINT_PATH_MAX], q[GLINT_PATH_MAX];
	struct stat st;

	if (n < GLINT_PATH_MAX || glint_path_fmt(q, sizeof(q), "%s", queue) < 0)
		return glint_error_set(ENAMETOOLONG, "%s: path too long",
				       queue);
	if (!realpath(dirname(q), root))
		return glint_error_set(errno, "%s: the captures root: %s",
				       queue, strerror(errno));
	if (job->session[0] == '\0' || !realpath(job->session, real))
		return glint_error_set(ENOENT, "session '%s': %s", job->session,
				       strerror(errno ? errno : ENOENT));
	size_t rl = strlen(root);
	if (strncmp(real, root, rl) || (real[rl] != '/' && rl != 1))
		return glint_error_set(EPERM,
				       "session %s is outside the captures "
				       "root %s: a job may only fit sessions "
				       "under the folder holding its queue",
				       real, root);
	if (stat(real, &st) < 0 || !S_ISDIR(st.st_mode))
		return glint_error_set(ENOENT, "session %s: not a folder",
				       real);
	if ((unsigned)st.st_uid == job->uid)
		return 0;
	if ((st.st_mode & S_IWGRP) && in_group(job->uid, st.st_gid))
		return 0;
	return glint_error_set(EPERM,
			       "session %s belongs to uid %u and is not "
			       "shared with the job's submitter (uid %u): "
			       "refused",
			       real, (unsigned)st.st_uid, job->uid);
}

static int job_name(const struct dirent *e)
{
	size_t n = strlen(e->d_name);
	return n > 5 && !strcmp(e->d_name + n - 5, ".json") &&
	       !strstr(e->d_name, ".tmp");
}

static int load_job(const char *queue, const char *state, const char *file,
		    struct glint_job *job)
{
	char path[GLINT_PATH_MAX];
	json_error_t err;

	memset(job, 0, sizeof(*job));
	job->lock_fd = -1;
	int ret = qpath(path, queue, state, file, "");
	if (ret < 0)
		return ret;
	/* A link planted in the queue is never followed; the submitter is
	 * the file's owner. */
	int fd = open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
	struct stat st;
	if (fd < 0 || fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
		int e = fd < 0 ? errno : EINVAL;
		if (fd >= 0)
			close(fd);
		return glint_error_set(e, "%s: not a job file: %s", path,
				       strerror(e));
	}
	job->uid = (unsigned)st.st_uid;
	job->doc = json_loadfd(fd, 0, &err);
	close(fd);
	if (!job->doc)
		return glint_error_set(EINVAL, "%s: %s", path, err.text);
	/* A waiting or running job's file is its submitter's; a finished
	 * one was rewritten by the worker, which kept the submitter. */
	json_t *by = json_object_get(job->doc, "submitter_uid");
	if (strcmp(state, "pending") && strcmp(state, "running") &&
	    json_is_integer(by))
		job->uid = (unsigned)json_integer_value(by);
	else
		json_object_set_new(job->doc, "submitter_uid",
				    json_integer(job->uid));
	snprintf(job->id, sizeof(job->id), "%.*s", (int)(strlen(file) - 5),
		 file);
	snprintf(job->state, sizeof(job->state), "%s", state);
	const char *k = json_string_value(json_object_get(job->doc, "kind"));
	const char *s = json_string_value(json_object_get(job->doc, "session"));
	snprintf(job->kind, sizeof(job->kind), "%s", k ? k : "");
	if (glint_path_fmt(job->session, sizeof(job->session), "%s",
			   s ? s : "") < 0) {
		json_decref(job->doc);
		job->doc = NULL;
		return glint_error_prefix(ENAMETOOLONG, "%s: session", path);
	}
	return 0;
}

void glint_job_release(struct glint_job *job)
{
	json_decref(job->doc);
	job->doc = NULL;
	glint_lockfile_release(job->lock_fd);
	job->lock_fd = -1;
}

int glint_queue_list(const char *queue,
		     int (*cb)(const struct glint_job *job, void *ctx),
		     void *ctx)
{
	char dir[GLINT_PATH_MAX];
	int stop = 0;

	for (int s = 0; s < 5 && !stop; s++) {
		struct dirent **names = NULL;
		int ret = qpath(dir, queue, states[s], "", "");
		if (ret < 0)
			return ret;
		int n = scandir(dir, &names, job_name, alphasort);
		if (n < 0) {
			if (errno == ENOENT)
				continue;
			return glint_error_set(errno, "%s: %s", dir,
					       strerror(errno));
		}
		for (int i = 0; i < n; i++) {
			struct glint_job job;
			/* A job that moved on between listing and reading
			 * is skipped, not an error. */
			if (!stop && load_job(queue, states[s],
					      names[i]->d_name, &job) == 0) {
				stop = cb(&job, ctx);
				glint_job_release(&job);
			}
			free(names[i]);
		}
		free(names);
	}
	return 0;
}

static int move(const char *queue, const char *id, const char *from,
		const char *to)
{
	char a[GLINT_PATH_MAX], b[GLINT_PATH_MAX];
	int ret = qpath(a, queue, from, id, ".json");
	if (!ret)
		ret = qpath(b, queue, to, id, ".json");
	if (ret < 0)
		return ret;
	if (rename(a, b) < 0)
		return -errno;
	return 0;
}

int glint_queue_cancel(const char *queue, const char *id)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	int ret;

	if (strchr(id, '/') || !id[0])
		return glint_error_set(EINVAL, "job id '%s': not an id", id);
	if (move(queue, id, "pending", "cancelled") == 0)
		return 0; /* it never ran */
	ret = qpath(path, queue, "running", id, ".json");
	if (ret < 0)
		return ret;
	if (stat(path, &st) == 0) {
		ret = qpath(path, queue, "running", id, ".cancel");
		if (ret < 0)
			return ret;
		int fd = open(path, O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC,
			      0666);
		if (fd < 0)
			return glint_error_set(errno, "%s: %s", path,
					       strerror(errno));
		close(fd);
		return 1; /* running: its worker stops it */
	}
	return glint_error_set(ENOENT,
			       "job %s: not pending or running in %s (glint "
			       "jobs lists them)",
			       id, queue);
}

/* Is running/ID held by a live worker?  Take its lock to find out. */
static int orphaned(const char *queue, const char *id)
{
	char path[GLINT_PATH_MAX];
	if (qpath(path, queue, "running", id, ".lock") < 0)
		return 0;
	int fd = open(path, O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
	if (fd < 0)
		return 0;
	int free_ = flock(fd, LOCK_EX | LOCK_NB) == 0;
	close(fd);
	return free_;
}

int glint_queue_recover(const char *queue)
{
	char dir[GLINT_PATH_MAX], path[GLINT_PATH_MAX];
	struct dirent **names = NULL;
	int n, moved = 0;

	if (qpath(dir, queue, "running", "", "") < 0)
		return 0;
	n = scandir(dir, &names, job_name, alphasort);
	for (int i = 0; i < n; i++) {
		char id[256];
		snprintf(id, sizeof(id), "%.*s",
			 (int)(strlen(names[i]->d_name) - 5), names[i]->d_name);
		if (orphaned(queue, id) &&
		    move(queue, id, "running", "pending") == 0) {
			moved++;
			if (!qpath(path, queue, "running", id, ".cancel"))
				unlink(path);
		}
		free(names[i]);
	}
	free(names);
	return moved;
}

int glint_queue_claim(const char *queue, struct glint_job *job)
{
	char dir[GLINT_PATH_MAX], path[GLINT_PATH_MAX];
	struct dirent **names = NULL;
	int n, got = 0, ret = glint_queue_init(queue);

	if (ret < 0)
		return ret;
	glint_queue_recover(queue);
	ret = qpath(dir, queue, "pending", "", "");
	if (ret < 0)
		return ret;
	n = scandir(dir, &names, job_name, alphasort);
	if (n < 0)
		return glint_error_set(errno, "%s: %s", dir, strerror(errno));
	for (int i = 0; i < n; i++) {
		char id[256];
		snprintf(id, sizeof(id), "%.*s",
			 (int)(strlen(names[i]->d_name) - 5), names[i]->d_name);
		if (!got) {
			/* Lock first, then claim: a claimed job is never
			 * seen unlocked (which would make it "orphaned"). */
			int fd;
			if (!qpath(path, queue, "running", id, ".lock") &&
			    glint_lockfile_acquire(path, "glint queue worker",
						   0, &fd) == 0) {
				if (move(queue, id, "pending", "running") ==
					    0 &&
				    load_job(queue, "running", names[i]->d_name,
					     job) == 0) {
					job->lock_fd = fd;
					got = 1;
				} else {
					/* Unreadable (a link, bad JSON):
					 * failed, not retried forever. */
					glint_log_warn("job %s: %s", id,
						       glint_error_msg());
					move(queue, id, "running", "failed");
					glint_lockfile_release(fd);
				}
			}
		}
		free(names[i]);
	}
	free(names);
	return got;
}

int glint_queue_cancel_requested(const char *queue, const struct glint_job *job)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	if (qpath(path, queue, "running", job->id, ".cancel") < 0)
		return 0;
	return stat(path, &st) == 0;
}

int glint_queue_finish(const char *queue, struct glint_job *job,
		       const char *state, json_t *result)
{
	char path[GLINT_PATH_MAX], when[32];
	int ret;

	utc_now(when, sizeof(when), 0);
	json_object_set_new(job->doc, "finished", json_string(when));
	json_object_set_new(job->doc, "state", json_string(state));
	if (result)
		json_object_update(job->doc, result);
	json_decref(result);
	ret = qpath(path, queue, state, job->id, ".json");
	if (!ret)
		ret = write_job(path, job->doc);
	for (int i = 0; i < 3 && ret == 0; i++)
		if (!qpath(path, queue, "running", job->id,
			   (const char *[]){ ".json", ".cancel", ".lock" }[i]))
			unlink(path);
	glint_job_release(job);
	return ret;
}
