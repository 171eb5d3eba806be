/* SPDX-License-Identifier: MIT */
#define _GNU_SOURCE
#include "appliance/worker.h"

#include "appliance/queue.h"
#include "appliance/session_fit.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"
#include "core/path.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <math.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* The child's error message: the last non-empty line of its stderr, the
 * text of a JSON log line ({"level": ..., "msg": ...}) rather than the
 * line itself. */
static void last_line(int fd, char *out, size_t n)
{
	char line[1024];
	int dup_fd = fcntl(fd, F_DUPFD_CLOEXEC, 0);
	FILE *f = dup_fd < 0 ? NULL : fdopen(dup_fd, "r");
	out[0] = '\0';
	if (!f) {
		if (dup_fd >= 0)
			close(dup_fd);
		return;
	}
	rewind(f);
	while (fgets(line, sizeof(line), f))
		if (line[0] != '\n') {
			line[strcspn(line, "\n")] = '\0';
			snprintf(out, n, "%s", line);
		}
	fclose(f);
	json_t *doc = out[0] == '{' ? json_loads(out, 0, NULL) : NULL;
	const char *msg = json_string_value(json_object_get(doc, "msg"));
	if (msg)
		glint_text(out, n, "%s", msg);
	json_decref(doc);
}

/*
 * The forked child, in the session's folder: the session's fit as glint
 * fit SESSION --wait runs it, through the library (appliance/session_fit.h),
 * its logs as JSON lines into the job's .err file, the result document into
 * .out, and the outcome's values (its json_t pointer cleared) into the pipe.
 * Returns the child's exit status.
 */
static int fit_child(const char *session, int fo, int fe, int pipe_fd)
{
	static struct glint_fit_request req;
	static struct glint_fit_outcome o;
	/* the session is the working folder, opened at the check; its
	 * path only names it in the documents */
	char *args[1] = { (char *)"." };

	if (dup2(fo, 1) < 0 || dup2(fe, 2) < 0)
		return 126;
	glint_log_set_mode(GLINT_LOG_JSON);
	glint_fit_request_init(&req);
	req.args = args;
	req.nargs = 1;
	req.job.shown_dir = session;
	req.wait = 1;
	if (glint_session_fit(&req, &o) < 0) {
		glint_log_error("fit: %s", glint_error_msg());
		fflush(NULL);
		return 1;
	}
	json_dumpf(o.doc, stdout, JSON_INDENT(2));
	fputc('\n', stdout);
	fflush(NULL);
	json_decref(o.doc);
	o.doc = NULL;
	const char *p = (const char *)&o;
	for (size_t done = 0; done < sizeof(o);) {
		ssize_t w = write(pipe_fd, p + done, sizeof(o) - done);
		if (w < 0 && errno == EINTR)
			continue;
		if (w <= 0)
			return 1;
		done += (size_t)w;
	}
	return 0;
}

/*
 * Whose rights a job runs with.  A worker that is not root runs every job
 * as itself (the queue's owner): it can do no more for a submitter than
 * it could do alone.  A worker running as root runs a job as its
 * submitter (the job file's owner, from fstat), with the submitter's
 * groups, never as root: root's reach would otherwise be lent to the
 * submitter (a scene.json naming a root-only file rendered into the
 * submitter's fit/, a session swapped for a link after the check making
 * root write outside the captures root).  Looked up in the worker before
 * the fork; the child only switches.
 */
#define GLINT_JOB_MAX_GROUPS 256

struct job_identity {
	int drop; /* 0: run as the worker */
	uid_t uid;
	gid_t gid;
	gid_t groups[GLINT_JOB_MAX_GROUPS];
	int ngroups;
};

static int job_identity(const struct glint_job *job, struct job_identity *id)
{
	memset(id, 0, sizeof(*id));
	if (geteuid() != 0 || job->uid == 0)
		return 0;
	errno = 0;
	struct passwd *pw = getpwuid((uid_t)job->uid);
	if (!pw)
		return glint_error_set(errno ? errno : ENOENT,
				       "the job's submitter (uid %u) has no "
				       "account: a worker running as root "
				       "runs a job only as its submitter",
				       job->uid);
	id->drop = 1;
	id->uid = pw->pw_uid;
	id->gid = pw->pw_gid;
	id->ngroups = GLINT_JOB_MAX_GROUPS;
	if (getgrouplist(pw->pw_name, pw->pw_gid, id->groups, &id->ngroups) < 0)
		return glint_error_set(E2BIG,
				       "the job's submitter %s is in more than "
				       "%d groups",
				       pw->pw_name, GLINT_JOB_MAX_GROUPS);
	return 0;
}

/* In the child: become the submitter, irrevocably (all three ids), or
 * fail. */
static int become(const struct job_identity *id)
{
	if (!id->drop)
		return 0;
	uid_t r, e, s;
	if (setgroups((size_t)id->ngroups, id->groups) < 0 ||
	    setresgid(id->gid, id->gid, id->gid) < 0 ||
	    setresuid(id->uid, id->uid, id->uid) < 0)
		return -errno;
	if (getresuid(&r, &e, &s) < 0 || r != id->uid || e != id->uid ||
	    s != id->uid || setresuid(0, 0, 0) == 0)
		return -EPERM;
	return 0;
}

/* The child's outcome, whole, from the pipe (after it exited). */
static int read_outcome(int fd, struct glint_fit_outcome *o)
{
	char *p = (char *)o;
	size_t done = 0;
	while (done < sizeof(*o)) {
		ssize_t r = read(fd, p + done, sizeof(*o) - done);
		if (r < 0 && errno == EINTR)
			continue;
		if (r <= 0)
			return -EIO;
		done += (size_t)r;
	}
	o->doc = NULL;
	return 0;
}

static int run_job(const char *queue, struct glint_job *job, atomic_int *stop,
		   const struct glint_clock *clock)
{
	/* A job file is data: its session must be an absolute path (as
	 * glint queue add writes it), and it is passed after "--", so it
	 * can never be taken for an option. */
	char session[GLINT_PATH_MAX];
	if (strcmp(job->kind, "fit") || job->session[0] != '/')
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error",
				  "bad job: expected kind \"fit\" and an "
				  "absolute session path"));
	/* The session is opened once, here, where it is checked; the fit
	 * runs beneath that descriptor (its working folder), so a path
	 * swapped for a link after the check leads it nowhere else. */
	int sfd = glint_job_session_open(queue, job, session, sizeof(session));
	if (sfd < 0)
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", glint_error_msg()));
	int fo = glint_queue_output(job, ".out");
	int fe = fo < 0 ? -1 : glint_queue_output(job, ".err");
	struct job_identity who;
	if (fe < 0 || job_identity(job, &who) < 0) {
		if (fo >= 0)
			close(fo);
		if (fe >= 0)
			close(fe);
		close(sfd);
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", glint_error_msg()));
	}
	if (who.drop)
		glint_log_info("job %s: fitting %s as uid %u", job->id,
			       job->session, (unsigned)who.uid);
	else
		glint_log_info("job %s: fitting %s", job->id, job->session);
	/* The child's outcome comes back as values through a pipe. */
	int pfd[2];
	if (pipe2(pfd, O_CLOEXEC) < 0) {
		int e = errno;
		close(sfd);
		close(fo);
		close(fe);
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", strerror(e)));
	}
	pid_t worker = getpid();
	pid_t pid = fork();
	if (pid == 0) {
		/* The fit dies with its worker (SIGTERM when the worker
		 * exits, even by SIGKILL), in a process group of its own,
		 * and holds the job's lock (inherited) while it lives: no
		 * next worker re-runs a job whose fit is still running. */
		setpgid(0, 0);
		/* The worker's handlers (a flag to stop after this job)
		 * are not the fit's: SIGTERM ends it. */
		signal(SIGTERM, SIG_DFL);
		signal(SIGINT, SIG_DFL);
		signal(SIGHUP, SIG_DFL);
		close(pfd[0]);
		int e = become(&who);
		if (e < 0) {
			dprintf(fe, "cannot run the job as uid %u: %s\n",
				(unsigned)who.uid, strerror(-e));
			_exit(126);
		}
		/* After the switch: a change of credentials clears the
		 * parent-death signal. */
		prctl(PR_SET_PDEATHSIG, SIGTERM);
		if (getppid() != worker)
			_exit(127);
		if (fchdir(sfd) < 0) {
			dprintf(fe, "session %s: %s\n", session,
				strerror(errno));
			_exit(126);
		}
		_exit(fit_child(session, fo, fe, pfd[1]));
	}
	close(sfd);
	close(pfd[1]);
	if (pid > 0)
		setpgid(pid, pid); /* as the child does: no race with kill */
	if (pid < 0) {
		int e = errno;
		close(fo);
		close(fe);
		close(pfd[0]);
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", strerror(e)));
	}
	int status = 0, cancelled = 0;
	static struct glint_fit_outcome outcome;
	struct rusage ru;
	memset(&ru, 0, sizeof(ru));
	for (;;) {
		/* wait4: the fit's own peak memory, for the job's record */
		pid_t w = wait4(pid, &status, WNOHANG, &ru);
		if (w == pid || (w < 0 && errno != EINTR))
			break;
		if (!cancelled &&
		    (*stop || glint_queue_cancel_requested(job))) {
			cancelled = 1 + (*stop != 0);
			kill(-pid, SIGTERM);
		}
		glint_clock_sleep(clock, 0.1);
	}
	json_t *res;
	const char *state;
	if (cancelled == 2) {
		/* The worker is stopping: the job goes back to pending for
		 * the next worker. */
		close(fo);
		close(fe);
		close(pfd[0]);
		glint_queue_drop_outputs(job);
		glint_job_release(job);
		glint_queue_recover(queue);
		return 0;
	}
	if (cancelled) {
		state = "cancelled";
		res = json_object();
	} else if (WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
		   read_outcome(pfd[0], &outcome) == 0) {
		state = "done";
		res = json_object();
		json_object_set_new(res, "parameters",
				    glint_fit_outcome_parameters(&outcome));
		if (isfinite(outcome.relative_rmse))
			json_object_set_new(res, "relative_rmse",
					    json_real(outcome.relative_rmse));
	} else {
		char msg[1024];
		last_line(fe, msg, sizeof(msg));
		state = "failed";
		res = json_pack("{s:s, s:i}", "error",
				msg[0] ? msg : "glint fit failed", "exit",
				WIFEXITED(status) ? WEXITSTATUS(status)
						  : 128 + WTERMSIG(status));
	}
	double peak_mib = ru.ru_maxrss / 1024.0; /* kB */
	if (res && ru.ru_maxrss > 0)
		json_object_set_new(res, "peak_rss_mib", json_real(peak_mib));
	if (ru.ru_maxrss > 0)
		glint_log_info("job %s: %s (the fit's peak memory %.0f MiB)",
			       job->id, state, peak_mib);
	else
		glint_log_info("job %s: %s", job->id, state);
	close(fo);
	close(fe);
	close(pfd[0]);
	return glint_queue_finish(queue, job, state, res);
}

int glint_queue_work(const char *queue, int until_empty, atomic_int *stop,
		     const struct glint_clock *clock)
{
	int ran = 0;
	int r = glint_queue_recover(queue);
	if (r > 0)
		glint_log_info("%d job(s) of a worker that died put back in "
			       "the queue",
			       r);
	while (!*stop) {
		struct glint_job job;
		int got = glint_queue_claim(queue, &job);
		if (got < 0)
			return got;
		if (!got) {
			if (until_empty)
				break;
			glint_clock_sleep(clock, 0.5);
			continue;
		}
		int ret = run_job(queue, &job, stop, clock);
		if (ret < 0)
			return ret;
		ran++;
	}
	return ran;
}
