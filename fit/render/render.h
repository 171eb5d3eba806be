/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_RENDER_H
#define GLINT_FIT_RENDER_RENDER_H

/*
 * Shading of a traced G-buffer under a distant environment map:
 *   L_o(x, wo) = integral of L_env(wi) f(wo, wi) cos(theta_i) dwi,
 * estimated with multiple importance sampling (balance heuristic) of
 * env-map samples and BRDF samples, on fixed deterministic sample sets
 * (the same inputs always give the same image).  Only direct light from the
 * map: the sample is the only object.  Shadow rays are traced only when the
 * scene is not a single convex sphere.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: a renderer renders on its own threads
 * (nthreads) and is driven by one thread.  Who frees:
 * glint_renderer_release() a renderer's tracer, map and buffers.
 */

#include "fit/scene/envmap.h"
#include "fit/brdf/model.h"
#include "fit/scene/scene.h"
#include "tracer.h"

#include "core/image.h"
#include "core/log.h"

struct glint_shade_opts {
	int light_samples; /* env-map samples per hit */
	int brdf_samples;  /* BRDF samples per hit */
	int background;	   /* misses show the env map (else black) */
	int nthreads;	   /* 0 = all CPUs */
	struct glint_progress *progress; /* may be NULL; counts rows */
	/* Which sample sets: renders with different seeds are independent
	 * estimates (0: the sets every render used before seeds). */
	uint32_t seed;
	/* > 1: shade only the rows y with y % row_step == 0 (a pilot);
	 * the others are left as they are */
	int row_step;
	/* > 1: shade every pixel_step-th pixel of every pixel_step-th row,
	 * then each pixel between four of them that lie wholly on the
	 * sphere bilinearly from them, and shade the rest (the rim, the
	 * backdrop): a render for a budget too small for every pixel, whose
	 * grid pixels are the full render's own bits */
	int pixel_step;
};

/*
 * Shade gb into out (gb->width x gb->height, allocated by the caller).
 * coverage, if not NULL, receives the fraction of each pixel's samples that
 * hit the sample (same value in R, G, B).  tracer is used for shadow rays
 * and may be NULL for a convex scene.
 */
int glint_render_shade(const struct glint_gbuffer *gb,
		       struct glint_tracer *tracer,
		       const struct glint_envmap *env,
		       const struct glint_model *model, const double *params,
		       const struct glint_shade_opts *opts,
		       struct glint_image *out, struct glint_image *coverage);

/* Radiance estimate for one hit (exposed for tests). */
void glint_shade_hit(const struct glint_hit *h, uint32_t seed,
		     struct glint_tracer *tracer,
		     const struct glint_envmap *env,
		     const struct glint_model *model, const double *params,
		     int nl, int nb, double rgb[3]);

/* Everything a render needs, built from a scene. */
struct glint_renderer {
	struct glint_scene scene;
	struct glint_envmap *env;
	struct glint_tracer *tracer;
	struct glint_gbuffer gb;
	double trace_seconds;
};

/* Load the env map, build the tracer, trace the primary rays. */
int glint_renderer_init(struct glint_renderer *r,
			const struct glint_scene *scene, int nthreads,
			struct glint_progress *progress);
/* The same with an env map already built (scene->env_path is not read);
 * the renderer owns env from then on, also on failure. */
int glint_renderer_init_env(struct glint_renderer *r,
			    const struct glint_scene *scene,
			    struct glint_envmap *env, int nthreads,
			    struct glint_progress *progress);
void glint_renderer_release(struct glint_renderer *r);

/* Render the scene's sphere of any model (BRDF models by
 * glint_render_shade, transparent ones by following their paths) with
 * the renderer's G-buffer. */
int glint_renderer_shade(struct glint_renderer *r,
			 const struct glint_model *model, const double *params,
			 const struct glint_shade_opts *opts,
			 struct glint_image *out, struct glint_image *coverage);

#endif
