/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_REFERENCE_H
#define GLINT_SIM_REFERENCE_H

/*
 * Ground-truth renders for the simulated rig, made independently of the
 * fitter's fast path so that fitting them is no "inverse crime":
 *   - its own analytic ray-sphere intersection (no Embree, no G-buffer),
 *     with many jittered samples per pixel, stratified over its area;
 *   - every lobe by independent pseudo-random sampling (no fixed sample
 *     sets, no hot-texel quadrature, no irradiance map), env map and lobe,
 *     combined with the power heuristic and the true pdfs; env-map
 *     samples jittered in strata of the row coordinate.
 * What it shares with the fitter is the definition of the scene: the
 * camera model, the env map's lookup and sampler, the BRDF.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: renders on its own threads
 * (opts.nthreads).  Who frees: nothing (the caller's image).
 */

#include "fit/scene/envmap.h"
#include "fit/brdf/model.h"
#include "fit/scene/scene.h"

#include "core/image.h"

#include <stdint.h>

/* Raised whenever the same options come to render another image (2:
 * pixel positions stratified): renders kept on disk name it, so that an
 * older renderer's are never read as this one's. */
#define GLINT_REFERENCE_VERSION 2

struct glint_reference_opts {
	int spp;	  /* jittered primary samples per pixel */
	int samples;	  /* per hit and technique, for varying lobes */
	uint32_t seed;	  /* pseudo-random stream */
	int nthreads;	  /* 0 = all CPUs */
	int irradiance_w; /* irradiance map width (height = width / 2) */
	/* Adaptive sampling (0: off): a pixel whose first round of spp
	 * samples has a relative standard error above rel_noise is
	 * rendered again in up to max_rounds rounds, its value their mean. */
	double rel_noise;
	int max_rounds;
	long *rounds; /* if set: the rounds rendered over every pixel */
};

void glint_reference_default_opts(struct glint_reference_opts *o);

/* Render scene->cam's image of the sphere of material (model, p) into out
 * (allocated by the caller at the camera's size); _bxdf the same for an
 * opaque sphere of any BRDF with lobe structure (GLINT_BXDF_LOBES: the
 * measured tables of sim/tabulated.h).  Errors: -EINVAL (a BRDF without
 * lobes, a target of the wrong size), -ENOMEM. */
int glint_reference_render(const struct glint_scene *scene,
			   const struct glint_envmap *env,
			   const struct glint_model *model, const double *p,
			   const struct glint_reference_opts *opts,
			   struct glint_image *out);
int glint_reference_render_bxdf(const struct glint_scene *scene,
				const struct glint_envmap *env,
				const struct glint_bxdf *bxdf,
				const struct glint_reference_opts *opts,
				struct glint_image *out);

#endif
