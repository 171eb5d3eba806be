/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_SESSION_H
#define GLINT_CAPTURE_HDR_SESSION_H

/*
 * A capture session on disk: one directory per capture,
 *   <root>/<kind>-<UTC date>T<time>Z[-n]/
 *     session.json      status: "incomplete" while capturing and when the
 *                       bracket did not finish; "failed" when a stage
 *                       after it (merge, unwrap, scene) refused; and
 *                       "complete" only once every output it promises is
 *                       written and checked (listed in "files"); camera,
 *                       bracket outcome, frame list, the stage and error
 *                       that stopped it if any
 *     rig.json          the rig configuration used
 *     log.txt           one line per event, appended and flushed
 *     frame-NNN.png     raw frames (capture/hdr/frame_file.h), in capture order
 *     frame-NNN.json    each frame's metadata
 * Every file but the log is written whole or not at all (temp + fsync +
 * rename + directory fsync); a frame is on disk before the next is
 * requested, so an interrupted capture keeps every frame it got, and its
 * session.json still says "incomplete".
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (the session folder and the file in it).  Threads:
 * a session is written by one process at a time (its lock); the functions
 * are re-entrant.  Who frees: glint_session_list_free() a listing; a lock
 * with glint_lockfile_release().
 */

#include "capture/camera/bracket.h"
#include "core/error.h"
#include "core/path.h"

#include <jansson.h>

/* The files of a session folder: the one place their names are spelt. */
#define GLINT_SESSION_JSON	     "session.json"
#define GLINT_SESSION_RIG	     "rig.json"
#define GLINT_SESSION_LOG	     "log.txt"
#define GLINT_SESSION_ENV	     "env.exr"	  /* probe: the unwrapped map */
#define GLINT_SESSION_SCENE	     "scene.json" /* sample: what to fit */
#define GLINT_SESSION_SAMPLE	     "sample.exr" /* sample: merged photo */
#define GLINT_SESSION_SAMPLE_WEIGHTS "sample-weights.exr"
#define GLINT_SESSION_FIT	     "fit"	/* the fit's result folder */
#define GLINT_SESSION_FIT_LOCK	     "fit.lock" /* one fit per session */

struct glint_session;

/* Create the directory and its first session.json ("incomplete").  rig
 * may be NULL.  *out is the caller's until glint_session_finish(). */
int glint_session_create(const char *root, const char *kind,
			 const char *rig_json,
			 const struct glint_camera_info *cam,
			 struct glint_session **out);
/* The session's folder: valid until glint_session_finish(s). */
const char *glint_session_dir(const struct glint_session *s);

/* Write frame `index` and add it to session.json. */
int glint_session_add_frame(struct glint_session *s,
			    const struct glint_frame *f, int index);

/* Append a line to log.txt. */
void glint_session_log(struct glint_session *s, const char *fmt, ...)
	GLINT_PRINTF(2, 3);

/*
 * Final session.json, with the bracket's outcome (b may be NULL).  With
 * error NULL: "complete", and `files` (NULL-terminated, may be NULL) the
 * outputs the caller verified are there.  Else the stage that stopped it
 * ("bracket", "merge", "unwrap", "scene", "verify") and the error: status
 * "incomplete" when the capture itself did not finish (stage "bracket" or
 * "camera", or NULL), "failed" when a later stage refused or could not
 * write.  Frees s.
 */
int glint_session_finish(struct glint_session *s, const struct glint_bracket *b,
			 const char *stage, const char *error,
			 const char *const *files);

/* What `glint fit SESSION` fits: a complete sample session's scene,
 * photo, weights ("" when it has none) and result folder, each a path of
 * GLINT_PATH_MAX bytes.  Anything else (a probe session, an incomplete
 * one, one without a scene) is an error saying what it is and what to do:
 * checked when a fit is queued, not when it runs. */
struct glint_session_fit_files {
	char scene[GLINT_PATH_MAX], photo[GLINT_PATH_MAX];
	char weights[GLINT_PATH_MAX], out[GLINT_PATH_MAX];
};
int glint_session_fit_inputs(const char *dir,
			     struct glint_session_fit_files *fs);

/*
 * glint_session_fit_inputs(), then take the session's fit lock (one fit
 * per session at a time): with `wait`, block until another fit is done;
 * without it, fail with -EBUSY saying the session is being fitted.  Once
 * the lock is held, what a killed fit left in the result folder is swept.
 * Returns 1 (lock held) when it waited and the fit it waited for left a
 * whole result (fs->out/params.json written since the wait began), else
 * 0.  *lock is the caller's: release it with glint_lockfile_release().
 */
int glint_session_fit_open(const char *dir, int wait,
			   struct glint_session_fit_files *fs, int *lock);

/* The sessions (folders holding a session.json) in root and one level
 * down (the daemon's run folders), sorted: *list holds *n paths; free it
 * with glint_session_list_free().  A missing root is an empty list. */
int glint_session_list(const char *root, char ***list, int *n);
void glint_session_list_free(char **list, int n);

/* What `glint sessions` shows of a session folder: kind, status ("?"
 * and "unreadable" when its session.json cannot be read), frame count,
 * whether it holds a fit result, and the error it ended with ("" when
 * none).  Never fails: an unreadable session is a row that says so. */
struct glint_session_summary {
	char kind[16], status[16];
	int frames, fitted;
	int run_fitted; /* a sample of a run (run.json) whose joint fit,
			 * RUN/fit, is written */
	char error[256];
};
void glint_session_summarize(const char *dir, struct glint_session_summary *s);

/* The params.json of the session's fit result, or NULL when there is
 * none (or it cannot be read); the caller json_decref()s it. */
json_t *glint_session_fit_params(const char *dir);

/*
 * A rig run (OUTPUT/run-STAMP) that captured the sample under several
 * lamps, one sample session per lamp: RUN/run.json names them (plain
 * folder names inside RUN, in capture order, with each one's lamp), and
 * `glint fit RUN` fits one material to all of them into RUN/fit.
 */
#define GLINT_RUN_JSON	      "run.json"
#define GLINT_RUN_MAX_SAMPLES 16
struct glint_run_samples {
	int n;
	char session[GLINT_RUN_MAX_SAMPLES][GLINT_PATH_MAX]; /* RUN/NAME */
	int light[GLINT_RUN_MAX_SAMPLES]; /* lamp 1.., 0: every lamp */
	char out[GLINT_PATH_MAX];	  /* RUN/fit */
};
/* Write RUN/run.json whole (atomically): sessions are paths inside dir. */
int glint_run_write(const char *dir, const struct glint_run_samples *rs);
/* 1 and *rs when dir holds a run.json; 0 when it holds none; an error
 * naming the file and the entry for a run.json that is not one (a name
 * that is not a plain folder name in dir, too many, none). */
int glint_run_read(const char *dir, struct glint_run_samples *rs);
/* Can `glint fit DIR` fit it: a sample session (glint_session_fit_inputs)
 * or a run whose every sample is one?  The error names what is not. */
int glint_fit_target_check(const char *dir);

#endif
