/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_RIG_CONFIG_H
#define GLINT_CMD_RIG_CONFIG_H

#include "board/board.h"
#include "capture/bracket.h"
#include "core/json.h"

enum rig_step {
	RIG_LIGHTS_ON,
	RIG_LIGHTS_OFF,
	RIG_TURNTABLE_PROBE,
	RIG_TURNTABLE_SAMPLE,
	RIG_CAPTURE_PROBE,
	RIG_CAPTURE_SAMPLE,
	RIG_FIT,
	RIG_STEP_COUNT
};
#define RIG_MAX_STEPS 32
extern const char *const rig_step_names[RIG_STEP_COUNT];

struct rig {
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
	enum rig_step steps[RIG_MAX_STEPS];
	int nsteps;
};

/* Load and validate; rig_free() after, also on failure. */
int rig_load(const char *path, struct rig *r);
void rig_free(struct rig *r);

#endif
