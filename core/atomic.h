/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_ATOMIC_H
#define GLINT_CORE_ATOMIC_H

/*
 * atomic_int for flags shared between threads and signal handlers (cancel,
 * stop), in headers that C++ files (the libcamera backend, bench/hdr)
 * include too: C11's <stdatomic.h> in C, std::atomic_int in C++ (the same
 * lock-free int on every platform glint builds for).
 *
 * Errors: none.  Threads: atomic_int flags may be set from any thread or a
 * signal handler.  Who frees: nothing.
 */
#ifdef __cplusplus
#include <atomic>
using std::atomic_int;
#else
#include <stdatomic.h>
#endif

#endif
