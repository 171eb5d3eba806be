/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_PROBE_SIM_H
#define GLINT_SIM_PROBE_SIM_H

/*
 * A photograph of a mirror ball, rendered forward (independently of
 * capture/probe/probe.c's inverse mapping): a pinhole camera at the origin
 * looking along -Z (x right, y up, principal point at the image centre),
 * each pixel's rays (spp x spp, stratified) intersected with the sphere,
 * reflected, and looked up in a lat-long map (bilinear), times the
 * conductor's Fresnel reflectance computed with complex arithmetic.
 * Background: 0.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: the image out
 * with glint_image_free().
 */

#include "core/image.h"
#include "core/vec.h"

int glint_sim_mirror_ball(const struct glint_image *latlong, int w, int h,
			  double fpx, struct vec3 centre, double radius,
			  const double n[3], const double k[3], int spp,
			  struct glint_image **out);

#endif
