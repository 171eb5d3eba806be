/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_BRDF_BXDF_H
#define GLINT_FIT_BRDF_BXDF_H

/*
 * A BRDF behind a small interface: an ops table and the state it reads
 * (`self`): a model's parameter vector (model.h: glint_model_bxdf()), a
 * measured table (sim/tabulated.h).  The renderers (fit/render/render.c,
 * sim/reference.c), the exports' tabulation and the tests use it; what
 * only the fitter needs of a model is model.h's struct glint_fit_lobes.
 *
 * Directions are in the local shading frame (normal +z), unit length,
 * pointing away from the surface: wo towards the viewer, wi towards the
 * light.  Values are RGB per steradian, 0 below the surface.
 *
 * Errors: none; a direction that cannot be drawn gives pdf 0.
 * Threads: the functions are re-entrant; an instance may be shared by
 * threads while nothing writes its self.  Who frees: nothing: a struct
 * glint_bxdf borrows its self, which must outlive it; ops tables are
 * static.
 */

#include "core/vec.h"

enum glint_bxdf_flags {
	GLINT_BXDF_REFLECTION = 1 << 0, /* reflects (all of glint's do) */
	GLINT_BXDF_DIFFUSE = 1 << 1,	/* has a broad lobe */
	GLINT_BXDF_GLOSSY = 1 << 2,	/* has a lobe about the mirror */
	GLINT_BXDF_LOBES = 1 << 3,	/* f is a sum of lobes (below) */
};

struct glint_bxdf_ops {
	/* GLINT_BXDF_* */
	unsigned flags;
	/* f(wo, wi). */
	void (*eval)(const void *self, struct vec3 wo, struct vec3 wi,
		     double f[3]);
	/* Draw wi for wo from three uniforms; returns its solid-angle pdf,
	 * 0 if no direction was produced. */
	double (*sample)(const void *self, struct vec3 wo, const double u[3],
			 struct vec3 *wi);
	/* The pdf sample() has for wi. */
	double (*pdf)(const void *self, struct vec3 wo, struct vec3 wi);

	/*
	 * With GLINT_BXDF_LOBES: f = sum over nlobes lobes j of albedo_j (an
	 * RGB triple) times a scalar lobe b_j, each lobe with its own
	 * sampling (renderers weigh it against the light's lobe by lobe).
	 */
	int nlobes;
	/* Lobe j's RGB albedo (a pointer into self). */
	const double *(*albedo)(const void *self, int j);
	/* b_j(wo, wi) for every lobe j into b[nlobes]. */
	void (*eval_lobes)(const void *self, struct vec3 wo, struct vec3 wi,
			   double *b);
	/* b_j(wo, wi) of lobe j alone, the value eval_lobes() gives it; NULL
	 * where a model has only eval_lobes(). */
	double (*eval_lobe)(const void *self, int j, struct vec3 wo,
			    struct vec3 wi);
	/* Sample lobe j (density ~ b_j cos where possible); returns the
	 * pdf, 0 if no direction was produced. */
	double (*sample_lobe)(const void *self, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi);
	double (*pdf_lobe)(const void *self, int j, struct vec3 wo,
			   struct vec3 wi);
};

struct glint_bxdf {
	const struct glint_bxdf_ops *ops;
	const void *self;
};

static inline void glint_bxdf_eval(const struct glint_bxdf *b, struct vec3 wo,
				   struct vec3 wi, double f[3])
{
	b->ops->eval(b->self, wo, wi, f);
}

static inline double glint_bxdf_sample(const struct glint_bxdf *b,
				       struct vec3 wo, const double u[3],
				       struct vec3 *wi)
{
	return b->ops->sample(b->self, wo, u, wi);
}

static inline double glint_bxdf_pdf(const struct glint_bxdf *b, struct vec3 wo,
				    struct vec3 wi)
{
	return b->ops->pdf(b->self, wo, wi);
}

#endif
