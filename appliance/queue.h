/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_QUEUE_H
#define GLINT_APPLIANCE_QUEUE_H

/*
 * The job queue shared by the rig daemon and SSH users: a directory, safe
 * for any number of processes without a server.
 *
 *   QUEUE/pending/ID.json     waiting, oldest ID first
 *   QUEUE/running/ID.json     claimed by a worker (an atomic rename), which
 *   QUEUE/running/ID.lock     holds this flock while it works
 *   QUEUE/running/ID.cancel   asks that worker to stop
 *   QUEUE/done/ID.json        finished, with its result
 *   QUEUE/failed/ID.json      finished with an error
 *   QUEUE/cancelled/ID.json
 *
 *   QUEUE/running/ID.out|err  the fit's output while it runs
 *
 * Job files are written whole (temp, fsync, rename).  Every file is
 * opened relative to its folder, never through a link; new state folders
 * are sticky, and a lock or cancel request made by someone other than the
 * job's submitter, the queue's owner or root is ignored, so users sharing
 * a queue (group glint) cannot steer each other's jobs.  A worker that dies
 * (SIGKILL, power cut) leaves running/ID.json with no lock held: the next
 * claim puts it back in pending/, so it is re-run with no manual clean-up.
 * IDs sort by time added: "YYYYmmddTHHMMSSZ-PID-N".
 *
 * Errors: a negative errno with glint_error_msg() naming the file.
 * Threads: a claimed job (struct glint_job) belongs to one thread; the
 * queue itself is shared through the file system only.  Who frees: a
 * claimed job is finished (glint_queue_finish) or released
 * (glint_job_release) by its claimer.
 */

#include "core/path.h"

#include <jansson.h>

struct glint_job {
	char id[64];
	char state[16]; /* pending, running, done, failed, cancelled */
	char kind[16];	/* "fit" */
	char session[GLINT_PATH_MAX];
	json_t *doc;	    /* the job file */
	int lock_fd;	    /* running: the worker's lock */
	int dir_fd;	    /* running: the running/ folder it was claimed in */
	unsigned uid;	    /* the submitter: the job file's owner, never
			     * what the file says */
	unsigned queue_uid; /* the queue folder's owner */
};

/* Create QUEUE and its folders if missing. */
int glint_queue_init(const char *queue);

/* Add a job (kind "fit" on a session inside the captures root, the
 * folder holding QUEUE); *id (may be NULL, >= 64 bytes) gets its ID. */
int glint_queue_add(const char *queue, const char *kind, const char *session,
		    char *id);

/* Every job, oldest first, each state in turn; cb returns nonzero to
 * stop.  job->doc is valid during the call. */
int glint_queue_list(const char *queue,
		     int (*cb)(const struct glint_job *job, void *ctx),
		     void *ctx);

/* Cancel a pending job (moved to cancelled/: returns 0) or ask a running
 * one's worker to stop (returns 1).  -ENOENT names the ID if it is in no
 * such state; -EPERM if the caller is not its submitter, the queue's
 * owner or root. */
int glint_queue_cancel(const char *queue, const char *id);

/* Put jobs whose worker died back in pending/; returns how many. */
int glint_queue_recover(const char *queue);

/* Claim the oldest pending job: 1 with *job (running, locked), 0 when
 * none. */
int glint_queue_claim(const char *queue, struct glint_job *job);

/* Has its submitter (or the queue's owner) asked the claimed job to
 * stop?  A request by anyone else is removed and ignored. */
int glint_queue_cancel_requested(const struct glint_job *job);

/* A new file running/ID`ext` for a claimed job's output (a file or link
 * already there is removed, never followed), open read-write; fd or -1. */
int glint_queue_output(const struct glint_job *job, const char *ext);

/* Remove a claimed job's output files and cancel request. */
void glint_queue_drop_outputs(const struct glint_job *job);

/* Move a claimed job to done/, failed/ or cancelled/ with `result` (an
 * object merged into the job file; consumed) and release it. */
int glint_queue_finish(const char *queue, struct glint_job *job,
		       const char *state, json_t *result);

void glint_job_release(struct glint_job *job);

/*
 * May this job's submitter have its session fitted?  Into `real` (size n,
 * at least GLINT_PATH_MAX) the session's resolved path, which must be a
 * folder inside the captures root (the folder holding QUEUE; links are
 * resolved, so none leads out) and owned by the submitter or shared with
 * it (group-writable, a group it is in); a run's samples too, each a
 * folder in the run.  Returns the folder opened (O_DIRECTORY, close on
 * exec), the checks made on it rather than on its path: the fit then
 * works beneath that descriptor, and a path swapped for a link after the
 * check leads it nowhere else.  -EPERM/-ENOENT with the reason.
 */
int glint_job_session_open(const char *queue, const struct glint_job *job,
			   char *real, size_t n);

#endif
