/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_PHOTO_H
#define GLINT_SIM_PHOTO_H

/*
 * A simulated photo of a sphere of a material: the reference renderer
 * (sim/reference.h, never the fitter's fast path) at the scene camera's
 * size, optionally through the sensor model as one 12-bit exposure set
 * for the diffuse body (highlights clip), with its per-pixel weights.
 * What glint demo and the tests fit.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: renders on its own threads (nthreads).
 * Who frees: the photo with glint_image_free().
 */

#include "fit/brdf/model.h"
#include "fit/scene/scene.h"

#include "core/image.h"

struct glint_sim_photo_opts {
	int noise;    /* one noisy exposure instead of noise-free HDR */
	int nthreads; /* 0: all CPUs */
};

/* Into *photo (linear radiance) and, with noise, *weight (1/variance;
 * NULL without noise); both new, the caller frees them with
 * glint_image_free().  On error neither is set. */
int glint_sim_photo(const struct glint_scene *scene,
		    const struct glint_model *model, const double *params,
		    const struct glint_sim_photo_opts *o,
		    struct glint_image **photo, struct glint_image **weight);

#endif
