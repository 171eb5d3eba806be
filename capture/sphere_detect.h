/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_SPHERE_DETECT_H
#define GLINT_CAPTURE_SPHERE_DETECT_H

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
 *      (a dark ball against a dark floor shows only part of its rim).
 * The pinhole image of an off-axis sphere is an ellipse; this fits its
 * circle of best fit (centre and tangential radius to well under a pixel
 * for the rig's small angles; glint_pinhole_sphere_from_circle() inverts it).
 */

#include "core/image.h"

struct glint_circle {
	double cx, cy, r;
	int points;	/* edge points in the final fit */
	double rms_px;	/* their RMS distance from the circle */
	double arc_deg; /* angular extent of the rim they cover */
};

/* Search radii [r_min, r_max] in pixels (0, 0: 5 % .. 50 % of the smaller
 * image side). */
int glint_sphere_detect(const struct glint_image *img, double r_min,
			double r_max, struct glint_circle *out);

/* The circle of a binary mask (pixels > 0.5): centroid and the radius of
 * the disk of equal area. */
int glint_mask_circle(const struct glint_image *mask, struct glint_circle *out);

#endif
