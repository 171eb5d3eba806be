/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_WORKER_H
#define GLINT_APPLIANCE_WORKER_H

#include "core/atomic.h"

/*
 * A queue worker: claim jobs (appliance/queue.h) and run each as a child
 * `glint fit SESSION --wait --json` (so one session is fitted by one
 * process at a time whoever queued it), until *stop, or until the queue
 * is empty when until_empty.  A cancel request stops the child (SIGTERM).
 * Returns the number of jobs run, or a negative error.
 */
int glint_queue_work(const char *queue, int until_empty, atomic_int *stop);

#endif
