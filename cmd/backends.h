/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_BACKENDS_H
#define GLINT_CMD_BACKENDS_H

/*
 * The backends this program offers, real and simulated: cameras (sim,
 * V4L2, libcamera) and boards (sim, libgpiod), registered with capture/
 * and board/.  Called once at start by glint, and by the tests and benches
 * that open cameras or boards by name.
 *
 * Errors: none.  Threads: call once, before any other thread starts.  Who
 * frees: nothing (the lists are static).
 */
#ifdef __cplusplus
extern "C" {
#endif

void glint_backends_register(void);

#ifdef __cplusplus
}
#endif

#endif
