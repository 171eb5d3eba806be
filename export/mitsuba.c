/* SPDX-License-Identifier: MIT */
/* Mitsuba 3: a blendbsdf of diffuse and roughconductor (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"
#include "fit/brdf/microfacet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { M_KD = 0, M_ALPHA = 3, M_KS = 4, M_NX = 7 };

/* Mitsuba 3's Smith G1 for direction v and microfacet normal h. */
double glint_export_g1(int ggx, double alpha, struct vec3 v, struct vec3 h)
{
	if (v3_dot(v, h) * v.z <= 0)
		return 0;
	double xy = alpha * alpha * (v.x * v.x + v.y * v.y);
	if (xy == 0)
		return 1;
	double t2 = xy / (v.z * v.z);
	if (ggx)
		return 2 / (1 + sqrt(1 + t2));
	double a = 1 / sqrt(t2);
	return a >= 1.6 ? 1
			: (3.535 * a + 2.181 * a * a) /
				  (1 + 2.276 * a + 2.577 * a * a);
}

double glint_export_d(int ggx, double alpha, double cos_h)
{
	double c2 = cos_h * cos_h, a2 = alpha * alpha;
	if (ggx) {
		double t = (1 - c2) / a2 + c2;
		return 1 / (M_PI * a2 * t * t);
	}
	return glint_beckmann_d(cos_h, alpha);
}

static void mitsuba_brdf(const double *x, double ior, int ggx, struct vec3 wo,
			 struct vec3 wi, struct vec3 h, double f[3])
{
	double alpha = x[M_ALPHA];
	double s = glint_export_d(ggx, alpha, h.z) *
		   glint_export_g1(ggx, alpha, wi, h) *
		   glint_export_g1(ggx, alpha, wo, h) *
		   glint_fresnel_dielectric(v3_dot(wi, h), ior) /
		   (4 * wi.z * wo.z);

	for (int c = 0; c < 3; c++)
		f[c] = x[M_KD + c] / M_PI + x[M_KS + c] * s;
}

static void mitsuba_eval(const double *x, const struct glint_export *e,
			 const void *view, struct vec3 wo, struct vec3 wi,
			 struct vec3 h, double f[3])
{
	(void)view;
	mitsuba_brdf(x, e->ior, e->ggx, wo, wi, h, f);
}

static int mitsuba_start(const struct glint_model *model, const double *p,
			 const struct glint_export *e, double *x, double *lo,
			 double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, M_KD + c, kd[c], 0, 1);
		glint_export_set(x, lo, hi, M_KS + c, ks[c], 0, 2);
	}
	glint_export_set(x, lo, hi, M_ALPHA, w, 1e-3, 1);
	return M_NX;
}

/*
 * Mitsuba's blend weight w and the nested reflectances kd / (1 - w) and
 * ks / w.  When max kd + max ks <= 1 every value fits in [0, 1]; else the
 * diffuse one is kept within it and the specular one exceeds 1 (written
 * as an unbounded srgb texture).
 */
static double mitsuba_split(const struct glint_export *e, double kd[3],
			    double ks[3])
{
	double md = 0, ms = 0, w;
	for (int c = 0; c < 3; c++) {
		md = fmax(md, e->x[M_KD + c]);
		ms = fmax(ms, e->x[M_KS + c]);
	}
	if (md + ms <= 0)
		w = 0.5;
	else if (md + ms <= 1)
		w = ms / (md + ms);
	else
		w = 1 - md;
	w = fmin(0.999, fmax(0.001, w));
	for (int c = 0; c < 3; c++) {
		kd[c] = e->x[M_KD + c] / (1 - w);
		ks[c] = e->x[M_KS + c] / w;
	}
	return w;
}

static char *mitsuba_dielectric(const struct glint_export *e, const char *name,
				const char *source,
				const struct glint_model *model)
{
	/* sigma_t as a colour within [0, 1] (a bounded RGB in spectral
	 * variants) times scale. */
	double top = fmax(glint_export_sigma_a_max(e), 1e-12);
	char *s = NULL;

	if (asprintf(&s,
		     "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
		     "<!-- glint export of %s (%s) for Mitsuba 3.\n"
		     "     refit_relative_rms %.4f: %s.\n"
		     "     Use (a volumetric integrator, e.g. volpath): "
		     "<include filename=\"this file\"/>, then\n"
		     "     <shape type=\"sphere\"> <float name=\"radius\" "
		     "value=\"%.6g\"/> <ref id=\"%s\"/>\n"
		     "     <ref name=\"interior\" id=\"%s_interior\"/> "
		     "</shape> (units: metres). -->\n"
		     "<scene version=\"3.0.0\">\n"
		     "    <bsdf type=\"dielectric\" id=\"%s\">\n"
		     "        <float name=\"int_ior\" value=\"%.6g\"/>\n"
		     "        <float name=\"ext_ior\" value=\"1\"/>\n"
		     "    </bsdf>\n"
		     "    <medium type=\"homogeneous\" id=\"%s_interior\">\n"
		     "        <rgb name=\"sigma_t\" value=\"%.6g, %.6g, "
		     "%.6g\"/>\n"
		     "        <float name=\"scale\" value=\"%.6g\"/>\n"
		     "        <float name=\"albedo\" value=\"0\"/>\n"
		     "    </medium>\n"
		     "</scene>\n",
		     source, model->name, e->residual, glint_export_note_of(e),
		     e->diameter_m / 2, name, name, name, e->ior, name,
		     glint_export_sigma_a(e, 0) / top,
		     glint_export_sigma_a(e, 1) / top,
		     glint_export_sigma_a(e, 2) / top, top) < 0)
		return NULL;
	return s;
}

static char *mitsuba_text(const struct glint_export *e, const char *name,
			  const char *source, const struct glint_model *model)
{
	if (e->dielectric)
		return mitsuba_dielectric(e, name, source, model);
	double kd[3], ks[3], w = mitsuba_split(e, kd, ks);
	int unbounded = ks[0] > 1 || ks[1] > 1 || ks[2] > 1;
	char *s = NULL;

	if (asprintf(&s,
		     "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
		     "<!-- glint export of %s (%s) for Mitsuba 3.\n"
		     "     refit_relative_rms %.4f: %s.\n"
		     "     Use: <include filename=\"this file\"/>, then "
		     "<ref id=\"%s\"/> in a shape. -->\n"
		     "<scene version=\"3.0.0\">\n"
		     "    <bsdf type=\"blendbsdf\" id=\"%s\">\n"
		     "        <float name=\"weight\" value=\"%.6g\"/>\n"
		     "        <bsdf type=\"diffuse\">\n"
		     "            <rgb name=\"reflectance\" "
		     "value=\"%.6g, %.6g, %.6g\"/>\n"
		     "        </bsdf>\n"
		     "        <bsdf type=\"roughconductor\">\n"
		     "            <string name=\"distribution\" "
		     "value=\"%s\"/>\n"
		     "            <float name=\"alpha\" value=\"%.6g\"/>\n"
		     "            <float name=\"eta\" value=\"%.6g\"/>\n"
		     "            <float name=\"k\" value=\"0\"/>\n"
		     "            <texture type=\"srgb\" "
		     "name=\"specular_reflectance\">\n"
		     "                <rgb name=\"color\" "
		     "value=\"%.6g, %.6g, %.6g\"/>\n"
		     "%s"
		     "            </texture>\n"
		     "        </bsdf>\n"
		     "    </bsdf>\n"
		     "</scene>\n",
		     source, model->name, e->residual, glint_export_note_of(e),
		     name, name, w, kd[0], kd[1], kd[2],
		     e->ggx ? "ggx" : "beckmann", e->x[M_ALPHA], e->ior, ks[0],
		     ks[1], ks[2],
		     unbounded ? "                <boolean name=\"unbounded\" "
				 "value=\"true\"/>\n"
			       : "") < 0)
		return NULL;
	return s;
}

static json_t *mitsuba_params(const struct glint_export *e)
{
	const double *x = e->x;
	double kd[3], ks[3], w = mitsuba_split(e, kd, ks);
	return json_pack("{s:f, s:[f,f,f], s:s, s:f, s:f, s:[f,f,f]}", "weight",
			 w, "reflectance", kd[0], kd[1], kd[2], "distribution",
			 e->ggx ? "ggx" : "beckmann", "alpha", x[M_ALPHA],
			 "eta", e->ior, "specular_reflectance", ks[0], ks[1],
			 ks[2]);
}

const struct glint_export_target glint_export_target_mitsuba = {
	.name = "mitsuba",
	.extension = ".xml",
	.brdf = mitsuba_eval,
	.view = NULL,
	.start = mitsuba_start,
	.text = mitsuba_text,
	.params = mitsuba_params,
	.schlick = 0,
};
