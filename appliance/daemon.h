/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_DAEMON_H
#define GLINT_APPLIANCE_DAEMON_H

/*
 * The appliance: wait for the capture button; run the rig file's sequence
 * (lights, turntable, brackets, queue the fit) into a run folder; show
 * idle / busy / done / error on the LED.  A press during a run cancels it;
 * *stop (set by a signal handler) ends the loop with the outputs safe and
 * the current session closed as incomplete.
 *
 * Errors: a negative errno with glint_error_msg() naming the step
 * ("step i/n (name)").  Threads: the loop runs on the caller's thread and
 * watches the button on one of its own during a run; *stop and *cancel
 * may be set from a signal handler.  Who frees: nothing (the loop returns
 * a status).
 */

#include "board/board.h"
#include "appliance/rig.h"
#include "capture/hdr/session.h"

#include <sys/types.h>

/* One run's folders (empty strings for what it did not reach). */
struct glint_rig_run {
	char dir[GLINT_PATH_MAX];    /* OUTPUT/run-STAMP */
	char probe[GLINT_PATH_MAX];  /* its last probe session, or the
				      * reference session that calibrated it */
	char sample[GLINT_PATH_MAX]; /* its last sample session */
	char job[64];		     /* the queued fit's id */
	/* Every sample session, with the lamp it was lit by ("light K"
	 * steps; 0: "lights on").  Several: RUN/run.json names them and
	 * the fit is one joint fit of them all, into RUN/fit. */
	struct glint_run_samples samples;
	char fit_of[GLINT_PATH_MAX]; /* the queued fit writes fit_of/fit */
};

/* Check the rig's camera opens (before any output is touched); logs what
 * it is.  The message names the rig file. */
int glint_rig_check_camera(const struct glint_rig *rig);

/*
 * One run of the sequence into a new folder under rig->output; fits are
 * queued in `queue`.  *cancel (checked between steps and inside brackets
 * and turntable moves) stops it with -ECANCELED.
 */
int glint_rig_run_sequence(const struct glint_rig *rig, struct glint_board *b,
			   const char *queue, atomic_int *cancel,
			   struct glint_rig_run *ro);

/*
 * One capture with the rig (glint capture): with a board, the lights on
 * and the turntable to what is captured first, and the board closed (its
 * outputs safe) after; then glint_capture_run().  The board is busy while
 * the daemon runs: the error says so.
 */
int glint_rig_capture(const struct glint_rig *rig, const char *kind,
		      const char *out, const char *probe, atomic_int *cancel,
		      struct glint_capture_result *res);

struct glint_rig_serve_opts {
	int once; /* return after the first run */
	/* Start a queue worker on rig->output after a run that queued a
	 * fit (may be NULL: the fits wait for someone's worker); returns its
	 * pid or -1.  In once mode the worker is waited for. */
	pid_t (*start_worker)(const char *root, void *ctx);
	void *ctx;
	atomic_int *stop;   /* set by the caller's signal handler */
	atomic_int *cancel; /* likewise; reset at each run's start */
};

/*
 * Serve the button until *stop (returns 0: a clean shutdown) or, in once
 * mode, after one run: 0 when it completed (and its fit, if a worker was
 * started, wrote params.json), else the run's error.  *last gets the last
 * run's folders.  A board error ends it with the outputs safe.  Every
 * error returned has been logged.
 */
int glint_rig_serve(const struct glint_rig *rig, struct glint_board *b,
		    const struct glint_rig_serve_opts *o,
		    struct glint_rig_run *last);

#endif
