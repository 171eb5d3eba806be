/* SPDX-License-Identifier: MIT */
/* Blender 3.x (Cycles): a node material built by a Python script
 * (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"
#include "fit/brdf/microfacet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { B_KD = 0, B_ALPHA = 3, B_KS = 4, B_IOR = 7, B_NX = 8 };

/* Blender's node material: Cycles's Beckmann glossy (its G1 is Mitsuba's
 * rational approximation; o.h > 0 for every reflection), or its GGX one
 * with the separable Smith G1, weighed by the Fresnel node's F at the
 * view direction. */
static void blender_brdf(const double *x, int ggx, struct vec3 wo,
			 struct vec3 wi, struct vec3 h, double f[3])
{
	double alpha = x[B_ALPHA];
	double s = glint_export_d(ggx, alpha, h.z) *
		   glint_export_g1(ggx, alpha, wi, h) *
		   glint_export_g1(ggx, alpha, wo, h) *
		   glint_fresnel_dielectric(wo.z, x[B_IOR]) / (4 * wi.z * wo.z);

	for (int c = 0; c < 3; c++)
		f[c] = x[B_KD + c] / M_PI + x[B_KS + c] * s;
}

static void blender_eval(const double *x, const struct glint_export *e,
			 const void *view, struct vec3 wo, struct vec3 wi,
			 struct vec3 h, double f[3])
{
	(void)view;
	blender_brdf(x, e->ggx, wo, wi, h, f);
}

static int blender_start(const struct glint_model *model, const double *p,
			 const struct glint_export *e, double *x, double *lo,
			 double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, B_KD + c, kd[c], 0, 1);
		glint_export_set(x, lo, hi, B_KS + c, ks[c], 0, 10);
	}
	glint_export_set(x, lo, hi, B_ALPHA, w, 1e-3, 1);
	glint_export_set(x, lo, hi, B_IOR, e->ior, 1.01, 10);
	return B_NX;
}

/* The script after its constants: export/blender_preview.py, embedded
 * at build time. */
static char *blender_text(const struct glint_export *e, const char *name,
			  const char *source, const struct glint_model *model)
{
	const double *x = e->x;
	char *s = NULL;

	if (e->dielectric) {
		double dens = glint_export_sigma_a_max(e), col[3];
		for (int c = 0; c < 3; c++)
			col[c] = dens > 0
					 ? 1 - glint_export_sigma_a(e, c) / dens
					 : 1;
		if (asprintf(&s,
			     "# glint export of %s (%s) for Blender 3.x "
			     "(Cycles).\n"
			     "# refit_relative_rms %.4f: %s.\n"
			     "# Use: blender --background --python THIS.py "
			     "-- [--render OUT.png] [--env MAP] [--save "
			     "OUT.blend]\n"
			     "#   (units: metres; the preview sphere is the "
			     "measured one, %.6g m across)\n"
			     "KIND = \"dielectric\"\n"
			     "NAME = \"%s\"\n"
			     "IOR = %.6g\n"
			     "# Transmission per diameter (%.6g, %.6g, %.6g) "
			     "over DIAMETER metres\n"
			     "DIAMETER = %.6g\n"
			     "RADIUS = DIAMETER / 2\n"
			     "ABSORPTION_COLOR = (%.6g, %.6g, %.6g)\n"
			     "DENSITY = %.6g\n"
			     "REFIT_RELATIVE_RMS = %.6g\n\n%s",
			     source, model->name, e->residual,
			     glint_export_note_of(e), e->diameter_m, name,
			     e->ior, x[0], x[1], x[2], e->diameter_m, col[0],
			     col[1], col[2], dens, e->residual,
			     glint_export_blender_script) < 0)
			return NULL;
		return s;
	}
	if (asprintf(&s,
		     "# glint export of %s (%s) for Blender 3.x (Cycles; "
		     "EEVEE approximates it).\n"
		     "# refit_relative_rms %.4f: %s.\n"
		     "# Use: blender --background --python THIS.py -- "
		     "[--render OUT.png] [--env MAP] [--save OUT.blend]\n"
		     "#   or Blender's Text Editor: open it, Run Script (the "
		     "material appears in the file).\n"
		     "KIND = \"opaque\"\n"
		     "NAME = \"%s\"\n"
		     "RADIUS = 1.0\n"
		     "DISTRIBUTION = \"%s\"\n"
		     "DIFFUSE = (%.6g, %.6g, %.6g)\n"
		     "SPECULAR = (%.6g, %.6g, %.6g)\n"
		     "# The Glossy BSDF's roughness: alpha = "
		     "ROUGHNESS ** 2 = %.6g\n"
		     "ROUGHNESS = %.6g\n"
		     "IOR = %.6g\n"
		     "REFIT_RELATIVE_RMS = %.6g\n\n%s",
		     source, model->name, e->residual, glint_export_note_of(e),
		     name, e->ggx ? "GGX" : "BECKMANN", x[B_KD], x[B_KD + 1],
		     x[B_KD + 2], x[B_KS], x[B_KS + 1], x[B_KS + 2], x[B_ALPHA],
		     sqrt(x[B_ALPHA]), x[B_IOR], e->residual,
		     glint_export_blender_script) < 0)
		return NULL;
	return s;
}

static json_t *blender_params(const struct glint_export *e)
{
	const double *x = e->x;
	return json_pack("{s:[f,f,f], s:[f,f,f], s:f, s:f}", "diffuse", x[B_KD],
			 x[B_KD + 1], x[B_KD + 2], "glossy", x[B_KS],
			 x[B_KS + 1], x[B_KS + 2], "roughness",
			 sqrt(x[B_ALPHA]), "fresnel_ior", x[B_IOR]);
}

const struct glint_export_target glint_export_target_blender = {
	.name = "blender",
	.extension = ".py",
	.brdf = blender_eval,
	.view = NULL,
	.start = blender_start,
	.text = blender_text,
	.params = blender_params,
	.schlick = 0,
};
