/* SPDX-License-Identifier: MIT */
#define _DEFAULT_SOURCE
#include "appliance/worker.h"

#include "appliance/queue.h"
#include "core/error.h"
#include "core/log.h"
#include "core/path.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static void nap(double s)
{
	struct timespec ts = { (time_t)s, (long)((s - (time_t)s) * 1e9) };
	nanosleep(&ts, NULL);
}

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

static int run_job(const char *queue, struct glint_job *job, atomic_int *stop)
{
	char self[GLINT_PATH_MAX];

	if (glint_path_self(self, sizeof(self)) < 0)
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", glint_error_msg()));
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
	if (glint_job_session_allowed(queue, job, session, sizeof(session)) < 0)
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", glint_error_msg()));
	int fo = glint_queue_output(job, ".out");
	int fe = fo < 0 ? -1 : glint_queue_output(job, ".err");
	if (fe < 0) {
		if (fo >= 0)
			close(fo);
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", glint_error_msg()));
	}
	glint_log_info("job %s: fitting %s", job->id, job->session);
	pid_t worker = getpid();
	pid_t pid = fork();
	if (pid == 0) {
		/* The fit dies with its worker (SIGTERM when the worker
		 * exits, even by SIGKILL), in a process group of its own,
		 * and holds the job's lock while it lives: no next worker
		 * re-runs a job whose fit is still running. */
		setpgid(0, 0);
		prctl(PR_SET_PDEATHSIG, SIGTERM);
		if (getppid() != worker)
			_exit(127);
		if (job->lock_fd >= 0)
			fcntl(job->lock_fd, F_SETFD, 0);
		if (dup2(fo, 1) < 0 || dup2(fe, 2) < 0)
			_exit(126);
		execl(self, "glint", "fit", "--wait", "--json", "--", session,
		      (char *)NULL);
		_exit(127);
	}
	if (pid > 0)
		setpgid(pid, pid); /* as the child does: no race with kill */
	if (pid < 0) {
		int e = errno;
		close(fo);
		close(fe);
		return glint_queue_finish(
			queue, job, "failed",
			json_pack("{s:s}", "error", strerror(e)));
	}
	int status = 0, cancelled = 0;
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
		nap(0.1);
	}
	json_t *res;
	const char *state;
	if (cancelled == 2) {
		/* The worker is stopping: the job goes back to pending for
		 * the next worker. */
		close(fo);
		close(fe);
		glint_queue_drop_outputs(job);
		glint_job_release(job);
		glint_queue_recover(queue);
		return 0;
	}
	if (cancelled) {
		state = "cancelled";
		res = json_object();
	} else if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
		json_t *doc = lseek(fo, 0, SEEK_SET) == 0
				      ? json_loadfd(fo, 0, NULL)
				      : NULL;
		state = "done";
		/* (json_pack has no optional real: "f*" made the whole
		 * result NULL, and the job kept none of it) */
		res = json_object();
		json_t *pa = json_object_get(doc, "parameters");
		json_t *rr = json_object_get(doc, "relative_rmse");
		json_object_set(res, "parameters", pa ? pa : json_null());
		if (json_is_number(rr))
			json_object_set(res, "relative_rmse", rr);
		json_decref(doc);
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
	return glint_queue_finish(queue, job, state, res);
}

int glint_queue_work(const char *queue, int until_empty, atomic_int *stop)
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
			nap(0.5);
			continue;
		}
		int ret = run_job(queue, &job, stop);
		if (ret < 0)
			return ret;
		ran++;
	}
	return ran;
}
