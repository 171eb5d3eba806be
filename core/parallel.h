/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_PARALLEL_H
#define GLINT_CORE_PARALLEL_H

/*
 * fn(ctx, begin, end, thread) is called on disjoint ranges covering [0, n)
 * in chunks of `chunk`, from `nthreads` threads (0 = one per online CPU).
 * Returns 0 or a negative errno if threads could not be started (the work
 * is then done on the calling thread).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected when a worker thread cannot start.  Threads: the
 * callback runs on up to n threads at once and must only write its own
 * range.  Who frees: nothing.
 */
typedef void (*glint_range_fn)(void *ctx, int begin, int end, int thread);

int glint_parallel_for(int n, int chunk, int nthreads, glint_range_fn fn,
		       void *ctx);

/* Online CPUs (at least 1). */
int glint_cpu_count(void);

/* Flush-to-zero and denormals-are-zero for this thread (Embree asks it). */
void glint_thread_ftz(void);

#endif
