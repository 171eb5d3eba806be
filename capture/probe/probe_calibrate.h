/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_PROBE_CALIBRATE_H
#define GLINT_CAPTURE_PROBE_PROBE_CALIBRATE_H

/*
 * A probe calibrated by a gray ball: the matte half of the gray/chrome
 * pair of film sets, photographed by the same camera from the same place
 * as the mirror ball.  A matte ball of known albedo rho shows at each
 * normal n the irradiance the map predicts there:
 *
 *   I(n) = rho / pi * ( s E_rest(n) + sum_k g_k max(0, n . d_k) )
 *
 * E_rest is the irradiance of the map less its compact sources
 * (capture/probe/probe_sources.h), d_k each source's direction.  Per
 * channel, linear least squares over the ball's pixels gives the map's
 * scale s (a mirror whose reflectance is not its specification, an
 * exposure off by a factor) and each source's flux g_k as the gray ball
 * saw it: a sun clipped in the probe's shortest frame (its probe flux only
 * a lower bound) or one whose colour the mosaic aliased.  A source the
 * gray ball determines no better than the probe did (its standard error
 * over the probe's own, the probe's scaled by s; or a flux below zero)
 * enters the scale's fit at the probe's flux, and its calibrated flux is
 * the probe's (times s) and the gray ball's alone (every source free)
 * weighted by their inverse variances, per channel.  Each source's direction is
 * measured first, on green: on the side it lights, its shading rho / pi n . (g
 * d) is linear in the vector g d (probe_calibrate.c, refine_directions()); the
 * gray ball's direction is kept where its standard error is under the probe's.
 * Standard errors: the least squares' own, scaled by the residual's variance
 * (what the ball shows that the model does not, counted as noise), and the
 * albedo's relative uncertainty added in quadrature to every scale and flux
 * (fully correlated: one number multiplies all).
 *
 * The ball's pixels within max_radius of its image radius are used (the
 * rim is blurred and grazing), at most about 4000 of them on a regular
 * grid, and none whose merge weight is 0 (clipped).  The map is reduced
 * to at most 128 texels across for E_rest (its compact sources are taken
 * out first and enter as exact points, so the reduction blurs only
 * smooth light).
 *
 * Each stage checks what it made: fewer than 50 usable pixels, a ball
 * the model leaves a relative RMS above max_rel_rms (default 0.2: not a
 * matte ball under this probe, or another camera frame), or a scale
 * outside 0.2 to 5 (an albedo or an exposure wrong by that much) is
 * refused, naming the number.
 *
 * Errors: a negative errno with glint_error_msg() naming the value and
 * what was expected.  Threads: re-entrant.  Who frees: nothing (results
 * in the caller's structs); the map and sources are changed in place by
 * glint_probe_calibration_apply().
 */

#include "capture/probe/probe.h"
#include "capture/probe/probe_sources.h"

struct glint_calibrate_opts {
	double albedo[3];	/* the gray ball's diffuse albedo */
	double albedo_sigma[3]; /* its 1-sigma uncertainty (absolute) */
	double max_radius;	/* of the ball's image radius (default 0.9) */
	double max_rel_rms;	/* default 0.2 */
	/* the merge's weights of the gray ball's photo (may be NULL) */
	const struct glint_image *weights;
};

void glint_calibrate_default_opts(struct glint_calibrate_opts *o);

struct glint_calibrated_source {
	struct vec3 dir;      /* the gray ball's where it knows it better */
	double dir_sigma_deg; /* 1 sigma */
	double flux_probe[3]; /* what the probe measured */
	double flux[3];	      /* calibrated */
	double flux_sigma[3];
	int from_gray; /* 1: the gray ball's flux; 0: the probe's x scale
			  and the gray ball's, weighted */
	int saturated; /* clipped in the probe */
};

struct glint_calibration {
	double scale[3], scale_sigma[3];
	int nsources;
	struct glint_calibrated_source src[GLINT_MAX_SOURCES];
	int pixels;	   /* of the gray ball, fitted */
	double rel_rms[3]; /* residual RMS over the mean, per channel */
	double albedo[3], albedo_sigma[3];
};

/*
 * Calibrate the lat-long map env (the probe unwrapped in the camera's
 * frame) and its sources src (may be NULL: the scale alone) against the
 * photo of the gray ball; geom holds the camera and the gray ball's image
 * circle as for glint_probe_unwrap (focal length, principal point,
 * ball_cx, ball_cy, ball_r).
 */
int glint_probe_calibrate(const struct glint_image *env,
			  const struct glint_light_sources *src,
			  const struct glint_image *gray,
			  const struct glint_unwrap_opts *geom,
			  const struct glint_calibrate_opts *o,
			  struct glint_calibration *cal);

/* Apply cal to env (every texel times the scale, each source's flux
 * replaced by its calibrated one) and to src (may be NULL): flux, sigma,
 * saturated cleared where the gray ball measured it, total_flux. */
void glint_probe_calibration_apply(const struct glint_calibration *cal,
				   struct glint_image *env,
				   struct glint_light_sources *src);

/* cal as JSON at path (atomically); probe and gray name the inputs. */
int glint_probe_calibration_write(const char *path, const char *probe,
				  const char *gray,
				  const struct glint_calibration *cal);

#endif
