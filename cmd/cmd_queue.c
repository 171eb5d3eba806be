/* SPDX-License-Identifier: MIT */
/*
 * glint queue add|cancel|run, glint jobs, glint sessions: the job queue
 * (appliance/queue.h) and the capture sessions, as plain commands for SSH
 * users and the rig daemon alike.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"
#include "appliance/worker.h"
#include "appliance/rig.h"

#include "appliance/queue.h"
#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/log.h"

#include <signal.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The options every queue command takes to find the captures folder. */
static void root_options(void)
{
	printf("  --root DIR       the captures folder (default: the rig "
	       "file's \"output\")\n"
	       "  --config FILE    rig file to take the root from (default: "
	       "/etc/glint/rig.json\n"
	       "                   installed, data/rig-sim.json from a "
	       "build folder)\n");
}

static void queue_help_footer(void)
{
	printf("  --json           JSON on stdout\n"
	       "  -q, --quiet      no info messages\n"
	       "\nExit status: 0 done, 1 refused (named), 2 bad command "
	       "line.\n");
}

static void add_help(void)
{
	printf("usage: glint queue add SESSION [--root DIR]\n"
	       "\n"
	       "Queue a fit of a sample session (glint fit SESSION --wait, "
	       "run by a worker).\nWhat the fit needs is checked now: a probe "
	       "session, an incomplete one, one\nwithout a scene, or one "
	       "already pending or running (the job named) is\nrefused.  "
	       "Prints the job's id; the job file's owner is its submitter.\n"
	       "\n");
	root_options();
	queue_help_footer();
}

static void cancel_help(void)
{
	printf("usage: glint queue cancel ID [--root DIR]\n"
	       "\n"
	       "Cancel a job: a pending one is moved to cancelled, a running "
	       "one is stopped by\nits worker (its fit's process group gets "
	       "SIGTERM).  Only the job's submitter\n(or the queue's owner, or "
	       "root) may cancel it.\n"
	       "\n");
	root_options();
	queue_help_footer();
}

static void run_help(void)
{
	printf("usage: glint queue run [--until-empty] [--root DIR]\n"
	       "\n"
	       "A worker: fits the queued sessions one at a time, oldest "
	       "first, forever or\nuntil the queue is empty.  Any number of "
	       "workers share a queue safely; a\nworker that dies leaves its "
	       "job to be re-run by the next.\n"
	       "\n");
	root_options();
	printf("  --until-empty    stop when no job is left\n");
	queue_help_footer();
}

void cmd_queue_help(void)
{
	printf("usage: glint queue add SESSION [--root DIR]\n"
	       "       glint queue cancel ID [--root DIR]\n"
	       "       glint queue run [--until-empty] [--root DIR]\n"
	       "\n"
	       "The job queue shared by the rig daemon and SSH users, a folder "
	       "ROOT/queue that\nany number of processes use safely (no "
	       "server).  glint jobs lists the queue;\nglint sessions the "
	       "capture sessions.\n"
	       "\n"
	       "subcommands (glint queue SUB --help: its options):\n"
	       "  add        queue a fit of a sample session\n"
	       "  cancel     cancel a pending job, or stop a running one\n"
	       "  run        a worker: fit queued sessions one at a time\n"
	       "\n");
	root_options();
	printf("  --until-empty    run: stop when no job is left\n");
	queue_help_footer();
}

void cmd_jobs_help(void)
{
	printf("usage: glint jobs [--root DIR] [--json]\n"
	       "\n"
	       "The fit queue (glint queue): each job's id, state (pending, "
	       "running, done,\nfailed, cancelled), kind, submitter (the "
	       "job file's owner) and session, and\na failed job's error.  "
	       "--json: the queue folder and each job's record.\n"
	       "\n");
	root_options();
	printf("  --json           JSON on stdout\n"
	       "  -q, --quiet      no info messages\n");
}

void cmd_sessions_help(void)
{
	printf("usage: glint sessions [--root DIR] [--json]\n"
	       "\n"
	       "The capture sessions under the captures folder: each one's "
	       "kind (probe or\nsample), frames, status, whether it (or its "
	       "run) has been fitted, and a\nfailed one's error.  --json: "
	       "one array of them.\n"
	       "\n");
	root_options();
	printf("  --json           JSON on stdout\n"
	       "  -q, --quiet      no info messages\n");
}

struct qopts {
	char root[4096], queue[4200];
	int json, until_empty;
	int nargs; /* the positional arguments */
	char **args;
	int status; /* the exit status when parse() returns -1 */
};

static int parse(const char *cmd, void (*help)(void), int argc, char **argv,
		 struct qopts *q)
{
	const char *root = NULL, *config = NULL;
	char def[4096];

	memset(q, 0, sizeof(*q));
	const struct cmd_opt opts[] = {
		CMD_STRING("root", 0, &root),
		CMD_STRING("config", 0, &config),
		CMD_FLAG("until-empty", 0, &q->until_empty),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse(cmd, help, opts, argc, argv, &a);
	if (r) {
		q->status = cmd_options_exit(r);
		return -1;
	}
	q->json = a.json;
	q->nargs = a.argc;
	q->args = a.argv;
	if (!root) {
		struct glint_rig rig;
		config = cmd_rig_config(def, sizeof(def), config);
		if (glint_rig_load(config, &rig) < 0) {
			glint_rig_free(&rig);
			q->status = cmd_fail(cmd);
			return -1;
		}
		snprintf(q->root, sizeof(q->root), "%s", rig.output);
		glint_rig_free(&rig);
	} else {
		snprintf(q->root, sizeof(q->root), "%s", root);
	}
	snprintf(q->queue, sizeof(q->queue), "%s/queue", q->root);
	return 0;
}

static int print_job(const struct glint_job *j, void *ctx)
{
	json_t *arr = ctx;
	/* The submitter is the job file's owner, never what it says. */
	struct passwd *pw = getpwuid((uid_t)j->uid);
	char user[32];
	if (pw)
		snprintf(user, sizeof(user), "%s", pw->pw_name);
	else
		snprintf(user, sizeof(user), "%u", j->uid);
	if (arr) {
		json_t *d = json_deep_copy(j->doc);
		json_object_set_new(d, "state", json_string(j->state));
		json_object_set_new(d, "submitter", json_string(user));
		json_object_set_new(d, "submitter_uid", json_integer(j->uid));
		json_array_append_new(arr, d);
		return 0;
	}
	const char *err = json_string_value(json_object_get(j->doc, "error"));
	/* the job file's words are another user's: shown, never obeyed by
	 * the terminal */
	char id[4 * sizeof(j->id)], sess[4 * GLINT_PATH_MAX], e[1024];
	printf("%-34s %-9s %-4s %-10s %s%s%s\n",
	       glint_text_printable(j->id, id, sizeof(id)), j->state, j->kind,
	       user, glint_text_printable(j->session, sess, sizeof(sess)),
	       err ? "  -- " : "",
	       glint_text_printable(err ? err : "", e, sizeof(e)));
	return 0;
}

int cmd_jobs(int argc, char **argv)
{
	struct qopts q;
	if (parse("jobs", cmd_jobs_help, argc, argv, &q) < 0)
		return q.status;
	if (q.nargs != 0)
		return cmd_usage_error("jobs", "unexpected argument '%s'",
				       q.args[0]);
	json_t *arr = q.json ? json_array() : NULL;
	if (!q.json)
		printf("%-34s %-9s %-4s %-10s %s\n", "ID", "STATE", "KIND",
		       "USER", "SESSION");
	if (glint_queue_list(q.queue, print_job, arr) < 0) {
		json_decref(arr);
		return cmd_fail("jobs");
	}
	if (arr)
		cmd_print_json(
			json_pack("{s:s, s:o}", "queue", q.queue, "jobs", arr));
	return GLINT_EXIT_OK;
}

int cmd_sessions(int argc, char **argv)
{
	struct qopts q;
	char **list = NULL;
	int n = 0;
	if (parse("sessions", cmd_sessions_help, argc, argv, &q) < 0)
		return q.status;
	if (q.nargs != 0)
		return cmd_usage_error("sessions", "unexpected argument '%s'",
				       q.args[0]);
	if (glint_session_list(q.root, &list, &n) < 0)
		return cmd_fail("sessions");
	json_t *arr = json_array();
	if (!q.json)
		printf("%-9s %-6s %-11s %-5s %s\n", "KIND", "FRAMES", "STATUS",
		       "FIT", "SESSION");
	for (int i = 0; i < n; i++) {
		struct glint_session_summary ss;
		char name[4 * GLINT_PATH_MAX], e[4 * sizeof(ss.error)];
		glint_session_summarize(list[i], &ss);
		if (q.json)
			json_array_append_new(
				arr,
				json_pack("{s:s, s:s, s:s, s:i, s:b, "
					  "s:b, s:s*}",
					  "session", list[i], "kind", ss.kind,
					  "status", ss.status, "frames",
					  ss.frames, "fitted", ss.fitted,
					  "run_fitted", ss.run_fitted, "error",
					  ss.error[0] ? ss.error : NULL));
		else
			printf("%-9s %6d %-11s %-5s %s%s%s\n", ss.kind,
			       ss.frames, ss.status,
			       ss.fitted       ? "yes"
			       : ss.run_fitted ? "run"
					       : "-",
			       glint_text_printable(list[i], name,
						    sizeof(name)),
			       ss.error[0] ? "  -- " : "",
			       glint_text_printable(ss.error, e, sizeof(e)));
	}
	glint_session_list_free(list, n);
	if (q.json)
		cmd_print_json(json_pack("{s:s, s:o}", "root", q.root,
					 "sessions", arr));
	else
		json_decref(arr);
	return GLINT_EXIT_OK;
}

static atomic_int stop_worker;

static void on_stop(int sig)
{
	(void)sig;
	stop_worker = 1;
}

int cmd_queue(int argc, char **argv)
{
	struct qopts q;

	if (argc < 2 || argv[1][0] == '-') {
		if (argc >= 2 &&
		    (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help"))) {
			cmd_queue_help();
			return GLINT_EXIT_OK;
		}
		return cmd_usage_error("queue", "expected add, cancel or run");
	}
	static const char *const subs[] = { "add", "cancel", "run", NULL };
	if (strcmp(argv[1], "add") && strcmp(argv[1], "cancel") &&
	    strcmp(argv[1], "run")) {
		cmd_choice_error(argv[1], subs);
		return cmd_usage_error("queue", "'%s': %s", argv[1],
				       glint_error_msg());
	}
	const char *what = argv[1];
	char name[32];
	snprintf(name, sizeof(name), "queue %s", argv[1]);
	void (*help)(void) = !strcmp(what, "add")      ? add_help
			     : !strcmp(what, "cancel") ? cancel_help
						       : run_help;
	if (parse(name, help, argc - 1, argv + 1, &q) < 0)
		return q.status;
	int nargs = q.nargs;
	char **args = q.args;
	if (!strcmp(what, "add")) {
		char id[64];
		if (nargs != 1)
			return cmd_usage_error(name, "expected SESSION");
		/* What a fit of it needs, checked now rather than when
		 * the job runs: a probe session, an incomplete one or one
		 * without a scene is refused with the reason. */
		if (glint_fit_target_check(args[0]) < 0)
			return cmd_fail("queue");
		if (glint_queue_add(q.queue, "fit", args[0], id) < 0)
			return cmd_fail("queue");
		if (q.json)
			cmd_print_json(json_pack("{s:s}", "id", id));
		else
			printf("%s\n", id);
		return GLINT_EXIT_OK;
	}
	if (!strcmp(what, "cancel")) {
		if (nargs != 1)
			return cmd_usage_error(name, "expected ID");
		int was_running = glint_queue_cancel(q.queue, args[0]);
		if (was_running < 0)
			return cmd_fail("queue");
		if (q.json)
			cmd_print_json(json_pack(
				"{s:s,s:s}", "id", args[0], "cancelled",
				was_running ? "running (its worker stops it)"
					    : "pending"));
		else
			printf("cancelled %s job %s%s\n",
			       was_running ? "running" : "pending", args[0],
			       was_running ? " (its worker stops the fit)"
					   : "");
		return GLINT_EXIT_OK;
	}
	if (!strcmp(what, "run")) {
		struct sigaction sa;
		if (nargs != 0)
			return cmd_usage_error(name, "unexpected argument '%s'",
					       args[0]);
		memset(&sa, 0, sizeof(sa));
		sa.sa_handler = on_stop;
		sigaction(SIGINT, &sa, NULL);
		sigaction(SIGTERM, &sa, NULL);
		int done = glint_queue_work(q.queue, q.until_empty,
					    &stop_worker, NULL);
		if (done < 0)
			return cmd_fail("queue");
		return GLINT_EXIT_OK;
	}
	return cmd_usage_error("queue",
			       "'%s': expected add, cancel or run (glint jobs "
			       "lists the queue)",
			       what);
}
