/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_WORLD_H
#define GLINT_SIM_WORLD_H

/*
 * The simulated rig's physical state, shared in-process between the sim
 * board (which changes it: lights, turntable) and the sim camera's
 * "scene=rig" (which photographs it).  Without a sim board open, the
 * lights are on and the probe is in view.
 *
 * The lab has up to GLINT_MAX_LIGHTS lamps, each on its own relay; lamp k
 * lights the scene with the rig's map turned about +Y by
 * glint_sim_lamp_turn(k) degrees (sim/camera_sim.h), so each lamp's sun
 * meets the sphere from its own side.
 *
 * Errors: none.  Threads: get and set are locked: any thread.  Who frees:
 * nothing.
 */

#include "board/board.h" /* GLINT_MAX_LIGHTS */

enum glint_sim_view {
	GLINT_SIM_VIEW_NONE,
	GLINT_SIM_VIEW_PROBE,
	GLINT_SIM_VIEW_SAMPLE
};

struct glint_sim_world {
	unsigned lights; /* bit k - 1: lamp k on (1: the one lamp on) */
	enum glint_sim_view view;
	double turntable_deg;
};

void glint_sim_world_get(struct glint_sim_world *w);
void glint_sim_world_set(const struct glint_sim_world *w);
/* Back to "no board": lights on, probe in view. */
void glint_sim_world_reset(void);

/* With the lights off the lab is this much dimmer. */
#define GLINT_SIM_LIGHTS_OFF_FACTOR 0.002

#endif
