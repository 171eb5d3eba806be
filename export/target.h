/* SPDX-License-Identifier: MIT */
#ifndef GLINT_EXPORT_TARGET_H
#define GLINT_EXPORT_TARGET_H

/*
 * One export target: a renderer's material model and the file that
 * states it (private to export/).  export.c refits the target's
 * parameters x to glint's BRDF through brdf(), starting from start(), and
 * writes the file with text(); adding a target is a file with one of
 * these, its line in export.c's table and its name in export.h's enum.
 *
 * All functions are pure (no state, safe from any thread); text() and
 * params() return new storage the caller frees (free(), json_decref()),
 * or NULL when out of memory.
 *
 * Errors: a target's start and file functions return a negative errno with
 * glint_error_msg().  Threads: targets are static and re-entrant.  Who
 * frees: file text with free().
 */

#include "export/export.h"

#include <jansson.h>

/* What view() may cache per view direction, at most. */
#define GLINT_EXPORT_VIEW_BYTES 64

struct glint_export_target {
	const char *name;      /* as on the command line: "gltf" */
	const char *extension; /* of the file text() writes: ".gltf" */
	/* The target's f[3] at parameters x for wo, wi above the surface
	 * and h their half vector; view is what view() cached for wo.z, or
	 * NULL (then computed here). */
	void (*brdf)(const double *x, const struct glint_export *e,
		     const void *view, struct vec3 wo, struct vec3 wi,
		     struct vec3 h, double f[3]);
	/* Optional: what brdf() needs per view cosine mu, into view. */
	void (*view)(const double *x, double mu, void *view);
	/* x's start and bounds from glint's (model, p): the number of
	 * parameters. */
	int (*start)(const struct glint_model *model, const double *p,
		     const struct glint_export *e, double *x, double *lo,
		     double *hi);
	/* The file: the material `name` (already a safe identifier). */
	char *(*text)(const struct glint_export *e, const char *name,
		      const char *source, const struct glint_model *model);
	/* The target's own parameters for params.json. */
	json_t *(*params)(const struct glint_export *e);
	/* The target's dielectric interface is Schlick's approximation
	 * (else the exact Fresnel term: residual 0). */
	int schlick;
};

extern const struct glint_export_target glint_export_target_gltf,
	glint_export_target_mitsuba, glint_export_target_pbrt,
	glint_export_target_blender, glint_export_target_materialx;

/* The target of a format; NULL when there is none. */
const struct glint_export_target *
glint_export_target_of(enum glint_export_format format);

/* What the targets share (export.c). */
double glint_export_schlick_f0(double ior);
/* glint's diffuse and specular albedos, their mean ksm and the lobe's
 * width w (0.1 without one). */
void glint_export_lobes(const struct glint_model *model, const double *p,
			double kd[3], double ks[3], double *ksm, double *w);
/* The model's parameter called name, or fallback when it has none. */
double glint_export_model_param(const struct glint_model *m, const double *p,
				const char *name, double fallback);
/* x[k] = v clamped to [l, h], with those bounds. */
void glint_export_set(double *x, double *lo, double *hi, int k, double v,
		      double l, double h);
/* A transparent sphere's absorption per metre of channel c, and its
 * largest. */
double glint_export_sigma_a(const struct glint_export *e, int c);
double glint_export_sigma_a_max(const struct glint_export *e);
/* Mitsuba 3's (and Cycles's) microfacet terms (export/mitsuba.c): Smith
 * G1 for direction v and microfacet normal h, Beckmann's rational
 * approximation or GGX's exact form, and the distribution D. */
double glint_export_g1(int ggx, double alpha, struct vec3 v, struct vec3 h);
double glint_export_d(int ggx, double alpha, double cos_h);
/* The note every file carries on how its parameters were obtained. */
const char *glint_export_note_of(const struct glint_export *e);

/* export/blender_preview.py, embedded at build time. */
extern const char glint_export_blender_script[];

#endif
