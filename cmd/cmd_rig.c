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
#include "capture_run.h"
#include "cmd.h"
#include "queue_worker.h"
#include "board/rig.h"

#include "board/board.h"
#include "board/queue.h"
#include "capture/camera.h"
#include "core/error.h"
#include "core/log.h"

#include <errno.h>
#include <getopt.h>
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
	       "sample, capture the sample, lights off, fit) into\n"
	       "OUTPUT/run-<UTC time>/ (a probe and a sample session), queues "
	       "the fit\n(OUTPUT/queue, see glint queue) and starts a worker "
	       "for it.  The status LED\nshows idle (a short blink every 2 s), "
	       "busy (4 Hz), done (steady) or error\n(three quick blinks).  A "
	       "second press during a run cancels it; SIGTERM or\nCtrl-C stops "
	       "the daemon cleanly: lights off, stepper disabled, the session\n"
	       "being captured kept as incomplete.  Without --config: the "
	       "simulated rig\n(data/rig-sim.json: sim camera and board, one "
	       "scripted press).\n"
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
	       "\n"
	       "Check a rig file without capturing: every key, the camera "
	       "(opened and\ndescribed), every GPIO line (its chip present, "
	       "the line in range and free,\nthen requested and released with "
	       "outputs left off).  Exit 0 when all is well,\n1 naming the "
	       "first problem.\n");
}

static volatile sig_atomic_t stop_flag;
static volatile int cancel_flag;

static void on_signal(int sig)
{
	(void)sig;
	stop_flag = 1;
	cancel_flag = 1;
}

/* The camera must be there before any output is touched. */
static int check_camera(const struct glint_rig *rig)
{
	struct glint_camera *cam;
	struct glint_camera_info in;
	int ret = glint_camera_open(rig->backend, rig->device, NULL, &cam);
	if (ret < 0)
		return glint_error_prefix(ret, "%s: camera", rig->path);
	glint_camera_describe(cam, &in);
	glint_camera_close(cam);
	glint_log_info("camera: %s (%s), %dx%d", in.name, in.backend, in.width,
		       in.height);
	return 0;
}

/* The button during a run: a press cancels it. */
struct watcher {
	struct glint_board *board;
	volatile int done;
	int pressed;
};

static void *watch_button(void *arg)
{
	struct watcher *w = arg;
	while (!w->done && !cancel_flag) {
		int r = glint_board_wait_press(w->board, 0.2, &w->done);
		if (r == 1) {
			w->pressed = 1;
			cancel_flag = 1;
			glint_log_info("button pressed during the run: "
				       "cancelling");
			break;
		}
		if (r < 0)
			break;
	}
	return NULL;
}

struct run_out {
	char dir[4200];
	char probe[4096], sample[4096];
	char job[64];
};

static int run_sequence(const struct glint_rig *rig, struct glint_board *b,
			const char *queue, struct run_out *ro)
{
	char stamp[32];
	time_t t = time(NULL);
	struct tm tm;
	int ret = 0;

	gmtime_r(&t, &tm);
	strftime(stamp, sizeof(stamp), "%Y%m%dT%H%M%SZ", &tm);
	memset(ro, 0, sizeof(*ro));
	mkdir(rig->output, 0777);
	snprintf(ro->dir, sizeof(ro->dir), "%s/run-%s", rig->output, stamp);
	for (int k = 1; mkdir(ro->dir, 0777) < 0; k++) {
		if (errno != EEXIST || k > 99)
			return glint_error_set(errno, "%s: %s", ro->dir,
					       strerror(errno));
		snprintf(ro->dir, sizeof(ro->dir), "%s/run-%s-%d", rig->output,
			 stamp, k);
	}
	glint_log_info("run %s", ro->dir);
	for (int i = 0; i < rig->nsteps && ret == 0; i++) {
		enum glint_rig_step s = rig->steps[i];
		if (cancel_flag) {
			ret = glint_error_set(ECANCELED, "run cancelled");
			break;
		}
		glint_log_info("step %d/%d: %s", i + 1, rig->nsteps,
			       glint_rig_step_names[s]);
		switch (s) {
		case GLINT_RIG_LIGHTS_ON:
		case GLINT_RIG_LIGHTS_OFF:
			ret = glint_board_lights(b, s == GLINT_RIG_LIGHTS_ON);
			break;
		case GLINT_RIG_TURNTABLE_PROBE:
		case GLINT_RIG_TURNTABLE_SAMPLE:
			ret = glint_board_turntable(
				b, s == GLINT_RIG_TURNTABLE_SAMPLE,
				&cancel_flag);
			break;
		case GLINT_RIG_CAPTURE_PROBE:
		case GLINT_RIG_CAPTURE_SAMPLE: {
			struct capture_result res;
			int probe = s == GLINT_RIG_CAPTURE_PROBE;
			ret = capture_run(rig, probe ? "probe" : "sample",
					  ro->dir, NULL, &cancel_flag, &res);
			snprintf(probe ? ro->probe : ro->sample,
				 sizeof(ro->probe), "%s", res.session);
			json_decref(res.summary);
			if (ret == 0 && !probe && !res.scene[0])
				ret = glint_error_set(
					EINVAL,
					"the sample was captured but has no "
					"scene.json (see the warning above)");
			break;
		}
		case GLINT_RIG_FIT:
			if (!ro->sample[0]) {
				ret = glint_error_set(EINVAL,
						      "%s: sequence: \"fit\" "
						      "before \"capture "
						      "sample\"",
						      rig->path);
				break;
			}
			ret = glint_queue_add(queue, "fit", ro->sample,
					      ro->job);
			if (ret == 0)
				glint_log_info("fit queued: job %s", ro->job);
			break;
		default:
			break;
		}
	}
	return ret;
}

static pid_t start_worker(const char *root)
{
	char self[4096];
	ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
	if (n <= 0)
		return -1;
	self[n] = '\0';
	pid_t pid = fork();
	if (pid == 0) {
		const char *mode = glint_log_get_mode() == GLINT_LOG_JSON
					   ? "--json"
				   : glint_log_get_mode() == GLINT_LOG_QUIET
					   ? "-q"
					   : "--until-empty";
		execl(self, "glint", "queue", "run", "--until-empty", "--root",
		      root, mode, (char *)NULL);
		_exit(127);
	}
	return pid;
}

static void print_result(const struct run_out *ro, int json)
{
	char path[4300];
	snprintf(path, sizeof(path), "%s/fit/params.json", ro->sample);
	json_t *doc = json_load_file(path, 0, NULL);
	if (json) {
		cmd_print_json(json_pack("{s:s, s:s, s:s, s:s, s:o*}", "run",
					 ro->dir, "probe", ro->probe, "sample",
					 ro->sample, "job", ro->job, "fit",
					 doc));
		return;
	}
	printf("rig: one press, run %s\n  probe:  %s\n  sample: %s\n", ro->dir,
	       ro->probe, ro->sample);
	if (doc) {
		printf("  fit (job %s): relative RMSE %.4f\n", ro->job,
		       json_real_value(json_object_get(doc, "relative_rmse")));
		cmd_print_params(doc, NULL);
		printf("  results: %s/fit/params.json, render.exr, "
		       "compare.png\n",
		       ro->sample);
		json_decref(doc);
	}
}

int cmd_rig(int argc, char **argv)
{
	enum { O_CONFIG = 256, O_ONCE, O_JSON, O_NOWORKER };
	static const struct option opts[] = {
		{ "config", required_argument, NULL, O_CONFIG },
		{ "once", no_argument, NULL, O_ONCE },
		{ "no-worker", no_argument, NULL, O_NOWORKER },
		{ "json", no_argument, NULL, O_JSON },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *config = NULL;
	char path[4096], queue[4200];
	int once = 0, json = 0, worker = 1, c, ret;

	optind = 1;
	while ((c = getopt_long(argc, argv, "qh", opts, NULL)) != -1) {
		switch (c) {
		case O_CONFIG:
			config = optarg;
			break;
		case O_ONCE:
			once = 1;
			break;
		case O_NOWORKER:
			worker = 0;
			break;
		case O_JSON:
			json = 1;
			glint_log_set_mode(GLINT_LOG_JSON);
			break;
		case 'q':
			glint_log_set_mode(GLINT_LOG_QUIET);
			break;
		case 'h':
			cmd_rig_help();
			return GLINT_EXIT_OK;
		default:
			return GLINT_EXIT_USAGE;
		}
	}
	if (optind != argc)
		return cmd_usage_error("rig", "unexpected argument '%s'",
				       argv[optind]);
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
		ret = check_camera(&rig);
	if (ret == 0)
		ret = glint_board_open(&rig.board, "glint rig", &board);
	if (ret < 0) {
		glint_rig_free(&rig);
		return cmd_fail("rig");
	}
	snprintf(queue, sizeof(queue), "%s/queue", rig.output);

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);

	pid_t wpid = -1;
	int status = GLINT_EXIT_OK, runs = 0;
	glint_board_led(board, GLINT_LED_IDLE);
	glint_log_info("ready: waiting for the capture button (%s board)",
		       rig.board.backend);
	while (!stop_flag) {
		if (wpid > 0 && waitpid(wpid, NULL, WNOHANG) == wpid)
			wpid = -1;
		int r = glint_board_wait_press(board, 0.5,
					       (volatile int *)&stop_flag);
		if (r < 0) {
			glint_log_error("%s", glint_error_msg());
			glint_board_safe(board);
			glint_board_led(board, GLINT_LED_ERROR);
			status = GLINT_EXIT_FAIL;
			break;
		}
		if (r == 0)
			continue;
		glint_log_info("button pressed: starting a run");
		glint_board_led(board, GLINT_LED_BUSY);
		cancel_flag = 0;
		struct watcher w = { board, 0, 0 };
		pthread_t th;
		int watching = pthread_create(&th, NULL, watch_button, &w) == 0;
		struct run_out ro;
		ret = run_sequence(&rig, board, queue, &ro);
		w.done = 1;
		if (watching)
			pthread_join(th, NULL);
		runs++;
		if (ret < 0) {
			/* Whatever stopped it, the outputs go safe. */
			glint_board_safe(board);
			if (w.pressed || stop_flag) {
				glint_log_info("run cancelled (%s); sessions "
					       "kept as incomplete in %s",
					       w.pressed ? "button" : "signal",
					       ro.dir);
				glint_board_led(board, GLINT_LED_IDLE);
			} else {
				glint_log_error("run failed: %s",
						glint_error_msg());
				glint_board_led(board, GLINT_LED_ERROR);
			}
			status = GLINT_EXIT_FAIL;
		} else {
			glint_board_led(board, GLINT_LED_DONE);
			glint_log_info("run complete: %s", ro.dir);
			status = GLINT_EXIT_OK;
			if (ro.job[0] && worker && wpid < 0)
				wpid = start_worker(rig.output);
		}
		if (once) {
			if (wpid > 0) {
				while (waitpid(wpid, NULL, 0) < 0 &&
				       errno == EINTR) {
				}
				wpid = -1;
			}
			if (status == GLINT_EXIT_OK && ro.job[0]) {
				char fit[4300];
				struct stat st;
				snprintf(fit, sizeof(fit), "%s/fit/params.json",
					 ro.sample);
				if (worker && stat(fit, &st) < 0) {
					glint_log_error("the fit of %s failed "
							"(glint jobs --root "
							"%s says why)",
							ro.sample, rig.output);
					status = GLINT_EXIT_FAIL;
				}
			}
			if (status == GLINT_EXIT_OK)
				print_result(&ro, json);
			break;
		}
	}
	if (stop_flag) {
		glint_log_info("stopping: outputs safe, board released");
		status = GLINT_EXIT_OK; /* a clean shutdown */
	}
	glint_board_close(board);
	glint_rig_free(&rig);
	(void)runs;
	return status;
}

int cmd_check_rig(int argc, char **argv)
{
	enum { O_CONFIG = 256, O_JSON };
	static const struct option opts[] = {
		{ "config", required_argument, NULL, O_CONFIG },
		{ "json", no_argument, NULL, O_JSON },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *config = NULL;
	char path[4096];
	int json = 0, c, ret;

	optind = 1;
	while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
		switch (c) {
		case O_CONFIG:
			config = optarg;
			break;
		case O_JSON:
			json = 1;
			glint_log_set_mode(GLINT_LOG_JSON);
			break;
		case 'h':
			cmd_check_rig_help();
			return GLINT_EXIT_OK;
		default:
			return GLINT_EXIT_USAGE;
		}
	}
	if (optind != argc)
		return cmd_usage_error("check-rig", "unexpected argument '%s'",
				       argv[optind]);
	cmd_rig_config(path, sizeof(path), config);
	struct glint_rig rig;
	struct glint_board *board = NULL;
	ret = glint_rig_load(path, &rig);
	if (ret == 0)
		ret = check_camera(&rig);
	if (ret == 0 && rig.has_board) {
		ret = glint_board_open(&rig.board, "glint check-rig", &board);
		if (ret == 0) {
			int n = 0;
			for (int r = 0; r < GLINT_ROLE_COUNT; r++)
				n += rig.board.lines[r].used;
			glint_log_info(
				"board (%s): %d line(s) present and free",
				rig.board.backend, n);
		}
		glint_board_close(board);
	}
	glint_rig_free(&rig);
	if (ret < 0)
		return cmd_fail("check-rig");
	if (json)
		cmd_print_json(json_pack("{s:s, s:b}", "rig", path, "ok", 1));
	else
		printf("%s: ok\n", path);
	return GLINT_EXIT_OK;
}
