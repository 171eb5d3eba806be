/* SPDX-License-Identifier: MIT */
/*
 * The appliance's state machine: idle (LED idle) -> a press -> a run of
 * the rig file's steps (LED busy; a press cancels) -> done or error ->
 * idle.  The fit itself runs in a queue worker (appliance/worker.c).
 */
#define _POSIX_C_SOURCE 200809L
#include "appliance/daemon.h"

#include "appliance/queue.h"
#include "capture/run.h"
#include "capture/scene_file.h"
#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/log.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>

int glint_rig_check_camera(const struct glint_rig *rig)
{
	struct glint_camera *cam;
	struct glint_camera_info in;
	int ret = glint_camera_open(rig->capture.backend, rig->capture.device,
				    NULL, &cam);
	if (ret < 0)
		return glint_error_prefix(ret, "%s: camera", rig->path);
	glint_camera_describe(cam, &in);
	glint_camera_close(cam);
	glint_log_info("camera: %s (%s), %dx%d", in.name, in.backend, in.width,
		       in.height);
	return 0;
}

int glint_rig_capture(const struct glint_rig *rig, const char *kind,
		      const char *out, const char *probe, atomic_int *cancel,
		      struct glint_capture_result *res)
{
	struct glint_board *board = NULL;
	char found[GLINT_PATH_MAX];
	int ref = !strcmp(kind, "reference"), ret = 0;

	memset(res, 0, sizeof(*res));
	if (ref && !(rig->capture.ref_albedo > 0))
		return glint_error_set(EINVAL,
				       "%s: no \"reference\" section (the gray "
				       "ball's albedo): nothing to capture as "
				       "a reference",
				       rig->path);
	if (ref && !rig->capture.ref_own)
		return glint_error_set(EINVAL,
				       "%s: the gray ball is in the probe's "
				       "photo (reference.roi): the probe's "
				       "capture calibrates its map; a "
				       "reference capture is for a gray ball "
				       "at its own turntable position (no "
				       "reference.roi)",
				       rig->path);
	if (ref && !probe) {
		ret = glint_session_latest_probe(out, found, sizeof(found));
		probe = found;
		if (ret < 0)
			return glint_error_prefix(ret,
						  "a reference calibrates a "
						  "probe (capture the probe "
						  "first, or --probe SESSION)");
	}
	if (ret == 0 && rig->has_board) {
		ret = glint_board_open(&rig->board, "glint capture", &board);
		if (ret == 0)
			ret = glint_board_lights(board, 1);
		if (ret == 0)
			ret = glint_board_turntable(board,
						    ref ? GLINT_TT_AT_REFERENCE
						    : !strcmp(kind, "sample")
							    ? GLINT_TT_AT_SAMPLE
							    : GLINT_TT_AT_PROBE,
						    cancel);
	}
	if (ret == 0)
		ret = glint_capture_run(&rig->capture, kind, out, probe, cancel,
					res);
	glint_board_close(board);
	return ret;
}

/* OUTPUT/run-STAMP[-k], made. */
static int make_run_dir(const char *output, char *dir, size_t n)
{
	char stamp[32];
	time_t t = time(NULL);
	struct tm tm;
	int ret;

	gmtime_r(&t, &tm);
	strftime(stamp, sizeof(stamp), "%Y%m%dT%H%M%SZ", &tm);
	if (mkdir(output, 0777) < 0 && errno != EEXIST)
		return glint_error_set(errno, "%s: %s", output,
				       strerror(errno));
	ret = glint_path_fmt(dir, n, "%s/run-%s", output, stamp);
	for (int k = 1; ret == 0 && mkdir(dir, 0777) < 0; k++) {
		if (errno != EEXIST || k > 99)
			return glint_error_set(errno, "%s: %s", dir,
					       strerror(errno));
		ret = glint_path_fmt(dir, n, "%s/run-%s-%d", output, stamp, k);
	}
	return ret;
}

/* The gray ball at its own position: this run's last probe calibrated
 * into the reference session, which lights the samples after it. */
static int reference_step(const struct glint_rig *rig, atomic_int *cancel,
			  struct glint_rig_run *ro)
{
	struct glint_capture_result res;
	if (!ro->probe[0])
		return glint_error_set(EINVAL,
				       "%s: sequence: \"capture reference\" "
				       "before \"capture probe\"",
				       rig->path);
	int ret = glint_capture_run(&rig->capture, "reference", ro->dir,
				    ro->probe, cancel, &res);
	json_decref(res.summary);
	if (ret == 0)
		snprintf(ro->probe, sizeof(ro->probe), "%s", res.session);
	return ret;
}

/* A sample is lit by this run's last probe (or the reference that
 * calibrated it), captured under the same lamps. */
static int capture_step(const struct glint_rig *rig, int probe, int light,
			atomic_int *cancel, struct glint_rig_run *ro)
{
	struct glint_capture_result res;
	int ret = glint_capture_run(
		&rig->capture, probe ? "probe" : "sample", ro->dir,
		!probe && ro->probe[0] ? ro->probe : NULL, cancel, &res);

	snprintf(probe ? ro->probe : ro->sample, sizeof(ro->probe), "%s",
		 res.session);
	json_decref(res.summary);
	if (ret == 0 && !probe && !res.scene[0])
		ret = glint_error_set(EINVAL,
				      "the sample was captured but has no "
				      "scene.json (see the warning above)");
	struct glint_run_samples *rs = &ro->samples;
	if (ret < 0 || probe || rs->n == GLINT_RUN_MAX_SAMPLES)
		return ret;
	snprintf(rs->session[rs->n], sizeof(rs->session[0]), "%s", ro->sample);
	rs->light[rs->n++] = light;
	/* several: the run says which sessions belong together */
	return rs->n > 1 ? glint_run_write(ro->dir, rs) : 0;
}

static int fit_step(const struct glint_rig *rig, const char *queue,
		    struct glint_rig_run *ro)
{
	if (!ro->sample[0])
		return glint_error_set(EINVAL,
				       "%s: sequence: \"fit\" before "
				       "\"capture sample\"",
				       rig->path);
	int joint = ro->samples.n > 1;
	snprintf(ro->fit_of, sizeof(ro->fit_of), "%s",
		 joint ? ro->dir : ro->sample);
	int ret = glint_queue_add(queue, "fit", ro->fit_of, ro->job);
	if (ret == 0 && joint)
		glint_log_info("fit queued: job %s, one material from the %d "
			       "samples' photos",
			       ro->job, ro->samples.n);
	else if (ret == 0)
		glint_log_info("fit queued: job %s", ro->job);
	return ret;
}

int glint_rig_run_sequence(const struct glint_rig *rig, struct glint_board *b,
			   const char *queue, atomic_int *cancel,
			   struct glint_rig_run *ro)
{
	memset(ro, 0, sizeof(*ro));
	int ret = make_run_dir(rig->output, ro->dir, sizeof(ro->dir));
	int light = 0; /* the lamp that is on alone, 0: all or none */
	if (ret < 0)
		return ret;
	glint_log_info("run %s", ro->dir);
	for (int i = 0; i < rig->nsteps && ret == 0; i++) {
		enum glint_rig_step s = rig->steps[i];
		if (*cancel)
			return glint_error_set(ECANCELED, "run cancelled");
		glint_log_info("step %d/%d: %s", i + 1, rig->nsteps,
			       glint_rig_step_names[s]);
		switch (s) {
		case GLINT_RIG_LIGHTS_ON:
		case GLINT_RIG_LIGHTS_OFF:
			light = 0;
			ret = glint_board_lights(b, s == GLINT_RIG_LIGHTS_ON);
			break;
		case GLINT_RIG_LIGHT_1:
		case GLINT_RIG_LIGHT_2:
		case GLINT_RIG_LIGHT_3:
		case GLINT_RIG_LIGHT_4:
			light = (int)(s - GLINT_RIG_LIGHT_1) + 1;
			ret = glint_board_light_only(b, light);
			break;
		case GLINT_RIG_TURNTABLE_PROBE:
		case GLINT_RIG_TURNTABLE_SAMPLE:
		case GLINT_RIG_TURNTABLE_REFERENCE:
			ret = glint_board_turntable(
				b,
				s == GLINT_RIG_TURNTABLE_SAMPLE
					? GLINT_TT_AT_SAMPLE
				: s == GLINT_RIG_TURNTABLE_REFERENCE
					? GLINT_TT_AT_REFERENCE
					: GLINT_TT_AT_PROBE,
				cancel);
			break;
		case GLINT_RIG_CAPTURE_REFERENCE:
			ret = reference_step(rig, cancel, ro);
			break;
		case GLINT_RIG_CAPTURE_PROBE:
		case GLINT_RIG_CAPTURE_SAMPLE:
			ret = capture_step(rig, s == GLINT_RIG_CAPTURE_PROBE,
					   light, cancel, ro);
			break;
		case GLINT_RIG_FIT:
			ret = fit_step(rig, queue, ro);
			break;
		default:
			break;
		}
		if (ret < 0)
			glint_error_prefix(ret, "step %d/%d (%s)", i + 1,
					   rig->nsteps,
					   glint_rig_step_names[s]);
	}
	return ret;
}

/* The button during a run: a press cancels it. */
struct watcher {
	struct glint_board *board;
	atomic_int done;
	atomic_int *cancel;
	int pressed;
};

static void *watch_button(void *arg)
{
	struct watcher *w = arg;
	while (!w->done && !*w->cancel) {
		int r = glint_board_wait_press(w->board, 0.2, &w->done);
		if (r == 1) {
			w->pressed = 1;
			*w->cancel = 1;
			glint_log_info("button pressed during the run: "
				       "cancelling");
			break;
		}
		if (r < 0)
			break;
	}
	return NULL;
}

/* One run with the button watched; the LED and outputs left as the
 * outcome says. */
static int one_run(const struct glint_rig *rig, struct glint_board *b,
		   const char *queue, const struct glint_rig_serve_opts *o,
		   struct glint_rig_run *ro)
{
	struct watcher w = { .board = b, .cancel = o->cancel };
	pthread_t th;

	glint_log_info("button pressed: starting a run");
	glint_board_led(b, GLINT_LED_BUSY);
	*o->cancel = 0;
	int watching = pthread_create(&th, NULL, watch_button, &w) == 0;
	int ret = glint_rig_run_sequence(rig, b, queue, o->cancel, ro);
	w.done = 1;
	if (watching)
		pthread_join(th, NULL);
	if (ret == 0) {
		glint_board_led(b, GLINT_LED_DONE);
		glint_log_info("run complete: %s", ro->dir);
		return 0;
	}
	/* Whatever stopped it, the outputs go safe. */
	glint_board_safe(b);
	if (w.pressed || *o->stop) {
		glint_log_info("run cancelled (%s); sessions kept as "
			       "incomplete in %s",
			       w.pressed ? "button" : "signal", ro->dir);
		glint_board_led(b, GLINT_LED_IDLE);
	} else {
		glint_log_error("run failed: %s", glint_error_msg());
		glint_board_led(b, GLINT_LED_ERROR);
	}
	return ret;
}

/* Once mode: the worker's fit must have written its result. */
static int fit_written(const struct glint_rig *rig,
		       const struct glint_rig_run *ro)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	int ret = glint_path_fmt(path, sizeof(path), "%s/%s/params.json",
				 ro->fit_of, GLINT_SESSION_FIT);
	if (ret == 0 && stat(path, &st) < 0)
		ret = glint_error_set(EIO,
				      "the fit of %s failed (glint jobs "
				      "--root %s says why)",
				      ro->fit_of, rig->output);
	return ret;
}

int glint_rig_serve(const struct glint_rig *rig, struct glint_board *b,
		    const struct glint_rig_serve_opts *o,
		    struct glint_rig_run *last)
{
	char queue[GLINT_PATH_MAX];
	pid_t wpid = -1;
	int ret = glint_path_join(queue, sizeof(queue), rig->output, "queue");

	memset(last, 0, sizeof(*last));
	if (ret < 0)
		return ret;
	glint_board_led(b, GLINT_LED_IDLE);
	glint_log_info("ready: waiting for the capture button (%s board)",
		       rig->board.backend);
	while (!*o->stop) {
		if (wpid > 0 && waitpid(wpid, NULL, WNOHANG) == wpid)
			wpid = -1;
		int r = glint_board_wait_press(b, 0.5, o->stop);
		if (r < 0) {
			glint_log_error("%s", glint_error_msg());
			glint_board_safe(b);
			glint_board_led(b, GLINT_LED_ERROR);
			return r;
		}
		if (r == 0)
			continue;
		ret = one_run(rig, b, queue, o, last);
		if (ret == 0 && last->job[0] && o->start_worker && wpid < 0)
			wpid = o->start_worker(rig->output, o->ctx);
		if (!o->once)
			continue;
		while (wpid > 0 && waitpid(wpid, NULL, 0) < 0 && errno == EINTR)
			;
		if (ret == 0 && last->job[0] && o->start_worker &&
		    (ret = fit_written(rig, last)) < 0)
			glint_log_error("%s", glint_error_msg());
		return ret;
	}
	glint_log_info("stopping: outputs safe, board released");
	return 0;
}
