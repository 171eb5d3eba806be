/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_PROBE_INTERNAL_H
#define GLINT_CAPTURE_PROBE_PROBE_INTERNAL_H

/*
 * The photographed ball's geometry, shared by the unwrap (probe.c) and the
 * compact light sources (probe_sources.c).  Not installed.
 *
 * Errors: a negative errno with glint_error_msg() naming the value and
 * what was expected (glint_probe_ball_setup); the rest cannot fail.
 * Threads: re-entrant; a probe_ball is read-only once set up.  Who frees:
 * nothing (plain values).
 */

#include "capture/probe/probe.h"

/* The ball's frame: camera at the origin looking along -Z, x right, y up;
 * lengths in ball radii. */
struct probe_ball {
	double fpx, cx, cy;
	struct vec3 c;	     /* centre */
	double bcx, bcy, br; /* its image circle (orthographic mode) */
	int ortho;
};

/* The ball as the photo's pinhole camera sees it (its centre from its
 * circle, exact for the pinhole); -EINVAL for a ball outside the photo or
 * a focal length or radius not > 0. */
int glint_probe_ball_setup(const struct glint_image *photo,
			   const struct glint_unwrap_opts *o,
			   struct probe_ball *b);

/*
 * Where the ball shows direction d: the point P = c + n whose mirror
 * reflection of the camera's ray i (unit, towards P) leaves along d, i.e.
 * n = normalize(d - i) with i = normalize(c + n): a fixed point, exact for
 * the perspective camera.  Orthographic (the peers' approximation): i is
 * the ray to the centre for every point, and the ball's image is its
 * outline scaled, P at ball_c + r (n . right, n . up).  Returns 0 if the
 * point is not visible; *ci = cos(incidence).
 */
int glint_probe_ball_image(const struct probe_ball *b, struct vec3 d, double *x,
			   double *y, double *ci);

/* The ball's outward unit normal where the camera's ray through the
 * photo's continuous pixel (x, y) meets it, and that ray (unit, towards
 * the ball); 0 when the ray misses the ball. */
int glint_probe_ball_normal(const struct probe_ball *b, double x, double y,
			    struct vec3 *n, struct vec3 *ray);

/* The other way: the direction the ball reflects into the photo's
 * continuous pixel (x, y), and cos(incidence) there; 0 when the pixel
 * misses the ball. */
int glint_probe_ball_reflect(const struct probe_ball *b, double x, double y,
			     struct vec3 *d, double *ci);

#endif
