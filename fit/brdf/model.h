/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_BRDF_MODEL_H
#define GLINT_FIT_BRDF_MODEL_H

/*
 * Appearance models behind one interface.  A model is a static const ops
 * table; adding one is one file plus a line in model.c's registry.
 *
 * Directions are in the local shading frame (normal = +z), unit length,
 * pointing away from the surface: wo towards the viewer, wi towards the
 * light.  Parameter vectors are plain double arrays laid out as `params`.
 */

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

struct glint_model_ops {
	/* Name used in material files and on the command line. */
	const char *name;
	/* The conventions, stated for params.json and the docs. */
	const char *conventions;
	/* Number of parameters and their descriptions. */
	int nparams;
	const struct glint_param *params;
	/* BRDF value f(wo, wi), RGB, per steradian; 0 below the surface. */
	void (*eval)(const double *p, struct vec3 wo, struct vec3 wi,
		     double f[3]);
	/* Draw wi for wo from three uniforms; returns its solid-angle pdf,
	 * 0 if no direction was produced. */
	double (*sample)(const double *p, struct vec3 wo, const double u[3],
			 struct vec3 *wi);
	/* The pdf sample() has for wi. */
	double (*pdf)(const double *p, struct vec3 wo, struct vec3 wi);

	/*
	 * Optional linear structure, used by the fitter: f = sum over lobes j
	 * of albedo_j (an RGB parameter triple) times a scalar lobe b_j that
	 * depends only on the other parameters.  nlobes = 0 when the model
	 * is not of that form.
	 */
	int nlobes;
	/* Index of each lobe's first RGB parameter. */
	const int *lobe_param;
	/* Whether lobe j depends on any parameter (else it is cached). */
	const int *lobe_varies;
	/* b_j(wo, wi) for every lobe j into b[nlobes]. */
	void (*eval_lobes)(const double *p, struct vec3 wo, struct vec3 wi,
			   double *b);
	/* Sample lobe j (density ~ b_j cos where possible); returns the
	 * pdf, 0 if no direction was produced. */
	double (*sample_lobe)(const double *p, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi);
	double (*pdf_lobe)(const double *p, int j, struct vec3 wo,
			   struct vec3 wi);
	/* Optional, the same sharing work (glint_lobe_value_pdf(),
	 * glint_lobe_sample_value() fall back on the three above): b_j at wi
	 * and pdf_lobe (pdf may be NULL); sample_lobe, b_j at the direction
	 * drawn in *bj. */
	double (*lobe_value_pdf)(const double *p, int j, struct vec3 wo,
				 struct vec3 wi, double *pdf);
	double (*sample_lobe_value)(const double *p, int j, struct vec3 wo,
				    const double u[2], struct vec3 *wi,
				    double *bj);
	/* Optional, for directions fixed across evaluations (the fitter's
	 * env samples): what of the varying lobes' value and pdf at wo, wi
	 * depends on no parameter, in g[4] (all 0 where the lobes are), and
	 * lobe j's value and pdf_lobe (pdf may be NULL) from it. */
	void (*lobe_geometry)(struct vec3 wo, struct vec3 wi, float g[4]);
	double (*lobe_from_geometry)(const double *p, int j, const float g[4],
				     double *pdf);
	/* Index of the parameter that sets the lobe's angular width (a
	 * roughness), or -1: coarse fitting levels bound it from below by
	 * what they can resolve. */
	int roughness_param;
	/* Angle (radians) from the mirror direction beyond which lobe j is
	 * below 1e-12 of its peak, or <= 0 when it has no such bound. */
	double (*lobe_extent)(const double *p, int j);
	/* Lobe j's core width: the standard deviation (radians) of its
	 * reflected directions about the mirror direction; and p with that
	 * width widened to sqrt(width^2 + s^2) in place, as if a Gaussian
	 * of s were convolved into the lobe (the spread of a light's
	 * quadrature points).  NULL: the fitter does not integrate lobe j's
	 * hot texels over pixel footprints (fit/render/shade_cache.c). */
	double (*lobe_width)(const double *p, int j);
	void (*lobe_widen)(double *p, int j, double s);
	/* A transparent sphere (fit/render/dielectric_paths.h): no BRDF (eval,
	 * sample and pdf are NULL); rendered and fitted by following its paths.
	 */
	int transparent;
};

extern const struct glint_model_ops glint_model_lambert;
extern const struct glint_model_ops glint_model_torrance_sparrow;
extern const struct glint_model_ops glint_model_ts_constant_fresnel;
extern const struct glint_model_ops glint_model_dielectric;
extern const struct glint_model_ops glint_model_ggx;
extern const struct glint_model_ops glint_model_oren_nayar;
extern const struct glint_model_ops glint_model_two_lobe;

/* Cosine-weighted direction about +z from two uniforms; returns its pdf. */
double glint_sample_cosine(const double u[2], struct vec3 *wi);

/*
 * For a linear model (nlobes > 0): f as the sum over lobes of albedo_j b_j;
 * and sampling that picks lobe j in proportion to the luminance of its
 * albedo, times spec_scale for every lobe past the first (the specular
 * lobes' F(o.n), or 1; each lobe with weight gets at least 5 %), then
 * draws from it.  The pdf is the mixture's, sum_j P(j) pdf_lobe_j.
 */
void glint_lobes_eval(const struct glint_model_ops *m, const double *p,
		      struct vec3 wo, struct vec3 wi, double f[3]);
double glint_lobes_pdf(const struct glint_model_ops *m, const double *p,
		       double spec_scale, struct vec3 wo, struct vec3 wi);
double glint_lobes_sample(const struct glint_model_ops *m, const double *p,
			  double spec_scale, struct vec3 wo, const double u[3],
			  struct vec3 *wi);

/* Lobe j of a linear model: b_j at wi and pdf_lobe there (pdf may be
 * NULL); sample_lobe with b_j at the direction drawn (0 when none). */
double glint_lobe_value_pdf(const struct glint_model_ops *m, const double *p,
			    int j, struct vec3 wo, struct vec3 wi, double *pdf);
double glint_lobe_sample_value(const struct glint_model_ops *m, const double *p,
			       int j, struct vec3 wo, const double u[2],
			       struct vec3 *wi, double *bj);

/* Model by name (a static table entry, never freed), or NULL. */
const struct glint_model_ops *glint_model_find(const char *name);
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
			     const struct glint_model_ops **model,
			     double *params);
/* Read a material file (or a fit's params.json: its "material"), or one
 * entry of a Table-1 style file when `entry` is not NULL (matched against
 * "materials"[].name).  *model is static; params holds
 * GLINT_MAX_PARAMS values. */
int glint_material_load(const char *path, const char *entry,
			const struct glint_model_ops **model, double *params);
/* The material as JSON (same shape as read). Caller json_decref()s. */
json_t *glint_material_to_json(const struct glint_model_ops *model,
			       const double *params);

#endif
