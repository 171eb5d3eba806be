/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_COMPARE_H
#define GLINT_FIT_RENDER_COMPARE_H

#include "core/image.h"

/*
 * compare.png: photo | render | signed error (render - photo, luminance)
 * side by side.  Photo and render share one exposure (the photo's auto
 * exposure, docs/conventions.md); the error panel maps -s..+s to blue,
 * white, red, with s the 99th percentile of |error| on the sphere, shown on
 * a scale bar.  mask (may be NULL) marks the pixels on the sphere (> 0);
 * elsewhere the error panel is grey.
 */
int glint_compare_png(const char *path, const struct glint_image *photo,
		      const struct glint_image *render,
		      const struct glint_image *mask, double *scale_out);

#endif
