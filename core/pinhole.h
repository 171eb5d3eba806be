/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_PINHOLE_H
#define GLINT_CORE_PINHOLE_H

/*
 * Pinhole camera, with an optional thin lens for depth of field.
 * World units are metres.  Camera frame: `fwd` is the optical axis, `right`
 * is image +x, `up` is image -y (image rows grow downwards).  The principal
 * point is the image centre (width / 2, height / 2) in pixel coordinates.
 *
 * Errors: the loader's are a negative errno with glint_error_msg(); the
 * projections have none.  Threads: re-entrant.  Who frees: nothing
 * (values).
 */

#include "core/vec.h"

struct glint_pinhole {
	int width, height;
	double fpx;		/* focal length in pixels */
	double cx, cy;		/* principal point, pixels */
	double aperture_radius; /* metres; 0 = pinhole */
	double focus_distance;	/* metres along fwd (thin lens only) */
	struct vec3 pos, right, up, fwd;
	/* This image is the window at (frame_x, frame_y) of a frame
	 * frame_width pixels wide (0: the whole frame; glint_fit_job_crop).
	 * Only the per-pixel sample patterns and seeds use it, so that a
	 * window's pixels get the frame's samples. */
	int frame_x, frame_y, frame_width;
	/* The camera's blur, which a rendered pixel takes in as a pixel
	 * filter (glint_pixel_filter_*): a Gaussian of psf_sigma_px (the
	 * lens; without cfa, the demosaic's spread too) and, with olpf, the
	 * optical low-pass filter's split of each ray into two, one pixel
	 * apart, along each axis; 0 and 0: the pixel's own square. */
	double psf_sigma_px;
	int olpf;
	/* The photo's colour filter array, when its pixels were demosaiced
	 * from one: cfa[(X & 1) + 2 (Y & 1)] is the colour (0 red, 1 green,
	 * 2 blue) measured at frame pixel (X, Y), the other two being
	 * interpolated; cfa[0] < 0: every pixel measured in all three. */
	signed char cfa[4];
};

/* "RGGB", "GRBG", "GBRG" or "BGGR" (the colours at (0, 0), (1, 0),
 * (0, 1), (1, 1)) into cam->cfa; NULL or "" clears it. */
int glint_pinhole_set_cfa(struct glint_pinhole *cam, const char *layout);

/*
 * The pixel filter as a sampling map: the inverse of the cumulative
 * distribution, along one axis, of the pixel's square convolved with the
 * camera's blur, tabulated at GLINT_PIXEL_FILTER_N + 1 points.  A
 * stratified sample u in [0, 1) maps to the position
 * glint_pixel_filter_map(table, u) in pixels from the pixel's corner (the
 * square alone gives u itself), so that a pixel's samples average the
 * blurred image: the photo's pixel, not the scene's.
 */
#define GLINT_PIXEL_FILTER_N 512

/* Whether cam has a blur to sample (psf_sigma_px > 0 or olpf). */
int glint_pixel_filter_on(const struct glint_pinhole *cam);
void glint_pixel_filter_table(const struct glint_pinhole *cam,
			      float table[GLINT_PIXEL_FILTER_N + 1]);
static inline double glint_pixel_filter_map(const float *table, double u)
{
	double f = u * GLINT_PIXEL_FILTER_N;
	int i = (int)f;
	if (i >= GLINT_PIXEL_FILTER_N)
		return table[GLINT_PIXEL_FILTER_N];
	return table[i] + (f - i) * (table[i + 1] - table[i]);
}

/*
 * Build a camera: focal length and pixel pitch in metres, f_number 0 for a
 * pinhole, pose from position / look-at / up.  Returns -EINVAL if the pose
 * is degenerate (up parallel to the view direction).
 */
int glint_pinhole_init(struct glint_pinhole *cam, int width, int height,
		       double focal_m, double pitch_m, double f_number,
		       double focus_m, struct vec3 pos, struct vec3 look_at,
		       struct vec3 up);

/*
 * The ray through image point (px, py) (pixel coordinates, continuous);
 * (lu, lv) in [0, 1)^2 pick the point on the lens (ignored for a pinhole).
 * dir is unit length.
 */
void glint_pinhole_ray(const struct glint_pinhole *cam, double px, double py,
		       double lu, double lv, struct vec3 *org,
		       struct vec3 *dir);

/* Project a world point; returns 0 if it is in front of the camera. */
int glint_pinhole_project(const struct glint_pinhole *cam, struct vec3 p,
			  double *px, double *py);

/* The pinhole image of a sphere: an ellipse (a circle on the axis). */
struct glint_ellipse {
	double cx, cy; /* centre, pixels */
	double a, b;   /* semi-axes, pixels: a radial, b tangential */
	double angle;  /* direction of the a axis, radians from image +x */
};

/* Silhouette of the sphere (centre, radius) through the pinhole model. */
int glint_pinhole_sphere_ellipse(const struct glint_pinhole *cam,
				 struct vec3 centre, double radius,
				 struct glint_ellipse *out);

/*
 * Inverse: the 3-D centre of a sphere of known radius whose silhouette is
 * centred at (cx, cy) with tangential semi-axis b (the circle's radius for a
 * sphere on the axis), exact for the pinhole model (the silhouette is the
 * section of the tangent cone by the image plane).
 */
int glint_pinhole_sphere_from_circle(const struct glint_pinhole *cam, double cx,
				     double cy, double b, double radius,
				     struct vec3 *centre);

#endif
