/* SPDX-License-Identifier: MIT */
/* MaterialX 1.38: standard_surface as a dielectric over Oren-Nayar
 * (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"
#include "fit/brdf/microfacet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
	X_BASE = 0,
	X_DR = 3,
	X_ROUGH = 4,
	X_SPEC = 5,
	X_SCOL = 6,
	X_IOR = 9,
	X_NX = 10
};

/* MaterialX's lobe's directional albedos at view cosine mu: e with
 * Schlick's Fresnel from f0 (and 1 at grazing), ess with F = 1. */
struct mx_albedo {
	double mu, e, ess;
};

/* Integrated over half vectors distributed as D(h) cos(t_h) (GGX:
 * tan^2 t_h = a^2 u / (1 - u)) on a stratified 48 x 48 grid:
 * E = mean of F G2 (v.h) / (mu cos t_h) over reflections above the
 * surface. */
static void mx_albedo_at(double mu, double alpha, double ior,
			 struct mx_albedo *a)
{
	enum { N = 48 };
	double f0 = glint_export_schlick_f0(ior), e = 0, ess = 0;
	struct vec3 wo = v3(sqrt(fmax(0, 1 - mu * mu)), 0, mu);

	for (int i = 0; i < N; i++) {
		double u = (i + 0.5) / N, t2 = alpha * alpha * u / (1 - u);
		double ch = 1 / sqrt(1 + t2), sh = sqrt(t2) * ch;
		for (int j = 0; j < N; j++) {
			double ph = 2 * M_PI * (j + 0.5) / N;
			struct vec3 h = v3(sh * cos(ph), sh * sin(ph), ch);
			double vh = v3_dot(wo, h), lz = 2 * vh * ch - mu;
			if (vh <= 0 || lz <= 0)
				continue;
			double w = glint_ggx_g2(mu, lz, alpha) * vh / (mu * ch);
			ess += w;
			e += w * (f0 + (1 - f0) * pow(1 - vh, 5));
		}
	}
	a->mu = mu;
	a->e = e / (N * N);
	a->ess = ess / (N * N);
}

static void materialx_brdf(const double *x, const struct mx_albedo *a,
			   struct vec3 wo, struct vec3 wi, struct vec3 h,
			   double f[3])
{
	double alpha = fmax(x[X_ROUGH] * x[X_ROUGH], 1e-6), w = x[X_SPEC];
	double F = glint_fresnel_dielectric(v3_dot(wo, h), x[X_IOR]);
	double comp = a->ess > 0 ? 1 + F * (1 - a->ess) / a->ess : 1;
	double s = glint_ggx_d(h.z, alpha) * glint_ggx_g2(wo.z, wi.z, alpha) *
		   F * comp / (4 * wi.z * wo.z);
	double base = (1 - w * a->e * comp) * glint_oren_nayar(x[X_DR], wo, wi);

	for (int c = 0; c < 3; c++)
		f[c] = w * x[X_SCOL + c] * s + x[X_BASE + c] * base;
}

_Static_assert(sizeof(struct mx_albedo) <= GLINT_EXPORT_VIEW_BYTES,
	       "the albedos fit the view cache");

/* The albedos at this view, cached for the view's incident directions. */
static void materialx_view(const double *x, double mu, void *view)
{
	mx_albedo_at(mu, fmax(x[X_ROUGH] * x[X_ROUGH], 1e-6), x[X_IOR], view);
}

static void materialx_eval(const double *x, const struct glint_export *e,
			   const void *view, struct vec3 wo, struct vec3 wi,
			   struct vec3 h, double f[3])
{
	const struct mx_albedo *mx = view;
	struct mx_albedo own;
	(void)e;
	if (!mx || mx->mu != wo.z) {
		mx_albedo_at(wo.z, fmax(x[X_ROUGH] * x[X_ROUGH], 1e-6),
			     x[X_IOR], &own);
		mx = &own;
	}
	materialx_brdf(x, mx, wo, wi, h, f);
}

static int materialx_start(const struct glint_model *model, const double *p,
			   const struct glint_export *e, double *x, double *lo,
			   double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, X_BASE + c, kd[c], 0, 1);
		glint_export_set(x, lo, hi, X_SCOL + c, ks[c], 0, 1);
	}
	glint_export_set(
		x, lo, hi, X_DR,
		glint_export_model_param(model, p, "diffuse_roughness", 0), 0,
		1);
	glint_export_set(x, lo, hi, X_ROUGH, sqrt(w), 0.02, 1);
	glint_export_set(x, lo, hi, X_SPEC, ksm > 0 ? 1 : 0, 0, 1);
	glint_export_set(x, lo, hi, X_IOR, e->ior, 1.01, 10);
	return X_NX;
}

/* One standard_surface input: a float (n = 1) or a colour3 (n = 3). */
struct mx_input {
	const char *name;
	int n;
	double v[3];
};

static char *materialx_text(const struct glint_export *e, const char *name,
			    const char *source, const struct glint_model *model)
{
	/* MaterialX names: letters, digits and '_', not led by a digit. */
	char id[256];
	snprintf(id, sizeof(id), "%s%s",
		 name[0] >= '0' && name[0] <= '9' ? "m_" : "", name);
	for (char *c = id; *c; c++)
		if (*c == '-' || *c == '.')
			*c = '_';
	const double *x = e->x;
	int d = e->dielectric;
	const struct mx_input in[] = {
		{ "base", 1, { 1 } },
		{ "base_color",
		  3,
		  { d ? 1 : x[X_BASE], d ? 1 : x[X_BASE + 1],
		    d ? 1 : x[X_BASE + 2] } },
		{ "diffuse_roughness", 1, { d ? 0 : x[X_DR] } },
		{ "metalness", 1, { 0 } },
		{ "specular", 1, { d ? 1 : x[X_SPEC] } },
		{ "specular_color",
		  3,
		  { d ? 1 : x[X_SCOL], d ? 1 : x[X_SCOL + 1],
		    d ? 1 : x[X_SCOL + 2] } },
		{ "specular_roughness", 1, { d ? 0 : x[X_ROUGH] } },
		{ "specular_IOR", 1, { d ? e->ior : x[X_IOR] } },
		{ "specular_anisotropy", 1, { 0 } },
		{ "transmission", 1, { d } },
		{ "transmission_color",
		  3,
		  { d ? x[0] : 1, d ? x[1] : 1, d ? x[2] : 1 } },
		{ "transmission_depth", 1, { d ? e->diameter_m : 0 } },
		{ "subsurface", 1, { 0 } },
		{ "sheen", 1, { 0 } },
		{ "coat", 1, { 0 } },
		{ "thin_film_thickness", 1, { 0 } },
		{ "emission", 1, { 0 } },
	};
	char *s = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&s, &len);

	if (!f)
		return NULL;
	fprintf(f,
		"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
		"<!-- glint export of %s (%s) as a MaterialX "
		"standard_surface.\n"
		"     refit_relative_rms %.4f: %s.\n"
		"     %s -->\n"
		"<materialx version=\"1.38\">\n"
		"  <standard_surface name=\"%s_shader\" "
		"type=\"surfaceshader\">\n",
		source, model->name, e->residual, glint_export_note_of(e),
		d ? "Transmission: the sphere's diameter in scene units "
		    "(metres) is transmission_depth."
		  : "specular_roughness r: GGX alpha = r^2.",
		id);
	for (size_t k = 0; k < sizeof(in) / sizeof(in[0]); k++) {
		fprintf(f, "    <input name=\"%s\" type=\"%s\" value=\"",
			in[k].name, in[k].n == 3 ? "color3" : "float");
		for (int c = 0; c < in[k].n; c++)
			fprintf(f, "%s%.6g", c ? ", " : "", in[k].v[c]);
		fputs("\" />\n", f);
	}
	fprintf(f,
		"  </standard_surface>\n"
		"  <surfacematerial name=\"%s\" type=\"material\">\n"
		"    <input name=\"surfaceshader\" type=\"surfaceshader\" "
		"nodename=\"%s_shader\" />\n"
		"  </surfacematerial>\n"
		"</materialx>\n",
		id, id);
	if (fclose(f) != 0) {
		free(s);
		return NULL;
	}
	return s;
}

static json_t *materialx_params(const struct glint_export *e)
{
	const double *x = e->x;
	return json_pack("{s:[f,f,f], s:f, s:f, s:[f,f,f], s:f, s:f}",
			 "base_color", x[X_BASE], x[X_BASE + 1], x[X_BASE + 2],
			 "diffuse_roughness", x[X_DR], "specular", x[X_SPEC],
			 "specular_color", x[X_SCOL], x[X_SCOL + 1],
			 x[X_SCOL + 2], "specular_roughness", x[X_ROUGH],
			 "specular_IOR", x[X_IOR]);
}

const struct glint_export_target glint_export_target_materialx = {
	.name = "materialx",
	.extension = ".mtlx",
	.brdf = materialx_eval,
	.view = materialx_view,
	.start = materialx_start,
	.text = materialx_text,
	.params = materialx_params,
	.schlick = 0,
};
