/* SPDX-License-Identifier: MIT */
#ifndef GLINT_BOARD_RIG_H
#define GLINT_BOARD_RIG_H

#include "board.h"
#include "capture/bracket.h"
#include "core/json.h"

enum glint_rig_step {
	GLINT_RIG_LIGHTS_ON,
	GLINT_RIG_LIGHTS_OFF,
	GLINT_RIG_TURNTABLE_PROBE,
	GLINT_RIG_TURNTABLE_SAMPLE,
	GLINT_RIG_CAPTURE_PROBE,
	GLINT_RIG_CAPTURE_SAMPLE,
	GLINT_RIG_FIT,
	GLINT_RIG_STEP_COUNT
};
#define GLINT_RIG_MAX_STEPS 32
extern const char *const glint_rig_step_names[GLINT_RIG_STEP_COUNT];

struct glint_rig {
	char path[4096];
	json_t *doc;
	char *text;
	const char *backend, *device, *output;
	struct glint_bracket_opts bracket;
	struct glint_roi roi[2];       /* probe, sample */
	double focal_px, principal[2]; /* optics; 0 = not given */
	double pitch_um;	       /* optics.pixel_pitch_um */
	double diameter_m;	       /* sample.diameter_m */
	int has_board;
	struct glint_board_cfg board;
	enum glint_rig_step steps[GLINT_RIG_MAX_STEPS];
	int nsteps;
};

/* Load and validate; glint_rig_free() after, also on failure. */
int glint_rig_load(const char *path, struct glint_rig *r);
void glint_rig_free(struct glint_rig *r);

#endif
