/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_CAMERA_SIM_H
#define GLINT_SIM_CAMERA_SIM_H

/* The simulated camera (a backend of capture/camera.h) and its scene. */

#include "core/image.h"

/* The test card it photographs: `decades` decades of radiance left to
 * right up to 100 (R 0.8, G 1, B 0.6 of that), and a disk of 500 at
 * (0.7 w, 0.5 h), radius 0.1 w.  Ground truth for HDR tests. */
struct glint_image *glint_sim_test_card(int w, int h, double decades);

/* Its "scene=probe": a chrome ball (n 3.2, k 3.3) reflecting the Venice
 * map shipped with glint, centred, 0.4 of the smaller side in radius,
 * seen by a pinhole of focal length glint_sim_probe_focal_px(w) looking
 * along -Z with +Y up (so an unwrap returns the map as it is). */
int glint_sim_probe_scene(int w, int h, struct glint_image **out);
double glint_sim_probe_focal_px(int w);

#endif
