/* SPDX-License-Identifier: MIT */
/* glTF 2.0: the metallic-roughness material with KHR_materials_ior and
 * _specular; a transparent sphere with _transmission and _volume
 * (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { G_BASE = 0, G_ROUGH = 3, G_SPEC = 4, G_SCOL = 5, G_NX = 8 };

/* glTF: separable Smith visibility of the specification. */
static double gltf_v(double nl, double nv, double a2)
{
	nl = fabs(nl);
	nv = fabs(nv);
	return 1 / ((nl + sqrt(a2 + (1 - a2) * nl * nl)) *
		    (nv + sqrt(a2 + (1 - a2) * nv * nv)));
}

static void gltf_brdf(const double *x, double ior, struct vec3 wo,
		      struct vec3 wi, struct vec3 h, double f[3])
{
	double a = x[G_ROUGH] * x[G_ROUGH], a2 = a * a;
	double t = h.z * h.z * (a2 - 1) + 1;
	double dv = a2 / (M_PI * t * t) * gltf_v(wi.z, wo.z, a2);
	double w5 = pow(1 - fabs(v3_dot(wo, h)), 5);
	double f0 = glint_export_schlick_f0(ior), s = x[G_SPEC];

	for (int c = 0; c < 3; c++) {
		double c0 = fmin(f0 * x[G_SCOL + c], 1) * s;
		double F = c0 + (s - c0) * w5;
		f[c] = (1 - F) * x[G_BASE + c] / M_PI + F * dv;
	}
}

static void gltf_eval(const double *x, const struct glint_export *e,
		      const void *view, struct vec3 wo, struct vec3 wi,
		      struct vec3 h, double f[3])
{
	(void)view;
	gltf_brdf(x, e->ior, wo, wi, h, f);
}

static int gltf_start(const struct glint_model *model, const double *p,
		      const struct glint_export *e, double *x, double *lo,
		      double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, G_BASE + c, kd[c], 0, 1);
		glint_export_set(
			x, lo, hi, G_SCOL + c, ksm > 0 ? ks[c] / ksm : 1, 0,
			1 / glint_export_schlick_f0(fmax(e->ior, 1.01)));
	}
	glint_export_set(x, lo, hi, G_ROUGH, sqrt(w), 0.02, 1);
	glint_export_set(x, lo, hi, G_SPEC, ksm, 0, 1);
	return G_NX;
}

/* glTF: KHR_materials_transmission and _volume (attenuation colour T at
 * distance d: exactly T per diameter). */
static json_t *gltf_dielectric(const struct glint_export *e, const char *name,
			       json_t *glint)
{
	const double *x = e->x, d = e->diameter_m;
	json_t *mat = json_pack(
		"{s:s, s:{s:[f,f,f,f], s:f, s:f}, s:{s:{s:f}, s:{s:f}, "
		"s:{s:f, s:f, s:[f,f,f]}}, s:{s:o}}",
		"name", name, "pbrMetallicRoughness", "baseColorFactor", 1.0,
		1.0, 1.0, 1.0, "metallicFactor", 0.0, "roughnessFactor", 0.0,
		"extensions", "KHR_materials_ior", "ior", e->ior,
		"KHR_materials_transmission", "transmissionFactor", 1.0,
		"KHR_materials_volume", "thicknessFactor", d,
		"attenuationDistance", d, "attenuationColor", x[0], x[1], x[2],
		"extras", "glint", glint);
	return json_pack("{s:{s:s, s:s}, s:[s, s, s], s:[o]}", "asset",
			 "version", "2.0", "generator", "glint export",
			 "extensionsUsed", "KHR_materials_ior",
			 "KHR_materials_transmission", "KHR_materials_volume",
			 "materials", mat);
}

static json_t *gltf_document(const struct glint_export *e, const char *name,
			     const char *source,
			     const struct glint_model *model)
{
	const double *x = e->x;
	json_t *glint = json_pack("{s:s, s:s, s:f, s:s}", "source", source,
				  "model", model->name, "refit_relative_rms",
				  e->residual, "note", glint_export_note_of(e));
	if (e->dielectric)
		return gltf_dielectric(e, name, glint);
	json_t *mat = json_pack(
		"{s:s, s:{s:[f,f,f,f], s:f, s:f}, s:{s:{s:f}, s:{s:f, "
		"s:[f,f,f]}}, s:{s:o}}",
		"name", name, "pbrMetallicRoughness", "baseColorFactor",
		x[G_BASE], x[G_BASE + 1], x[G_BASE + 2], 1.0, "metallicFactor",
		0.0, "roughnessFactor", x[G_ROUGH], "extensions",
		"KHR_materials_ior", "ior", e->ior, "KHR_materials_specular",
		"specularFactor", x[G_SPEC], "specularColorFactor", x[G_SCOL],
		x[G_SCOL + 1], x[G_SCOL + 2], "extras", "glint", glint);
	return json_pack("{s:{s:s, s:s}, s:[s, s], s:[o]}", "asset", "version",
			 "2.0", "generator", "glint export", "extensionsUsed",
			 "KHR_materials_ior", "KHR_materials_specular",
			 "materials", mat);
}

static char *gltf_text(const struct glint_export *e, const char *name,
		       const char *source, const struct glint_model *model)
{
	json_t *doc = gltf_document(e, name, source, model);
	char *text = doc ? json_dumps(doc, JSON_INDENT(2)) : NULL;
	json_decref(doc);
	return text;
}

static json_t *gltf_params(const struct glint_export *e)
{
	const double *x = e->x;
	return json_pack("{s:[f,f,f], s:f, s:f, s:f, s:[f,f,f]}", "base_color",
			 x[G_BASE], x[G_BASE + 1], x[G_BASE + 2], "roughness",
			 x[G_ROUGH], "ior", e->ior, "specular", x[G_SPEC],
			 "specular_color", x[G_SCOL], x[G_SCOL + 1],
			 x[G_SCOL + 2]);
}

const struct glint_export_target glint_export_target_gltf = {
	.name = "gltf",
	.extension = ".gltf",
	.brdf = gltf_eval,
	.view = NULL,
	.start = gltf_start,
	.text = gltf_text,
	.params = gltf_params,
	.schlick = 1,
};
