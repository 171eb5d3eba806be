/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_CAMERA_SIM_H
#define GLINT_SIM_CAMERA_SIM_H

/* The simulated camera (a backend of capture/camera.h) and its scene. */

#include "core/image.h"

/* The test card it photographs: `decades` decades of radiance left to
 * right up to 100 (R 0.8, G 1, B 0.6 of that), and a disk of 500 at
 * (0.7 w, 0.5 h), radius 0.1 w.  Ground truth for HDR tests. */
struct glint_image *glint_sim_test_card(int w, int h, double decades);

#endif
