/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_CAPTURE_RUN_H
#define GLINT_CMD_CAPTURE_RUN_H

#include "board/rig.h"

#include <jansson.h>

struct capture_result {
	char session[4096]; /* the session folder ("" if none was made) */
	char scene[4200];   /* a sample's scene.json, "" if none */
	json_t *summary;    /* complete: what glint capture --json prints */
};

/*
 * Capture `kind` ("probe" or "sample") with the rig into a new session
 * under `out`: the bracket (each frame on disk before the next), the
 * session finished complete or incomplete, the merge, and for a probe the
 * unwrap, for a sample the scene lit by `probe` (NULL: the newest probe
 * session under out).  *cancel stops it (-ECANCELED).  The error message
 * names the session kept.
 */
int capture_run(const struct glint_rig *rig, const char *kind, const char *out,
		const char *probe, volatile int *cancel,
		struct capture_result *res);

#endif
