/* SPDX-License-Identifier: MIT */
#define _GNU_SOURCE /* flock, scandirat */
#include "appliance/queue.h"

#include "capture/hdr/session.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json.h"
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
enum { PENDING, RUNNING, DONE, FAILED, CANCELLED, NSTATES };

/*
 * The queue's folders, open.  Every file in them is reached relative to
 * these descriptors and never through a link: a folder swapped for a link
 * after it was opened changes nothing, and a link planted as a job's file
 * is refused.
 */
struct qdir {
	int root;
	int st[NSTATES];
	unsigned owner; /* the queue folder's owner: the rig's worker */
};

static void qclose(struct qdir *d)
{
	for (int i = 0; i < NSTATES; i++)
		if (d->st[i] >= 0)
			close(d->st[i]);
	if (d->root >= 0)
		close(d->root);
}

static int state_of(const char *name)
{
	for (int i = 0; i < NSTATES; i++)
		if (!strcmp(states[i], name))
			return i;
	return -1;
}

/*
 * A queue folder others may write must be sticky, or any of them could
 * rename or remove what is in it (pending/ swapped for a folder of his
 * own, where the next user's job would land): its owner makes it so,
 * anyone else is refused, told the fix.
 */
static int sticky_if_shared(int fd, const char *queue, const char *name)
{
	const char *sep = name[0] ? "/" : "";
	struct stat st;
	if (fstat(fd, &st) < 0)
		return glint_error_set(errno, "%s%s%s: %s", queue, sep, name,
				       strerror(errno));
	if (!(st.st_mode & (S_IWGRP | S_IWOTH)) || (st.st_mode & S_ISVTX))
		return 0;
	if (st.st_uid == geteuid() &&
	    fchmod(fd, (st.st_mode & 07777) | S_ISVTX) == 0) {
		glint_log_info("%s%s%s: writable by others: made sticky", queue,
			       sep, name);
		return 0;
	}
	return glint_error_set(EPERM,
			       "%s%s%s: writable by others and not sticky "
			       "(mode %04o): any user could rename or remove "
			       "what is in it; its owner (uid %u) fixes it "
			       "with chmod +t",
			       queue, sep, name, (unsigned)(st.st_mode & 07777),
			       (unsigned)st.st_uid);
}

/*
 * Open QUEUE (made with its folders when `create`).  The queue folder and
 * its state folders are sticky (01777 less the umask, and checked on
 * every open: sticky_if_shared): in a queue shared through a group, only
 * a job's submitter and the queue's owner may move or remove it, and no
 * one else renames a state folder.
 */
static int qopen(const char *queue, struct qdir *d, int create)
{
	struct stat st;

	d->root = -1;
	for (int i = 0; i < NSTATES; i++)
		d->st[i] = -1;
	if (create && mkdir(queue, 01777) < 0 && errno != EEXIST)
		return glint_error_set(errno, "%s: cannot create the queue: %s",
				       queue, strerror(errno));
	d->root = open(queue, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (d->root < 0 || fstat(d->root, &st) < 0)
		return glint_error_set(errno, "%s: the queue: %s", queue,
				       strerror(errno));
	int ret = sticky_if_shared(d->root, queue, "");
	if (ret < 0) {
		qclose(d);
		return ret;
	}
	d->owner = (unsigned)st.st_uid;
	for (int i = 0; i < NSTATES; i++) {
		if (create && mkdirat(d->root, states[i], 01777) < 0 &&
		    errno != EEXIST) {
			int e = errno;
			qclose(d);
			return glint_error_set(e, "%s/%s: %s", queue, states[i],
					       strerror(e));
		}
		d->st[i] =
			openat(d->root, states[i],
			       O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
		if (d->st[i] < 0) {
			int e = errno;
			qclose(d);
			/* A link in a state folder's place would send job
			 * files and the worker's output elsewhere. */
			if (e == ENOTDIR || e == ELOOP)
				return glint_error_set(
					ENOTDIR,
					"%s/%s: not a folder (a link?): the "
					"queue refuses it",
					queue, states[i]);
			if (e == ENOENT && !create)
				return -ENOENT;
			return glint_error_set(e, "%s/%s: %s", queue, states[i],
					       strerror(e));
		}
		ret = sticky_if_shared(d->st[i], queue, states[i]);
		if (ret < 0) {
			qclose(d);
			return ret;
		}
	}
	return 0;
}

/* ID + ext, or -ENAMETOOLONG. */
static int jname(char *buf, size_t n, const char *id, const char *ext)
{
	if (!id[0] || strchr(id, '/'))
		return glint_error_set(EINVAL, "job id '%s': not an id", id);
	return glint_path_fmt(buf, n, "%s%s", id, ext);
}

int glint_queue_init(const char *queue)
{
	struct qdir d;
	int ret = qopen(queue, &d, 1);
	if (ret == 0)
		qclose(&d);
	return ret;
}

/* mode: -1 (the umask's), or e.g. 0640 for a finished record */
static int write_job(int dirfd, const char *id, json_t *doc, int mode)
{
	char name[GLINT_PATH_MAX];
	int ret = jname(name, sizeof(name), id, ".json");
	if (ret < 0)
		return ret;
	char *text = json_dumps(doc, JSON_INDENT(2) | JSON_SORT_KEYS);
	if (!text)
		return glint_error_set(ENOMEM, "out of memory");
	ret = glint_atomic_write_fileat(dirfd, name, text, strlen(text), mode);
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

static int in_group(unsigned uid, gid_t gid);

/* The worker runs as the queue's owner and writes SESSION/fit: refused at
 * once when that user cannot write the session folder (rather than the
 * job failing later, unseen). */
static int worker_can_write(const struct qdir *d, const char *session)
{
	struct stat st;
	if (stat(session, &st) < 0)
		return glint_error_set(errno, "session %s: %s", session,
				       strerror(errno));
	unsigned w = d->owner;
	if (w == 0 || ((unsigned)st.st_uid == w && (st.st_mode & S_IWUSR)) ||
	    ((unsigned)st.st_uid != w && (st.st_mode & S_IWGRP) &&
	     in_group(w, st.st_gid)) ||
	    ((unsigned)st.st_uid != w && !in_group(w, st.st_gid) &&
	     (st.st_mode & S_IWOTH)))
		return 0;
	return glint_error_set(EACCES,
			       "session %s (uid %u, group %u, mode %03o): "
			       "the queue's worker (uid %u) cannot write its "
			       "fit there: make it group-writable for a group "
			       "the worker is in (chmod g+w), or fit it "
			       "yourself with glint fit",
			       session, (unsigned)st.st_uid,
			       (unsigned)st.st_gid,
			       (unsigned)(st.st_mode & 0777), w);
}

/* A waiting or running job of the same session (glint_queue_list's
 * callback): its id and state. */
struct dup_find {
	const char *session;
	char id[64], state[16];
};

static int find_dup(const struct glint_job *j, void *ctx)
{
	struct dup_find *f = ctx;
	if ((strcmp(j->state, "pending") && strcmp(j->state, "running")) ||
	    strcmp(j->session, f->session))
		return 0;
	snprintf(f->id, sizeof(f->id), "%s", j->id);
	snprintf(f->state, sizeof(f->state), "%s", j->state);
	return 1;
}

int glint_queue_add(const char *queue, const char *kind, const char *session,
		    char *id_out)
{
	static int counter;
	char id[64], stamp[32], added[32];
	char abs[GLINT_PATH_MAX];
	struct qdir d;
	int ret;

	/* The worker runs in another folder, maybe as another user: the
	 * job names its session by its absolute, resolved path, inside the
	 * captures root. */
	struct glint_job me = { .uid = (unsigned)getuid() };
	snprintf(me.session, sizeof(me.session), "%s", session);
	ret = glint_job_session_open(queue, &me, abs, sizeof(abs));
	if (ret < 0)
		return ret;
	close(ret);
	session = abs;
	ret = qopen(queue, &d, 1);
	if (ret < 0)
		return ret;
	ret = worker_can_write(&d, session);
	/* one fit of a session at a time: a second add is refused, naming
	 * the job that will fit it */
	struct dup_find dup = { session, "", "" };
	if (ret == 0)
		ret = glint_queue_list(queue, find_dup, &dup);
	if (ret == 0 && dup.id[0])
		ret = glint_error_set(EEXIST,
				      "session %s is already queued: job %s "
				      "(%s); glint queue cancel %s first to "
				      "queue it again",
				      session, dup.id, dup.state, dup.id);
	if (ret < 0) {
		qclose(&d);
		return ret;
	}
	utc_now(stamp, sizeof(stamp), 1);
	utc_now(added, sizeof(added), 0);
	snprintf(id, sizeof(id), "%s-%ld-%d", stamp, (long)getpid(), ++counter);
	json_t *doc = json_pack("{s:s, s:s, s:s, s:s, s:i}", "id", id, "kind",
				kind, "session", session, "added", added,
				"added_by_pid", (int)getpid());
	ret = doc ? write_job(d.st[PENDING], id, doc, -1)
		  : glint_error_set(ENOMEM, "out of memory");
	json_decref(doc);
	qclose(&d);
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

/* May the job's submitter have the folder open as fd fitted: owned by
 * it, or group-writable by a group it is in (from fstat: the folder
 * opened, not a path that may since lead elsewhere). */
static int folder_shared(int fd, const char *name, const struct glint_job *job)
{
	struct stat st;
	if (fstat(fd, &st) < 0 || !S_ISDIR(st.st_mode))
		return glint_error_set(ENOENT, "session %s: not a folder",
				       name);
	if ((unsigned)st.st_uid == job->uid)
		return 0;
	if ((st.st_mode & S_IWGRP) && in_group(job->uid, st.st_gid))
		return 0;
	return glint_error_set(EPERM,
			       "session %s belongs to uid %u and is not "
			       "shared with the job's submitter (uid %u): "
			       "refused",
			       name, (unsigned)st.st_uid, job->uid);
}

int glint_job_session_open(const char *queue, const struct glint_job *job,
			   char *real, size_t n)
{
	char root[GLINT_PATH_MAX], q[GLINT_PATH_MAX], now[GLINT_PATH_MAX];

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
	int fd = open(real, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
	if (fd < 0)
		return glint_error_set(
			errno == ENOTDIR || errno == ELOOP ? ENOENT : errno,
			"session %s: not a folder (%s)", real, strerror(errno));
	/* The folder opened is the one checked: a component swapped for a
	 * link between realpath and open would show here as another path
	 * (the kernel's name of what fd holds). */
	char link[64];
	snprintf(link, sizeof(link), "/proc/self/fd/%d", fd);
	ssize_t ln = readlink(link, now, sizeof(now) - 1);
	if (ln < 0 || (now[ln] = '\0', strcmp(now, real))) {
		close(fd);
		return glint_error_set(EPERM,
				       "session %s changed while it was "
				       "checked: refused",
				       real);
	}
	int ret = folder_shared(fd, real, job);
	/* A rig run's joint fit: each of its samples too, opened beneath
	 * the run's folder (a run names plain folders in itself; a link
	 * there is refused, not followed). */
	struct glint_run_samples *rs = ret < 0 ? NULL : malloc(sizeof(*rs));
	if (ret == 0 && !rs)
		ret = glint_error_set(ENOMEM, "out of memory");
	int run = ret < 0 ? 0 : glint_run_read(real, rs);
	if (run < 0)
		ret = run;
	for (int k = 0; run > 0 && ret == 0 && k < rs->n; k++) {
		const char *name = strrchr(rs->session[k], '/') + 1;
		int s = openat(fd, name,
			       O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
		if (s < 0)
			ret = glint_error_set(EPERM,
					      "run %s: sample %s is not a "
					      "folder in the run (%s)",
					      real, name, strerror(errno));
		else
			ret = folder_shared(s, rs->session[k], job);
		if (s >= 0)
			close(s);
	}
	free(rs);
	if (ret < 0) {
		close(fd);
		return ret;
	}
	return fd;
}

/* A job file's name: ID.json, the id at most 63 letters, digits, '.',
 * '_' or '-' (what struct glint_job holds whole: a longer one would be
 * claimed under one name and finished under another).  Anything else in
 * a state folder is not a job, and no worker or listing touches it. */
static int job_name(const struct dirent *e)
{
	size_t n = strlen(e->d_name);
	if (n <= 5 || n - 5 >= sizeof(((struct glint_job *)0)->id) ||
	    strcmp(e->d_name + n - 5, ".json") || strstr(e->d_name, ".tmp"))
		return 0;
	for (size_t i = 0; i < n - 5; i++) {
		char c = e->d_name[i];
		if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
		      (c >= '0' && c <= '9') || c == '.' || c == '_' ||
		      c == '-'))
			return 0;
	}
	return 1;
}

/* A job file is a few hundred bytes; a megabyte is no job. */
#define GLINT_JOB_MAX_BYTES (1024 * 1024)

static int load_job(const struct qdir *d, int state, const char *file,
		    struct glint_job *job)
{
	memset(job, 0, sizeof(*job));
	job->lock_fd = -1;
	job->dir_fd = -1;
	job->queue_uid = d->owner;
	/* A link planted in the queue is never followed; the submitter is
	 * the file's owner. */
	/* ... nor is a FIFO waited on (O_NONBLOCK until fstat says it is a
	 * regular file), and a job file is read in blocks, up to a cap. */
	int fd = openat(d->st[state], file,
			O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
	struct stat st;
	if (fd < 0 || fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
		int e = fd < 0 ? errno : EINVAL;
		if (fd >= 0)
			close(fd);
		return glint_error_set(e, "%s/%s: not a job file: %s",
				       states[state], file, strerror(e));
	}
	int fl = fcntl(fd, F_GETFL);
	if (fl >= 0)
		fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
	job->uid = (unsigned)st.st_uid;
	char name[GLINT_PATH_MAX];
	snprintf(name, sizeof(name), "%s/%s", states[state], file);
	int ret = st.st_size > GLINT_JOB_MAX_BYTES
			  ? glint_error_set(EFBIG,
					    "%s: %lld bytes: expected a job "
					    "file of at most %d",
					    name, (long long)st.st_size,
					    GLINT_JOB_MAX_BYTES)
			  : glint_json_load_fd(fd, name, GLINT_JOB_MAX_BYTES,
					       &job->doc);
	close(fd);
	if (ret < 0)
		return ret;
	/* A waiting or running job's file is its submitter's; a finished
	 * one was rewritten by the worker, which kept the submitter. */
	json_t *by = json_object_get(job->doc, "submitter_uid");
	/* ... but only a record the worker wrote (the queue's owner's or
	 * root's, writable by its owner alone) is believed: one planted or
	 * rewritten by someone else names its file's owner */
	int worker_record =
		((unsigned)st.st_uid == d->owner || st.st_uid == 0) &&
		!(st.st_mode & (S_IWGRP | S_IWOTH));
	if (state != PENDING && state != RUNNING && json_is_integer(by) &&
	    worker_record)
		job->uid = (unsigned)json_integer_value(by);
	else
		json_object_set_new(job->doc, "submitter_uid",
				    json_integer(job->uid));
	snprintf(job->id, sizeof(job->id), "%.*s", (int)(strlen(file) - 5),
		 file);
	snprintf(job->state, sizeof(job->state), "%s", states[state]);
	const char *k = json_string_value(json_object_get(job->doc, "kind"));
	const char *s = json_string_value(json_object_get(job->doc, "session"));
	snprintf(job->kind, sizeof(job->kind), "%s", k ? k : "");
	if (glint_path_fmt(job->session, sizeof(job->session), "%s",
			   s ? s : "") < 0) {
		json_decref(job->doc);
		job->doc = NULL;
		return glint_error_prefix(ENAMETOOLONG, "%s/%s: session",
					  states[state], file);
	}
	return 0;
}

void glint_job_release(struct glint_job *job)
{
	json_decref(job->doc);
	job->doc = NULL;
	glint_lockfile_release(job->lock_fd);
	job->lock_fd = -1;
	if (job->dir_fd >= 0)
		close(job->dir_fd);
	job->dir_fd = -1;
}

/* Job files in a state folder, oldest first; -1 with errno on error. */
static int scan(const struct qdir *d, int state, struct dirent ***names)
{
	return scandirat(d->st[state], ".", names, job_name, alphasort);
}

static void free_names(struct dirent **names, int n)
{
	for (int i = 0; i < n; i++)
		free(names[i]);
	free(names);
}

static void id_of(char *id, size_t n, const struct dirent *e)
{
	snprintf(id, n, "%.*s", (int)(strlen(e->d_name) - 5), e->d_name);
}

int glint_queue_list(const char *queue,
		     int (*cb)(const struct glint_job *job, void *ctx),
		     void *ctx)
{
	struct qdir d;
	int stop = 0, ret = qopen(queue, &d, 0);

	if (ret == -ENOENT)
		return 0; /* no queue yet: no jobs */
	if (ret < 0)
		return ret;
	for (int s = 0; s < NSTATES && !stop; s++) {
		struct dirent **names = NULL;
		int n = scan(&d, s, &names);
		if (n < 0) {
			int e = errno;
			qclose(&d);
			return glint_error_set(e, "%s/%s: %s", queue, states[s],
					       strerror(e));
		}
		for (int i = 0; i < n && !stop; i++) {
			struct glint_job job;
			/* A job that moved on between listing and reading
			 * is skipped, not an error. */
			if (load_job(&d, s, names[i]->d_name, &job) == 0) {
				stop = cb(&job, ctx);
				glint_job_release(&job);
			}
		}
		free_names(names, n);
	}
	qclose(&d);
	return 0;
}

static int move(const struct qdir *d, const char *id, int from, int to)
{
	char name[GLINT_PATH_MAX];
	if (jname(name, sizeof(name), id, ".json") < 0)
		return -ENAMETOOLONG;
	if (renameat(d->st[from], name, d->st[to], name) < 0)
		return -errno;
	return 0;
}

/* May files owned by uid steer this job (its lock, a cancel request)?
 * Its submitter, the queue's owner, root and this process may; anyone
 * else sharing the queue may not. */
static int trusted(const struct glint_job *job, unsigned queue_uid,
		   unsigned uid)
{
	return uid == (unsigned)geteuid() || uid == 0 || uid == queue_uid ||
	       (job && uid == job->uid);
}

int glint_queue_cancel(const char *queue, const char *id)
{
	char name[GLINT_PATH_MAX];
	struct qdir d;
	int ret = jname(name, sizeof(name), id, ".json");

	if (ret < 0)
		return ret;
	ret = qopen(queue, &d, 0);
	if (ret == -ENOENT)
		return glint_error_set(ENOENT, "%s: no queue here", queue);
	if (ret < 0)
		return ret;
	/* Only its submitter (or the queue's owner, or root) cancels a
	 * job; the sticky folders make the kernel agree. */
	for (int s = PENDING; s <= RUNNING; s++) {
		struct glint_job job;
		if (load_job(&d, s, name, &job) < 0)
			continue;
		unsigned by = job.uid;
		glint_job_release(&job);
		unsigned me = (unsigned)geteuid();
		if (by != me && me != 0 && me != d.owner) {
			qclose(&d);
			return glint_error_set(EPERM,
					       "job %s was submitted by uid "
					       "%u: only it (or the queue's "
					       "owner) may cancel it",
					       id, by);
		}
		if (s == PENDING) {
			ret = move(&d, id, PENDING, CANCELLED);
			if (ret == 0) {
				qclose(&d);
				return 0; /* it never ran */
			}
			continue; /* claimed meanwhile: running now */
		}
		char cancel[GLINT_PATH_MAX];
		ret = jname(cancel, sizeof(cancel), id, ".cancel");
		int fd = ret < 0 ? -1
				 : openat(d.st[RUNNING], cancel,
					  O_WRONLY | O_CREAT | O_NOFOLLOW |
						  O_CLOEXEC,
					  0666);
		int e = errno;
		qclose(&d);
		if (fd < 0)
			return glint_error_set(e, "%s/running/%s: %s", queue,
					       cancel, strerror(e));
		close(fd);
		return 1; /* running: its worker stops it */
	}
	qclose(&d);
	return glint_error_set(ENOENT,
			       "job %s: not pending or running in %s (glint "
			       "jobs lists them)",
			       id, queue);
}

/* Is running/ID held by a live worker?  Take its lock to find out.  A
 * lock file someone untrusted made is no worker's: orphaned. */
static int orphaned(const struct qdir *d, const struct glint_job *job)
{
	char name[GLINT_PATH_MAX];
	struct stat st;
	if (jname(name, sizeof(name), job->id, ".lock") < 0)
		return 0;
	int fd = openat(d->st[RUNNING], name,
			O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
	if (fd < 0)
		return 0;
	int free_ = fstat(fd, &st) == 0 &&
		    (!trusted(job, d->owner, (unsigned)st.st_uid) ||
		     flock(fd, LOCK_EX | LOCK_NB) == 0);
	close(fd);
	return free_;
}

static void remove_file(const struct qdir *d, int state, const char *id,
			const char *ext)
{
	char name[GLINT_PATH_MAX];
	if (jname(name, sizeof(name), id, ext) == 0)
		unlinkat(d->st[state], name, 0);
}

static int recover(const struct qdir *d)
{
	struct dirent **names = NULL;
	int moved = 0, n = scan(d, RUNNING, &names);

	for (int i = 0; i < n; i++) {
		struct glint_job job;
		if (load_job(d, RUNNING, names[i]->d_name, &job) < 0)
			continue;
		if (orphaned(d, &job) &&
		    move(d, job.id, RUNNING, PENDING) == 0) {
			moved++;
			remove_file(d, RUNNING, job.id, ".cancel");
		}
		glint_job_release(&job);
	}
	free_names(names, n);
	return moved;
}

int glint_queue_recover(const char *queue)
{
	struct qdir d;
	if (qopen(queue, &d, 0) < 0)
		return 0;
	int moved = recover(&d);
	qclose(&d);
	return moved;
}

/*
 * Lock running/ID.lock for a job about to be claimed.  A lock file owned
 * by someone the job does not trust (planted to hold the job hostage) is
 * removed first; the lock taken must be on a file this process or a
 * trusted user made.
 */
static int lock_job(const struct qdir *d, const char *id, unsigned submitter,
		    int *fd)
{
	char name[GLINT_PATH_MAX];
	struct stat st;
	struct glint_job who = { .uid = submitter };

	*fd = -1;
	if (jname(name, sizeof(name), id, ".lock") < 0)
		return -1;
	if (fstatat(d->st[RUNNING], name, &st, AT_SYMLINK_NOFOLLOW) == 0 &&
	    (!S_ISREG(st.st_mode) || st.st_nlink != 1 ||
	     !trusted(&who, d->owner, (unsigned)st.st_uid))) {
		glint_log_warn("job %s: removing a lock file of uid %u, who "
			       "may not hold it (or a hard link)",
			       id, (unsigned)st.st_uid);
		unlinkat(d->st[RUNNING], name, 0);
	}
	if (glint_lockfile_acquireat(d->st[RUNNING], name, "glint queue worker",
				     0, fd) < 0)
		return -1;
	if (fstat(*fd, &st) < 0 ||
	    !trusted(&who, d->owner, (unsigned)st.st_uid)) {
		glint_lockfile_release(*fd);
		*fd = -1;
		return -1;
	}
	return 0;
}

int glint_queue_claim(const char *queue, struct glint_job *job)
{
	struct dirent **names = NULL;
	struct qdir d;
	int n, got = 0, ret = qopen(queue, &d, 1);

	if (ret < 0)
		return ret;
	recover(&d);
	n = scan(&d, PENDING, &names);
	if (n < 0) {
		int e = errno;
		qclose(&d);
		return glint_error_set(e, "%s/pending: %s", queue, strerror(e));
	}
	for (int i = 0; i < n && !got; i++) {
		char id[256];
		struct stat st;
		id_of(id, sizeof(id), names[i]);
		if (fstatat(d.st[PENDING], names[i]->d_name, &st,
			    AT_SYMLINK_NOFOLLOW) < 0)
			continue; /* taken meanwhile */
		/* Lock first, then claim: a claimed job is never seen
		 * unlocked (which would make it "orphaned"). */
		int fd;
		if (lock_job(&d, id, (unsigned)st.st_uid, &fd) < 0)
			continue;
		ret = move(&d, id, PENDING, RUNNING);
		if (ret < 0) {
			/* Taken by another worker, or (sticky folder) a
			 * job this user may not move: the queue's owner
			 * runs it. */
			remove_file(&d, RUNNING, id, ".lock");
			glint_lockfile_release(fd);
			continue;
		}
		if (load_job(&d, RUNNING, names[i]->d_name, job) == 0) {
			job->lock_fd = fd;
			job->dir_fd = fcntl(d.st[RUNNING], F_DUPFD_CLOEXEC, 0);
			got = 1;
		} else {
			/* Unreadable (a link, bad JSON): failed, not
			 * retried forever. */
			glint_log_warn("job %s: %s", id, glint_error_msg());
			move(&d, id, RUNNING, FAILED);
			glint_lockfile_release(fd);
		}
	}
	free_names(names, n);
	qclose(&d);
	return got;
}

int glint_queue_cancel_requested(const struct glint_job *job)
{
	char name[GLINT_PATH_MAX];
	struct stat st;
	if (job->dir_fd < 0 ||
	    jname(name, sizeof(name), job->id, ".cancel") < 0 ||
	    fstatat(job->dir_fd, name, &st, AT_SYMLINK_NOFOLLOW) < 0)
		return 0;
	/* a hard link carries its target's owner: only a file of one name
	 * is a request */
	if (S_ISREG(st.st_mode) && st.st_nlink == 1 &&
	    trusted(job, job->queue_uid, (unsigned)st.st_uid))
		return 1;
	/* Someone else sharing the queue: not theirs to stop. */
	glint_log_warn("job %s: ignoring a cancel request by uid %u (not its "
		       "submitter, or a hard link: %u names)",
		       job->id, (unsigned)st.st_uid, (unsigned)st.st_nlink);
	unlinkat(job->dir_fd, name, 0);
	return 0;
}

int glint_queue_output(const struct glint_job *job, const char *ext)
{
	char name[GLINT_PATH_MAX];
	int ret = jname(name, sizeof(name), job->id, ext);
	if (ret < 0)
		return ret;
	/* New files only: a link planted in their place (the queue is
	 * shared) is removed, never followed or truncated. */
	unlinkat(job->dir_fd, name, 0);
	int fd = openat(job->dir_fd, name,
			O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
			0600);
	if (fd < 0)
		return glint_error_set(errno, "running/%s: %s", name,
				       strerror(errno));
	return fd;
}

static void drop_files(const struct glint_job *job, int with_json)
{
	static const char *const ext[] = { ".out", ".err", ".cancel", ".json",
					   ".lock" };
	char name[GLINT_PATH_MAX];
	for (int i = 0; i < (with_json ? 5 : 3); i++)
		if (jname(name, sizeof(name), job->id, ext[i]) == 0)
			unlinkat(job->dir_fd, name, 0);
}

void glint_queue_drop_outputs(const struct glint_job *job)
{
	if (job->dir_fd >= 0)
		drop_files(job, 0);
}

int glint_queue_finish(const char *queue, struct glint_job *job,
		       const char *state, json_t *result)
{
	char when[32];
	struct qdir d;
	int s = state_of(state);

	utc_now(when, sizeof(when), 0);
	json_object_set_new(job->doc, "finished", json_string(when));
	json_object_set_new(job->doc, "state", json_string(state));
	if (result)
		json_object_update(job->doc, result);
	json_decref(result);
	int ret = s <= RUNNING ? glint_error_set(EINVAL, "state %s", state)
			       : qopen(queue, &d, 0);
	if (ret == 0) {
		/* a finished record says who submitted the job: the group
		 * reads it, only the worker writes it */
		ret = write_job(d.st[s], job->id, job->doc, 0640);
		qclose(&d);
	}
	if (ret == 0 && job->dir_fd >= 0)
		drop_files(job, 1);
	glint_job_release(job);
	return ret;
}
