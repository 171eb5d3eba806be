/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_WORLD_H
#define GLINT_SIM_WORLD_H

/*
 * The simulated rig's physical state, an object shared between the sim
 * board (which changes it: lights, turntable) and the sim camera's
 * "scene=rig" (which photographs it).  Simulators meet in the world of
 * their scenario file (sim/scenario.h): a camera whose device names a
 * scenario (scenario=FILE) and a board whose rig file names the same file
 * (board.scenario) share that file's world when the file describes the
 * camera; simulators of other scenarios do not see it.  Cameras without a
 * scenario share the world "" with the boards whose scenario plays
 * presses only.  Without a sim board open, the lights are on and the
 * probe is in view.
 *
 * The lab has up to GLINT_MAX_LIGHTS lamps, each on its own relay; lamp k
 * lights the scene with the rig's map turned about +Y by
 * glint_sim_lamp_turn(k) degrees (sim/camera_sim.h), so each lamp's sun
 * meets the sphere from its own side.
 *
 * Errors: glint_sim_world_open() returns a negative errno with
 * glint_error_msg().  Threads: get and set are locked: any thread; the
 * registry of worlds is locked too.  Who frees: glint_sim_world_close()
 * drops a reference; the last one frees the world.
 */

#include "board/board.h" /* GLINT_MAX_LIGHTS */

enum glint_sim_view {
	GLINT_SIM_VIEW_NONE,
	GLINT_SIM_VIEW_PROBE,
	GLINT_SIM_VIEW_SAMPLE,
	GLINT_SIM_VIEW_REFERENCE /* the gray ball's turntable position */
};

/* What is in view and how it is lit. */
struct glint_sim_state {
	unsigned lights; /* bit k - 1: lamp k on (1: the one lamp on) */
	enum glint_sim_view view;
	double turntable_deg;
};

struct glint_sim_world;

/* The world of scenario file `scenario` (NULL or "": the world of no
 * scenario), made in the "no board" state at its first open; the file is
 * named by its real path, so two spellings of one file are one world. */
int glint_sim_world_open(const char *scenario, struct glint_sim_world **out);
void glint_sim_world_close(struct glint_sim_world *w);

void glint_sim_world_get(struct glint_sim_world *w, struct glint_sim_state *st);
void glint_sim_world_set(struct glint_sim_world *w,
			 const struct glint_sim_state *st);
/* Back to "no board": lights on, probe in view. */
void glint_sim_world_reset(struct glint_sim_world *w);

/* With the lights off the lab is this much dimmer. */
#define GLINT_SIM_LIGHTS_OFF_FACTOR 0.002

#endif
