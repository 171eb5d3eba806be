/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_COMPARE_H
#define GLINT_FIT_RENDER_COMPARE_H

/*
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: nothing (the
 * PNG is the result).
 */

#include "core/image.h"

/*
 * compare.png: photo | render | signed error (render - photo, luminance)
 * side by side.  Photo and render share one exposure (the photo's auto
 * exposure, docs/conventions.md); the error panel maps -s..+s to blue,
 * white, red, with s the 99th percentile of |error| over the pixels the
 * sphere covers whole, shown on a scale bar (the rim's part-covered pixels
 * saturate).  mask (may be NULL) is the sphere's coverage of each pixel:
 * above 0 on the sphere, 1 where whole; elsewhere the error panel is grey.
 */
/*
 * A residual plot under the three panels: bands of some angle, each with
 * its mean residual and standard error, drawn as a dot with a +-2 standard
 * error bar (red where the mean is more than 5 standard errors from 0)
 * about a zero line.  edges has n + 1 values (degrees); bands with fewer
 * than 20 pixels are not drawn.  title and xlabel (the x axis's name;
 * NULL: "DEGREES"): capitals, digits and punctuation.  The y axis is
 * labelled "MEAN RENDER - PHOTO" with its range, and a legend under the
 * plots says what the marks are.
 */
struct glint_compare_plot {
	const char *title, *xlabel;
	int n;
	const double *edges, *mean, *se;
	const long *pixels;
};

int glint_compare_png(const char *path, const struct glint_image *photo,
		      const struct glint_image *render,
		      const struct glint_image *mask, double *scale_out);

/* The same with nplots residual plots (may be 0) side by side below. */
int glint_compare_png_plots(const char *path, const struct glint_image *photo,
			    const struct glint_image *render,
			    const struct glint_image *mask,
			    const struct glint_compare_plot *plots, int nplots,
			    double *scale_out);

#endif
