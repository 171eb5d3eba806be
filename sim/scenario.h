/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_SCENARIO_H
#define GLINT_SIM_SCENARIO_H

/*
 * A scenario for the simulated rig: one JSON file that both simulators
 * read, and whose world (sim/world.h) they share.
 *
 *   {
 *     "camera": {"width": 640, "height": 480, "scene": "rig",
 *                "material": "yellow-plastic", "latency": 2,
 *                "manual": true, "seed": 7, "noise": true, "decades": 6,
 *                "timescale": 0.01, "scene_scale": 4},
 *     "presses": [{"at_s": 0.5, "hold_s": 0.2, "bounces": 3}]
 *   }
 *
 * "camera" is the sim camera's sensor and scene (sim/camera_sim.c: the
 * same keys as its device string; a device "sim:scenario=FILE" reads
 * them), "presses" the sim board's button (sim/board_sim.c: a rig file's
 * board.scenario names the file).  Either may be missing; a file with a
 * "camera" is a world of its own (sim/world.h), shared by the camera and
 * the board that name it.
 *
 * Errors: a negative errno with glint_error_msg() naming the file and the
 * key.  Threads: re-entrant.  Who frees: json_decref() the document.
 */

#include <jansson.h>

/* The scenario at path, its top level checked (only "camera" and
 * "presses", each of its type). */
int glint_sim_scenario_load(const char *path, json_t **doc);

#endif
