/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "parallel.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

#define GLINT_MAX_THREADS 256

struct pfor {
	atomic_int next;
	int n, chunk;
	glint_range_fn fn;
	void *ctx;
};

struct worker {
	struct pfor *job;
	int index;
};

static void *worker_main(void *arg)
{
	struct worker *w = arg;
	struct pfor *job = w->job;

	for (;;) {
		int b = atomic_fetch_add(&job->next, job->chunk);
		if (b >= job->n)
			break;
		int e = b + job->chunk < job->n ? b + job->chunk : job->n;
		job->fn(job->ctx, b, e, w->index);
	}
	return NULL;
}

int glint_cpu_count(void)
{
	long n = sysconf(_SC_NPROCESSORS_ONLN);
	return n > 0 ? (int)n : 1;
}

void glint_thread_ftz(void)
{
#if defined(__SSE__) || defined(__x86_64__)
	_MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
	_MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

int glint_parallel_for(int n, int chunk, int nthreads, glint_range_fn fn,
		       void *ctx)
{
	struct pfor job = {
		.n = n, .chunk = chunk > 0 ? chunk : 1, .fn = fn, .ctx = ctx
	};
	pthread_t tid[GLINT_MAX_THREADS];
	struct worker w[GLINT_MAX_THREADS];
	int started = 0, ret = 0;

	atomic_init(&job.next, 0);
	if (nthreads <= 0)
		nthreads = glint_cpu_count();
	if (nthreads > GLINT_MAX_THREADS)
		nthreads = GLINT_MAX_THREADS;
	for (int i = 1; i < nthreads; i++) {
		w[i].job = &job;
		w[i].index = i;
		if (pthread_create(&tid[i], NULL, worker_main, &w[i]) != 0) {
			ret = -EAGAIN;
			break;
		}
		started = i;
	}
	w[0].job = &job;
	w[0].index = 0;
	worker_main(&w[0]);
	for (int i = 1; i <= started; i++)
		pthread_join(tid[i], NULL);
	return ret;
}
