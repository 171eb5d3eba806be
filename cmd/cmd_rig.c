/* SPDX-License-Identifier: MIT */
/*
 * glint rig: the appliance.  Waits for the capture button; runs the rig
 * file's sequence (lights, turntable, brackets) into a run folder; queues
 * the fit and starts a queue worker; shows idle / busy / done / error on
 * the LED.  A press during a run cancels it; SIGTERM stops cleanly
 * (outputs safe, the current session closed as incomplete).
 * glint check-rig: the rig file, its camera and its GPIO lines, checked
 * without capturing.
 */
#define _GNU_SOURCE /* pthread_timedjoin_np not used; strsignal */
#include "capture/run.h"
#include "cmd.h"
#include "options.h"
#include "appliance/daemon.h"
#include "appliance/rig.h"
#include "appliance/udev.h"

#include "board/board.h"
#include "appliance/queue.h"
#include "capture/camera/camera.h"
#include "capture/hdr/session.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/output.h"
#include "core/path.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

void cmd_rig_help(void)
{
	printf("usage: glint rig [--config RIG.json] [--once] [options]\n"
	       "\n"
	       "The capture rig's daemon.  It waits for the capture button, "
	       "then runs the rig\nfile's sequence (default: lights on, "
	       "turntable to the probe, capture the\nprobe, turntable to the "
	       "sample, capture the sample, lights off, fit; with a\nlamp on "
	       "each of several lines, that for each lamp alone, and one "
	       "joint fit of\nevery photo) into "
	       "OUTPUT/run-<UTC time>/ (a probe and a sample session\nper "
	       "lamp), queues the fit (OUTPUT/queue, see glint queue) and "
	       "starts a worker\n"
	       "for it.  The status LED shows idle (a short blink every 2 s), "
	       "busy (4 Hz),\ndone (steady) or error (three quick blinks).  A "
	       "second press during a run\ncancels it; SIGTERM or Ctrl-C "
	       "stops the daemon cleanly: lights off, stepper\ndisabled, the "
	       "session being captured kept as incomplete.  Without --config: "
	       "the installed\nappliance's /etc/glint/rig.json, or, run from "
	       "a build folder, the simulated\nrig (data/rig-sim.json: sim "
	       "camera and board, one scripted press).\n"
	       "\n"
	       "  --config FILE   rig file (docs/rig.md)\n"
	       "  --once          handle one press, wait for its fit, print "
	       "the result, exit\n"
	       "  --no-worker     queue fits but leave them to other workers\n"
	       "  --json          logs as JSON lines on stderr (for "
	       "journald), result on stdout\n"
	       "  -q, --quiet     no info messages\n"
	       "\nExit status: 0 stopped cleanly (--once: the run and its fit "
	       "succeeded),\n1 bad rig or a failed run (--once), 2 bad "
	       "command line.\n");
}

void cmd_check_rig_help(void)
{
	printf("usage: glint check-rig [--config RIG.json] [--json]\n"
	       "       glint check-rig --udev-rules FILE [--group G] "
	       "[--force]\n"
	       "\n"
	       "Check a rig file without capturing: every key, the camera "
	       "(opened and\ndescribed), every GPIO line (its chip present, "
	       "the line in range and free,\nthen requested and released with "
	       "outputs left off).  Exit 0 when all is well,\n1 naming the "
	       "first problem.\n"
	       "\n"
	       "  --config RIG.json    the rig file (default: the installed "
	       "one, else the\n"
	       "                       simulated rig)\n"
	       "  --udev-rules FILE    once checked, write a udev rules file "
	       "(- for stdout)\n"
	       "                       giving the devices' group read-write "
	       "access to this rig's\n"
	       "                       camera and GPIO chips and no other "
	       "device (docs/rig.md);\n"
	       "                       install it as "
	       "/etc/udev/rules.d/70-glint.rules\n"
	       "  --group G            that group (default glint-dev)\n"
	       "  --force              replace a rules file glint wrote\n");
}

static atomic_int stop_flag, cancel_flag;

static void on_signal(int sig)
{
	(void)sig;
	stop_flag = 1;
	cancel_flag = 1;
}

static pid_t start_worker(const char *root, void *ctx)
{
	(void)ctx;
	char self[GLINT_PATH_MAX];
	if (glint_path_self(self, sizeof(self)) < 0)
		return -1;
	pid_t pid = fork();
	if (pid == 0) {
		const char *mode =
			glint_log_get_mode() == GLINT_LOG_JSON ? "--json"
			: glint_log_get_verbosity() < 0	       ? "-q"
							: "--until-empty";
		execl(self, "glint", "queue", "run", "--until-empty", "--root",
		      root, mode, (char *)NULL);
		_exit(127);
	}
	return pid;
}

static void print_result(const struct glint_rig_run *ro, int json)
{
	const struct glint_run_samples *rs = &ro->samples;
	json_t *doc =
		ro->fit_of[0] ? glint_session_fit_params(ro->fit_of) : NULL;
	if (json) {
		json_t *samples = json_array();
		for (int k = 0; k < rs->n; k++)
			json_array_append_new(samples,
					      json_pack("{s:s, s:i}", "session",
							rs->session[k], "light",
							rs->light[k]));
		cmd_print_json(json_pack("{s:s, s:s, s:s, s:o, s:s, s:o*}",
					 "run", ro->dir, "probe", ro->probe,
					 "sample", ro->sample, "samples",
					 samples, "job", ro->job, "fit", doc));
		return;
	}
	printf("rig: one press, run %s\n", ro->dir);
	if (rs->n > 1)
		for (int k = 0; k < rs->n; k++)
			printf("  sample under light %d: %s\n", rs->light[k],
			       rs->session[k]);
	else
		printf("  probe:  %s\n  sample: %s\n", ro->probe, ro->sample);
	if (doc) {
		printf("  fit (job %s%s): relative RMSE %.4f\n", ro->job,
		       rs->n > 1 ? ", one material from every light's photo"
				 : "",
		       json_real_value(json_object_get(doc, "relative_rmse")));
		cmd_print_params(doc, NULL);
		cmd_print_verdicts(doc);
		printf("  results: %s/fit/report.html, params.json, "
		       "render.exr, compare.png%s\n",
		       ro->fit_of,
		       rs->n > 1 ? " (render-K.exr, compare-K.png: photo K)"
				 : "");
		json_decref(doc);
	}
}

int cmd_rig(int argc, char **argv)
{
	const char *config = NULL;
	char path[GLINT_PATH_MAX];
	int once = 0, noworker = 0, ret;
	const struct cmd_opt opts[] = {
		CMD_STRING("config", 0, &config),
		CMD_FLAG("once", 0, &once),
		CMD_FLAG("no-worker", 0, &noworker),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("rig", cmd_rig_help, opts, argc, argv, &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json, worker = !noworker;
	if (a.argc != 0)
		return cmd_usage_error("rig", "unexpected argument '%s'",
				       a.argv[0]);
	cmd_rig_config(path, sizeof(path), config);

	struct glint_rig rig;
	struct glint_board *board = NULL;
	ret = glint_rig_load(path, &rig);
	if (ret == 0 && !rig.has_board)
		ret = glint_error_set(EINVAL,
				      "%s: no \"board\" section: the daemon "
				      "needs at least the capture button "
				      "(docs/rig.md)",
				      path);
	if (ret == 0)
		ret = glint_rig_check_camera(&rig);
	if (ret == 0)
		ret = glint_board_open(&rig.board, "glint rig", &board);
	if (ret < 0) {
		glint_rig_free(&rig);
		return cmd_fail("rig");
	}
	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);

	struct glint_rig_serve_opts so = {
		.once = once,
		.start_worker = worker ? start_worker : NULL,
		.stop = &stop_flag,
		.cancel = &cancel_flag,
	};
	struct glint_rig_run ro;
	ret = glint_rig_serve(&rig, board, &so, &ro);
	if (ret == 0 && once && !stop_flag)
		print_result(&ro, json);
	glint_board_close(board);
	glint_rig_free(&rig);
	/* A signal is a clean shutdown, whatever it interrupted. */
	return ret < 0 && !stop_flag ? GLINT_EXIT_FAIL : GLINT_EXIT_OK;
}

/* The udev rules for the rig (appliance/udev.h) into `out`, by the one
 * overwrite rule ("-": stdout). */
static int write_rules(const struct glint_rig *rig,
		       const struct glint_board *board, const char *group,
		       const char *out, int force, const char *rig_path)
{
	char *text = NULL;
	const char *inputs[] = { rig_path, NULL };
	int ret = glint_udev_rules(rig, board, group, &text);

	if (ret == 0 && !strcmp(out, "-")) {
		fputs(text, stdout);
	} else if (ret == 0) {
		ret = glint_output_check(out, force, inputs);
		if (ret == 0)
			ret = glint_atomic_write_file(out, text, strlen(text));
		if (ret == 0)
			glint_log_info("udev rules for this rig's devices: %s "
				       "(udevadm control --reload; udevadm "
				       "trigger)",
				       out);
	}
	free(text);
	return ret;
}

int cmd_check_rig(int argc, char **argv)
{
	const char *config = NULL, *rules = NULL, *group = "glint-dev";
	char path[4096];
	int ret, force = 0;
	const struct cmd_opt opts[] = {
		CMD_STRING("config", 0, &config),
		CMD_STRING("udev-rules", 0, &rules),
		CMD_STRING("group", 0, &group),
		CMD_FLAG("force", 0, &force),
		{ 0 },
	};
	struct cmd_args a;
	int pr = cmd_options_parse("check-rig", cmd_check_rig_help, opts, argc,
				   argv, &a);
	if (pr)
		return cmd_options_exit(pr);
	int json = a.json;
	if (a.argc != 0)
		return cmd_usage_error("check-rig", "unexpected argument '%s'",
				       a.argv[0]);
	cmd_rig_config(path, sizeof(path), config);
	struct glint_rig rig;
	struct glint_board *board = NULL;
	json_t *lines = NULL; /* role -> where the board found it */
	ret = glint_rig_load(path, &rig);
	if (ret == 0)
		ret = glint_rig_check_camera(&rig);
	if (ret == 0 && rig.has_board) {
		ret = glint_board_open(&rig.board, "glint check-rig", &board);
		if (ret == 0) {
			int n = 0;
			lines = json_object();
			for (int r = 0; r < GLINT_ROLE_COUNT; r++) {
				char where[160];
				if (!rig.board.lines[r].used)
					continue;
				n++;
				glint_board_locate(board, r, where,
						   sizeof(where));
				glint_log_info("  %s: %s%s", glint_role_name(r),
					       where,
					       rig.board.lines[r].active_low
						       ? ", active low"
						       : "");
				json_object_set_new(lines, glint_role_name(r),
						    json_string(where));
			}
			glint_log_info(
				"board (%s): %d line(s) present and free",
				rig.board.backend, n);
		}
	}
	if (ret == 0 && rules)
		ret = write_rules(&rig, board, group, rules, force, path);
	glint_board_close(board);
	glint_rig_free(&rig);
	if (ret < 0) {
		json_decref(lines);
		return cmd_fail("check-rig");
	}
	if (json)
		cmd_print_json(json_pack("{s:s, s:b, s:o}", "rig", path, "ok",
					 1, "lines",
					 lines ? lines : json_object()));
	else if (!rules || strcmp(rules, "-"))
		printf("%s: ok\n", path);
	if (!json)
		json_decref(lines);
	return GLINT_EXIT_OK;
}
