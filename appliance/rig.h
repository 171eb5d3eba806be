/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_RIG_H
#define GLINT_APPLIANCE_RIG_H

/*
 * The rig file (docs/rig.md): camera, bracket, ROIs, optics, board lines,
 * the sequence of steps and the output folder, validated whole on load.
 *
 * Errors: -EINVAL (or the read's errno) with glint_error_msg() naming the
 * file and the key.  Threads: a loaded rig is read-only and may be shared.
 * Who frees: glint_rig_free() after glint_rig_load(), also after a
 * failed one.
 */

#include "board/board.h"
#include "capture/run.h"
#include "capture/hdr/session.h"
#include "core/json.h"
#include "core/path.h"

enum glint_rig_step {
	GLINT_RIG_LIGHTS_ON,
	GLINT_RIG_LIGHTS_OFF,
	GLINT_RIG_TURNTABLE_PROBE,
	GLINT_RIG_TURNTABLE_SAMPLE,
	GLINT_RIG_CAPTURE_PROBE,
	GLINT_RIG_CAPTURE_SAMPLE,
	GLINT_RIG_FIT,
	GLINT_RIG_LIGHT_1, /* "light K": lamp K alone on (a rig with lights */
	GLINT_RIG_LIGHT_2, /* on lines of their own, board.lines.lights a */
	GLINT_RIG_LIGHT_3, /* list) */
	GLINT_RIG_LIGHT_4,
	GLINT_RIG_TURNTABLE_REFERENCE, /* the gray ball's own position */
	GLINT_RIG_CAPTURE_REFERENCE,   /* its photo calibrates the probe */
	GLINT_RIG_STEP_COUNT
};
#define GLINT_RIG_MAX_STEPS 32
/* A run's sample captures: each lamp's, fitted jointly. */
#define GLINT_RIG_MAX_SAMPLES GLINT_RUN_MAX_SAMPLES
extern const char *const glint_rig_step_names[GLINT_RIG_STEP_COUNT];

/* A loaded rig file; strings point into doc and live as long as it. */
struct glint_rig {
	char path[GLINT_PATH_MAX];
	json_t *doc;
	const char *output; /* where sessions go */
	/* camera, bracket, ROIs, optics, sample (text: the file itself) */
	struct glint_capture_setup capture;
	int has_board;
	struct glint_board_cfg board;
	enum glint_rig_step steps[GLINT_RIG_MAX_STEPS];
	int nsteps;
};

/* Load and validate; glint_rig_free() after, also on failure. */
int glint_rig_load(const char *path, struct glint_rig *r);
void glint_rig_free(struct glint_rig *r);

#endif
