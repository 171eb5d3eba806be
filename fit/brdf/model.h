/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_BRDF_MODEL_H
#define GLINT_FIT_BRDF_MODEL_H

/*
 * Appearance models: named, bounded parameters over a BRDF (bxdf.h) and
 * the hooks the fitter uses, or the transparent sphere.  A model is a
 * static const table; adding one is one file plus a line in model.c's
 * registry.  The microfacet models are data over a distribution
 * descriptor (microfacet.h).
 *
 * Directions are in the local shading frame (normal = +z), unit length,
 * pointing away from the surface: wo towards the viewer, wi towards the
 * light.  Parameter vectors are plain double arrays laid out as `params`.
 *
 * Errors: the loaders return a negative errno with glint_error_msg() set
 * (file, key and bounds named); the evaluation functions have none.
 * Threads: everything here is re-entrant; models and parameter vectors
 * are read only.  Who frees: nothing for models (static); json_decref()
 * the json_t results.
 */

#include "bxdf.h"
#include "core/vec.h"

#include <jansson.h>

#define GLINT_MAX_PARAMS 16

struct glint_param {
	const char *name;     /* "diffuse.r", "roughness", ... */
	const char *json_key; /* key in material JSON ("diffuse") */
	int json_index;	      /* component of an RGB array, -1 for scalars */
	double lo, hi;	      /* bounds (inclusive) */
	double def;	      /* default / initial value */
};

struct glint_microfacet;

/*
 * What the fitter needs of a model beyond its BRDF (fit/, fit/render/
 * shade_cache.c): where the lobes' albedos sit, which lobes vary, values
 * and pdfs shared between a lobe's evaluation and its sampling, and the
 * lobes' microfacet distribution and widths.  The lobes themselves (their
 * count, b_j, sampling) are the BxDF's (bxdf.h).
 */
struct glint_fit_lobes {
	/* Index of each lobe's first RGB (albedo) parameter. */
	const int *param;
	/* Whether lobe j depends on any parameter (else it is cached). */
	const int *varies;
	/* Optional, the same as the BxDF's lobe functions sharing work
	 * (glint_lobe_value_pdf(), glint_lobe_sample_value() fall back on
	 * them): b_j at wi and pdf_lobe (pdf may be NULL); sample_lobe, b_j
	 * at the direction drawn in *bj.  dlog (may be NULL, here and in
	 * from_geometry) gets factor_dlog's value at those directions,
	 * sharing the lobe's work. */
	double (*value_pdf)(const double *p, int j, struct vec3 wo,
			    struct vec3 wi, double *pdf, double *dlog);
	double (*sample_value)(const double *p, int j, struct vec3 wo,
			       const double u[2], struct vec3 *wi, double *bj,
			       double *dlog);
	/* Optional: value_pdf's b_j (and dlog) at n directions wi given
	 * as x[], y[], z[], without the pdf, in one loop that vectorises
	 * (glint_lobe_values() falls back on value_pdf). */
	void (*values)(const double *p, int j, struct vec3 wo, int n,
		       const double *x, const double *y, const double *z,
		       double *b, double *dlog);
	/* Optional: sample_value at n uniform pairs (u0[k], u1[k]), each
	 * for its own wo[k], in one loop that vectorises: the directions
	 * into x, y, z, b_j into b, dlog (may be NULL), the pdf into pdf; 0
	 * for a lobe it does not cover (glint_lobe_sample_values() falls
	 * back on sample_value). */
	int (*sample_values)(const double *p, int j, int n,
			     const struct vec3 *wo, const double *u0,
			     const double *u1, double *x, double *y, double *z,
			     double *pdf, double *b, double *dlog);
	/* Optional, for directions fixed across evaluations (the fitter's
	 * env samples): what of the varying lobes' value and pdf at wo, wi
	 * depends on no parameter, in g[4] (all 0 where the lobes are), and
	 * lobe j's value and pdf_lobe (pdf may be NULL) from it. */
	void (*geometry)(struct vec3 wo, struct vec3 wi, float g[4]);
	double (*from_geometry)(const double *p, int j, const float g[4],
				double *pdf, double *dlog);
	/* Optional: a parameter that enters the varying lobes only as a
	 * factor of their value at each pair of directions (an ior,
	 * through Fresnel at o.h), leaving their sampling and pdf as they
	 * are; factor_dlog gives d log b_j / d p[factor_param] at wo, wi.
	 * The fitter then shades lobe j's derivative by it on the same
	 * samples as its value (glint_shade_cache_lobes_d()).  Unset
	 * (factor_dlog NULL): that parameter's derivative is a finite
	 * difference. */
	int factor_param;
	double (*factor_dlog)(const double *p, int j, struct vec3 wo,
			      struct vec3 wi);
	/* Index of the parameter that sets the lobe's angular width (a
	 * roughness), or -1: coarse fitting levels bound it from below by
	 * what they can resolve. */
	int roughness_param;
	/* The glossy lobes' microfacet distribution, NULL when there are
	 * none; width_param[j] the index of lobe j's width parameter (-1
	 * for a lobe that is not of the distribution).  With them,
	 * glint_lobe_extent(), glint_lobe_width() and glint_lobe_widen(). */
	const struct glint_microfacet *microfacet;
	const int *width_param;
};

/*
 * An appearance model: named parameters with bounds, and either a BRDF
 * (`bxdf`, whose self is the parameter vector, with the fitter's `lobes`)
 * or, for a transparent sphere, neither (bxdf and lobes NULL): the
 * dielectric is rendered and fitted by following its paths
 * (fit/render/dielectric_paths.h), see glint_model_is_transparent().
 * Models are static tables, never freed, shared by all threads.
 */
struct glint_model {
	/* Name used in material files and on the command line. */
	const char *name;
	/* The conventions, stated for params.json and the docs. */
	const char *conventions;
	/* Number of parameters and their descriptions. */
	int nparams;
	const struct glint_param *params;
	const struct glint_bxdf_ops *bxdf;
	const struct glint_fit_lobes *lobes;
};

extern const struct glint_model glint_model_lambert;
extern const struct glint_model glint_model_torrance_sparrow;
extern const struct glint_model glint_model_ts_constant_fresnel;
extern const struct glint_model glint_model_dielectric;
extern const struct glint_model glint_model_ggx;
extern const struct glint_model glint_model_oren_nayar;
extern const struct glint_model glint_model_two_lobe;

/* Whether m is the transparent sphere (no BRDF: its paths are followed). */
static inline int glint_model_is_transparent(const struct glint_model *m)
{
	return !m->bxdf;
}

/* The index of m's roughness parameter (struct glint_fit_lobes), -1 when
 * it has none (the transparent sphere too). */
static inline int glint_model_roughness_param(const struct glint_model *m)
{
	return m->lobes ? m->lobes->roughness_param : -1;
}

/* The BRDF of model m (not transparent) at parameters p, which must
 * outlive it. */
static inline struct glint_bxdf glint_model_bxdf(const struct glint_model *m,
						 const double *p)
{
	return (struct glint_bxdf){ m->bxdf, p };
}

/*
 * Lobe j's extent (the angle from the mirror direction beyond which it is
 * below 1e-12 of its peak) and core width (the standard deviation of its
 * reflected directions, radians), each <= 0 when the lobe has none (not
 * of the model's microfacet distribution, or unbounded); and p with that
 * width widened to sqrt(width^2 + s^2) in place, as if a Gaussian of s
 * were convolved into the lobe (the spread of a light's quadrature
 * points; fit/render/shade_cache.c).  From the model's microfacet
 * descriptor (microfacet.h).
 */
double glint_lobe_extent(const struct glint_model *m, const double *p, int j);
double glint_lobe_width(const struct glint_model *m, const double *p, int j);
void glint_lobe_widen(const struct glint_model *m, double *p, int j, double s);

/* Cosine-weighted direction about +z from two uniforms; returns its pdf. */
double glint_sample_cosine(const double u[2], struct vec3 *wi);

/*
 * For a linear model (nlobes > 0): f as the sum over lobes of albedo_j b_j;
 * and sampling that picks lobe j in proportion to the luminance of its
 * albedo, times spec_scale for every lobe past the first (the specular
 * lobes' F(o.n), or 1; each lobe with weight gets at least 5 %), then
 * draws from it.  The pdf is the mixture's, sum_j P(j) pdf_lobe_j.
 */
void glint_lobes_eval(const struct glint_model *m, const double *p,
		      struct vec3 wo, struct vec3 wi, double f[3]);
double glint_lobes_pdf(const struct glint_model *m, const double *p,
		       double spec_scale, struct vec3 wo, struct vec3 wi);
double glint_lobes_sample(const struct glint_model *m, const double *p,
			  double spec_scale, struct vec3 wo, const double u[3],
			  struct vec3 *wi);

/* Lobe j of a linear model: b_j at wi and pdf_lobe there (pdf may be
 * NULL); sample_lobe with b_j at the direction drawn (0 when none).
 * dlog (may be NULL; only for a model with factor_dlog) gets d log b_j /
 * d p[factor_param] there. */
double glint_lobe_value_pdf(const struct glint_model *m, const double *p, int j,
			    struct vec3 wo, struct vec3 wi, double *pdf,
			    double *dlog);
/* glint_lobe_sample_value() at n uniform pairs (u0[k], u1[k]), each for
 * its own wo[k]: the directions drawn into (x[k], y[k], z[k]), b_j there
 * into b[k], dlog into dlog[k] (unless NULL), the pdf into pdf[k] (0
 * where none). */
void glint_lobe_sample_values(const struct glint_model *m, const double *p,
			      int j, int n, const struct vec3 *wo,
			      const double *u0, const double *u1, double *x,
			      double *y, double *z, double *pdf, double *b,
			      double *dlog);
/* glint_lobe_value_pdf()'s b_j (into b[k]) and dlog (into dlog[k], unless
 * NULL) at n directions (x[k], y[k], z[k]), without the pdf. */
void glint_lobe_values(const struct glint_model *m, const double *p, int j,
		       struct vec3 wo, int n, const double *x, const double *y,
		       const double *z, double *b, double *dlog);
double glint_lobe_sample_value(const struct glint_model *m, const double *p,
			       int j, struct vec3 wo, const double u[2],
			       struct vec3 *wi, double *bj, double *dlog);

/* Model by name (a static table entry, never freed), or NULL. */
const struct glint_model *glint_model_find(const char *name);
/* "lambert, torrance-sparrow" for messages (static storage). */
const char *glint_model_names(void);
/* The models' names, NULL-terminated (static). */
const char *const *glint_model_list(void);

/*
 * A material document: {"model": NAME, <json_key>: value or [r, g, b], ...}
 * (the shape of ../shared/data/paper-table1.json entries; "name" is allowed).
 * Missing parameters take their defaults; values outside the bounds are
 * errors naming file, key and bounds.
 */
int glint_material_from_json(const char *file, const char *where, json_t *obj,
			     const struct glint_model **model, double *params);
/* Read a material file (or a fit's params.json: its "material"), or one
 * entry of a Table-1 style file when `entry` is not NULL (matched against
 * "materials"[].name).  *model is static; params holds
 * GLINT_MAX_PARAMS values. */
int glint_material_load(const char *path, const char *entry,
			const struct glint_model **model, double *params);
/* The material as JSON (same shape as read). Caller json_decref()s. */
json_t *glint_material_to_json(const struct glint_model *model,
			       const double *params);

#endif
