/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_SPHERE_DETECT_H
#define GLINT_CAPTURE_PROBE_SPHERE_DETECT_H

/*
 * Find a sphere's silhouette in a photo (the probe ball or the sample) to
 * sub-pixel accuracy, without a template:
 *   1. edges: Sobel gradient of log luminance (so an HDR photo's dark and
 *      bright halves count alike), thinned along the gradient, the
 *      strongest 6 %;
 *   2. centre: every edge pixel votes along its gradient line, both ways,
 *      at every radius in the range (a circle Hough transform that needs
 *      no radius axis); the smoothed accumulator's peak;
 *   3. radius: the peak of the histogram of edge distances from it, over
 *      edges whose gradient points along the radius;
 *   4. refinement: each such edge located to sub-pixel along its gradient
 *      (parabola through the gradient magnitude) and a geometric circle
 *      fit (Gauss-Newton with Huber weights), which works on a partial arc
 *      (a dark ball against a dark floor shows only part of its rim);
 *   5. the rim's profile: at about one angle per rim pixel, a blurred step
 *      between two sloped levels fitted along the radius, and the circle
 *      fitted again to those edges weighted by their inverse variances
 *      (the gradient's peak moves where the ball or its backdrop slopes
 *      towards the rim: sphere_detect.c, rim_refine()).
 * The pinhole image of an off-axis sphere is an ellipse; this fits its
 * circle of best fit (centre and tangential radius to well under a pixel
 * for the rig's small angles; glint_pinhole_sphere_from_circle() inverts it).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (no circle found is an error that says why).
 * Threads: re-entrant.  Who frees: nothing (results are values).
 */

#include "core/image.h"

struct glint_circle {
	double cx, cy, r;
	int points;	/* edge points of step 4's fit */
	double rms_px;	/* their RMS distance from the final circle */
	double arc_deg; /* angular extent of the rim they cover */
	/* The detection's test statistic: the share of the circle's rim
	 * (in steps of about a pixel) with an edge on it whose gradient is
	 * radial, and how far that share stands above what the image's own
	 * edge density gives a circle by chance (in standard deviations). */
	double rim_share, rim_z;
	double rim_run_deg; /* the longest arc of it covered (gaps <= 3 px) */
	double rim_slope;   /* median log-luminance slope across it, per px */
	/* (all four of the copy reduced to 1024 px on its shorter side for
	 * a larger image: where it was found and judged) */
};

/*
 * The thresholds a circle must pass to be found, set on 1000 images that
 * hold no sphere (noise, blank frames, vignetting, gradients, smooth
 * texture, rectangles, checkerboards, gratings) and on real and simulated
 * spheres: tests/sim/test_sphere_detect.c measures both, docs/hdr.md
 * gives the numbers.  A steep rim (the slope keeps out a vignette's ring
 * of steepest fall-off, 0.082 at most, whose edges the hysteresis joins
 * into most of a ring: share 0.59, z 45.9) covered on at least a tenth,
 * and either z >= 45 (the highest among the other frames with no sphere:
 * 33.9; the lowest of a find on the UW photos, 2.7 px from the mask's
 * circle: 60.6) or, for a small sphere whose rim is too short for such a
 * z, a covered share >= 0.36 with z >= 20 (the highest share among the
 * other frames with no sphere: 0.32; the rig's 25 px sample through its
 * optics: 0.64 at z 46.3).
 */
#define GLINT_DETECT_MIN_RIM_SHARE 0.10
#define GLINT_DETECT_MIN_RIM_Z	   45.0
#define GLINT_DETECT_MIN_RIM_SLOPE 0.2
#define GLINT_DETECT_SMALL_SHARE   0.36
#define GLINT_DETECT_SMALL_MIN_Z   20.0

/* Search radii [r_min, r_max] in pixels (0, 0: 5 % .. 50 % of the smaller
 * image side).  -ENOENT ("no sphere") when the best circle fails the
 * thresholds above; *out then still holds it and its statistic. */
int glint_sphere_detect(const struct glint_image *img, double r_min,
			double r_max, struct glint_circle *out);

/* The circle of a binary mask (pixels > 0.5): centroid and the radius of
 * the disk of equal area. */
int glint_mask_circle(const struct glint_image *mask, struct glint_circle *out);

#endif
