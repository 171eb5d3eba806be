/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_PROBE_REGISTER_H
#define GLINT_CAPTURE_PROBE_PROBE_REGISTER_H

/*
 * Two views of a probe (the second photo taken ~90 degrees away, so that
 * each covers the other's region behind the ball): the rotation R taking
 * view 2's map frame into view 1's (L1(d) = L2(R^T d)), and their blend.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: images out with
 * glint_image_free().
 */

#include "core/image.h"
#include "core/vec.h"

/*
 * From direction correspondences (a_i in view 1, b_i in view 2; n >= 2):
 * the rotation minimising sum |a_i - R b_i|^2 (Wahba's problem, solved in
 * closed form by SVD, the least-squares rotation of the paper's point
 * correspondences).  rms_deg (may be NULL): the residual angle.
 */
int glint_register_points(const struct vec3 *a, const struct vec3 *b, int n,
			  struct mat3 *r, double *rms_deg);

/*
 * Automatic: the rotation making the two lat-long maps agree best (the
 * mean squared difference of log luminance, weighted by both masks, over
 * their overlap), searched from `guess` over a coarse grid of
 * yaw (all of it), pitch and roll (+-10 degrees), then refined by a local
 * search down to 0.05 degrees on 128 x 64 maps.  mask1/mask2 may be NULL.
 */
int glint_register_auto(const struct glint_image *env1,
			const struct glint_image *mask1,
			const struct glint_image *env2,
			const struct glint_image *mask2,
			const struct mat3 *guess, struct mat3 *r, double *cost);

/* Blend: view 2 rotated into view 1's frame, each texel the average of
 * the views weighted by mask x sampling density.  mask/density may be
 * NULL (weight 1).  *out is the caller's, freed with glint_image_free(). */
int glint_probe_blend(const struct glint_image *env1,
		      const struct glint_image *w1,
		      const struct glint_image *env2,
		      const struct glint_image *w2, const struct mat3 *r,
		      struct glint_image **out);

/* Angle of the rotation a^T b, degrees. */
double glint_rotation_angle_deg(const struct mat3 *a, const struct mat3 *b);

/* The weight of an unwrapped view: ENV-mask.png x ENV-density.exr
 * beside env_path (glint_probe_unwrap_write), or NULL when they are absent
 * or do not match (the error is cleared: the view then weighs 1).  The
 * caller frees it with glint_image_free(). */
struct glint_image *glint_probe_view_weight(const char *env_path);

/* glint_register_points() from a file of lines "x1 y1 x2 y2": pixel
 * positions of one feature in lat-long maps e1 and e2 (at most 256). */
int glint_register_points_file(const char *path, const struct glint_image *e1,
			       const struct glint_image *e2, struct mat3 *r,
			       double *rms_deg);

#endif
