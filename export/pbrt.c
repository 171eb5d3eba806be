/* SPDX-License-Identifier: MIT */
/* pbrt-v4: a mix of diffuse and conductor (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"
#include "fit/brdf/microfacet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { P_R = 0, P_AMOUNT = 3, P_ALPHA = 4, P_ETA = 5, P_NX = 8 };

/* pbrt-v4's conductor is Trowbridge-Reitz with the height-correlated
 * Smith G: glint's own GGX lobe, with eta per channel. */
static void pbrt_brdf(const double *x, struct vec3 wo, struct vec3 wi,
		      double f[3])
{
	double a = x[P_AMOUNT];

	for (int c = 0; c < 3; c++)
		f[c] = (1 - a) * x[P_R + c] / M_PI +
		       a * glint_ggx_lobe(x[P_ALPHA], x[P_ETA + c], wo, wi);
}

static void pbrt_eval(const double *x, const struct glint_export *e,
		      const void *view, struct vec3 wo, struct vec3 wi,
		      struct vec3 h, double f[3])
{
	(void)e;
	(void)view;
	(void)h;
	pbrt_brdf(x, wo, wi, f);
}

static int pbrt_start(const struct glint_model *model, const double *p,
		      const struct glint_export *e, double *x, double *lo,
		      double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	double a = fmin(0.95, fmax(0.05, ksm));
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, P_R + c, kd[c] / (1 - a), 0, 1);
		glint_export_set(x, lo, hi, P_ETA + c, e->ior, 1.01, 10);
	}
	glint_export_set(x, lo, hi, P_AMOUNT, a, 0, 1);
	/* pbrt-v4 treats alpha below 1e-3 as a mirror. */
	glint_export_set(x, lo, hi, P_ALPHA, w, 2e-3, 1);
	return P_NX;
}

static char *pbrt_dielectric(const struct glint_export *e, const char *name,
			     const char *source,
			     const struct glint_model *model)
{
	char *s = NULL;

	if (asprintf(&s,
		     "# glint export of %s (%s) for pbrt-v4.\n"
		     "# refit_relative_rms %.4f: %s.\n"
		     "# Use (Integrator \"volpath\"; units: metres): "
		     "Include \"this file\", then\n"
		     "#   AttributeBegin\n"
		     "#     MediumInterface \"%s.interior\" \"\"\n"
		     "#     NamedMaterial \"%s\"\n"
		     "#     Shape \"sphere\" \"float radius\" %.6g\n"
		     "#   AttributeEnd\n"
		     "MakeNamedMedium \"%s.interior\"\n"
		     "    \"string type\" \"homogeneous\"\n"
		     "    \"rgb sigma_a\" [ %.6g %.6g %.6g ]\n"
		     "    \"rgb sigma_s\" [ 0 0 0 ]\n"
		     "    \"float scale\" 1\n"
		     "MakeNamedMaterial \"%s\"\n"
		     "    \"string type\" \"dielectric\"\n"
		     "    \"float eta\" %.6g\n",
		     source, model->name, e->residual, glint_export_note_of(e),
		     name, name, e->diameter_m / 2, name,
		     glint_export_sigma_a(e, 0), glint_export_sigma_a(e, 1),
		     glint_export_sigma_a(e, 2), name, e->ior) < 0)
		return NULL;
	return s;
}

static char *pbrt_text(const struct glint_export *e, const char *name,
		       const char *source, const struct glint_model *model)
{
	const double *x = e->x;
	char *s = NULL;

	if (e->dielectric)
		return pbrt_dielectric(e, name, source, model);
	if (asprintf(&s,
		     "# glint export of %s (%s) for pbrt-v4.\n"
		     "# refit_relative_rms %.4f: %s.\n"
		     "# Use after WorldBegin: Include \"this file\", then "
		     "NamedMaterial \"%s\".\n"
		     "MakeNamedMaterial \"%s.diffuse\"\n"
		     "    \"string type\" \"diffuse\"\n"
		     "    \"rgb reflectance\" [ %.6g %.6g %.6g ]\n"
		     "MakeNamedMaterial \"%s.specular\"\n"
		     "    \"string type\" \"conductor\"\n"
		     "    \"float roughness\" %.6g\n"
		     "    \"bool remaproughness\" false\n"
		     "    \"rgb eta\" [ %.6g %.6g %.6g ]\n"
		     "    \"rgb k\" [ 0 0 0 ]\n"
		     "MakeNamedMaterial \"%s\"\n"
		     "    \"string type\" \"mix\"\n"
		     "    \"string materials\" [ \"%s.diffuse\" "
		     "\"%s.specular\" ]\n"
		     "    \"float amount\" %.6g\n",
		     source, model->name, e->residual, glint_export_note_of(e),
		     name, name, x[P_R], x[P_R + 1], x[P_R + 2], name,
		     x[P_ALPHA], x[P_ETA], x[P_ETA + 1], x[P_ETA + 2], name,
		     name, name, x[P_AMOUNT]) < 0)
		return NULL;
	return s;
}

static json_t *pbrt_params(const struct glint_export *e)
{
	const double *x = e->x;
	return json_pack("{s:[f,f,f], s:f, s:f, s:[f,f,f]}", "reflectance",
			 x[P_R], x[P_R + 1], x[P_R + 2], "amount", x[P_AMOUNT],
			 "roughness", x[P_ALPHA], "eta", x[P_ETA], x[P_ETA + 1],
			 x[P_ETA + 2]);
}

const struct glint_export_target glint_export_target_pbrt = {
	.name = "pbrt",
	.extension = ".pbrt",
	.brdf = pbrt_eval,
	.view = NULL,
	.start = pbrt_start,
	.text = pbrt_text,
	.params = pbrt_params,
	.schlick = 0,
};
