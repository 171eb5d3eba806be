/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_CAMERA_SIM_H
#define GLINT_SIM_CAMERA_SIM_H

/*
 * The simulated camera (a backend of capture/camera/camera.h) and its
 * scene.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: as capture/camera/camera.h; the world
 * it shows is read under its lock (sim/world.h).  Who frees:
 * glint_camera_close(); images out with glint_image_free().
 */

#include "capture/camera/camera.h"
#include "core/image.h"
#include "fit/scene/scene.h"

/* The backend ("sim"), registered by the program (cmd/backends.c). */
extern const struct glint_camera_ops glint_camera_sim_ops;

/* The test card it photographs: `decades` decades of radiance left to
 * right up to 100 (R 0.8, G 1, B 0.6 of that), and a disk of 500 at
 * (0.7 w, 0.5 h), radius 0.1 w.  Ground truth for HDR tests.  The caller's
 * (glint_image_free()); NULL when out of memory. */
struct glint_image *glint_sim_test_card(int w, int h, double decades);

/* The sim rig's world: the Venice map shipped with glint turned about +Y
 * by GLINT_SIM_RIG_MAP_TURN degrees (a whole number of texel columns, so
 * exactly: world column x = map column x + shift), so that the low sun
 * lights the sample from the camera's side. */
#define GLINT_SIM_RIG_MAP_TURN 114.0
/* Lit by the lamps in `lamps` (bit k - 1: lamp k; 0 counts as lamp 1):
 * the sum of the map turned by GLINT_SIM_RIG_MAP_TURN +
 * glint_sim_lamp_turn(k) for each (0, 240, 120, 180 degrees): lamp 1's
 * low sun lights the sample from the camera's left (its highlight near
 * the left rim), lamp 2's from behind the sphere (a Fresnel glint on the
 * right rim), lamp 3's from near the camera (the highlight near the
 * centre). */
int glint_sim_rig_map(unsigned lamps, struct glint_image **out);
double glint_sim_lamp_turn(int k);

/* Its "scene=probe": a chrome ball (n 3.2, k 3.3) reflecting the rig's
 * map (above), centred, 0.4 of the smaller side in radius,
 * seen by a pinhole of focal length glint_sim_probe_focal_px(w) looking
 * along -Z with +Y up (so an unwrap returns the map as it is). */
int glint_sim_probe_scene(int w, int h, unsigned lamps,
			  struct glint_image **out);
double glint_sim_probe_focal_px(int w);

/* The gray/chrome pair ("gray=ALBEDO" with scene=probe or the rig's probe
 * view): the chrome ball at 0.3 of the width and a matte gray ball of
 * that albedo at 0.72, both centred in height, 0.25 of the smaller side
 * in radius, in the same map and camera; the gray ball rendered by the
 * reference renderer (Lambert), 9 x 64 samples a pixel. */
int glint_sim_probe_pair_scene(int w, int h, unsigned lamps, double albedo,
			       struct glint_image **out);
/* Where the pair's balls are: image centre and radius, pixels (ball 0 the
 * chrome, 1 the gray). */
void glint_sim_probe_pair_circle(int w, int h, int ball, double *cx, double *cy,
				 double *r);

/* The gray reference ball at its own turntable position ("reference=ALBEDO"
 * with scene=rig): a matte ball of that albedo where the probe scene's
 * chrome ball is (centred, 0.4 of the smaller side in radius), over black,
 * in the same map and camera, rendered as the pair's gray ball is. */
int glint_sim_reference_scene(int w, int h, unsigned lamps, double albedo,
			      struct glint_image **out);

/* Its "scene=sample": a 10 cm sphere of a Table-1 material under the same
 * map in the same orientation (so the probe's env.exr lights it as it is),
 * seen by the same camera, 0.35 of the smaller side in radius, in front of
 * the map itself; rendered by the reference renderer (sim/reference.h).
 * _def gives the scene (ground truth for tests). */
int glint_sim_sample_scene_def(int w, int h, struct glint_scene *sc);
int glint_sim_sample_scene(int w, int h, const char *material, unsigned lamps,
			   struct glint_image **out);

#endif
