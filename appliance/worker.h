/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_WORKER_H
#define GLINT_APPLIANCE_WORKER_H

#include "core/atomic.h"
#include "core/clock.h"

/*
 * A queue worker: claim jobs (appliance/queue.h) and run each in a forked
 * child that calls glint_session_fit() (appliance/session_fit.h) as
 * `glint fit SESSION --wait` would (so one session is fitted by one
 * process at a time whoever queued it; the child's outcome comes back as
 * values through a pipe), until *stop, or until the queue is empty when
 * until_empty.  A cancel request stops the child (SIGTERM to its process
 * group).  Returns the number of jobs run, or a negative error.
 *
 * Its polls (a child's end, a new job) sleep on `clock` (NULL: the real
 * one, core/clock.h), borrowed for the call.
 *
 * Errors: a negative errno with glint_error_msg() naming the queue or
 * job (a job's own failure is its record, not the worker's error).
 * Threads: call from a process with no other threads (the child is
 * forked and runs the fit without exec).  Who frees: nothing.
 */
int glint_queue_work(const char *queue, int until_empty, atomic_int *stop,
		     const struct glint_clock *clock);

#endif
