/* SPDX-License-Identifier: MIT */
/* The fitted material refitted in a renderer's model (export.h). */
#include "export.h"

#include "fit/optim/lm.h"
#include "fit/render/sampling.h"

#include "core/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NWO  8
#define NWI  512
#define NDIR (NWO * NWI)

enum { B0 = 0, ROUGH = 3, SPEC = 4, SC0 = 5, NX = 8 };

static double schlick_f0(double ior)
{
	double r = (ior - 1) / (ior + 1);
	return r * r;
}

/* Separable Smith visibility of the glTF specification (see export.h). */
static double gltf_v(double nl, double nv, double a2)
{
	nl = fabs(nl);
	nv = fabs(nv);
	return 1 / ((nl + sqrt(a2 + (1 - a2) * nl * nl)) *
		    (nv + sqrt(a2 + (1 - a2) * nv * nv)));
}

void glint_gltf_brdf(const struct glint_gltf_material *g, struct vec3 wo,
		     struct vec3 wi, double f[3])
{
	f[0] = f[1] = f[2] = 0;
	if (!(wo.z > 0 && wi.z > 0))
		return;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double a = g->roughness * g->roughness, a2 = a * a;
	double t = h.z * h.z * (a2 - 1) + 1;
	double dv = a2 / (M_PI * t * t) * gltf_v(wi.z, wo.z, a2);
	double w5 = pow(1 - fabs(v3_dot(wo, h)), 5);
	double f0 = schlick_f0(g->ior);

	for (int c = 0; c < 3; c++) {
		double c0 = fmin(f0 * g->specular_color[c], 1) * g->specular;
		double F = c0 + (g->specular - c0) * w5;
		f[c] = (1 - F) * g->base[c] / M_PI + F * dv;
	}
}

/* The direction set and glint's BRDF on it. */
struct dirs {
	struct vec3 wo[NDIR], wi[NDIR];
	double w[NDIR];	    /* cos(theta_i) / sqrt(pdf N) */
	double f[NDIR * 3]; /* glint's f */
	double norm;	    /* sqrt(sum (f w)^2) */
	double ior;
};

static void dirs_build(const struct glint_model_ops *m, const double *p,
		       struct dirs *d)
{
	double sum = 0;
	for (int o = 0; o < NWO; o++) {
		double t = (5 + 10 * o) * M_PI / 180;
		struct vec3 wo = v3(sin(t), 0, cos(t));
		for (int k = 0; k < NWI; k++) {
			int i = o * NWI + k;
			double u[3];
			for (int j = 0; j < 3; j++)
				u[j] = glint_u01(glint_hash3(k, o, 71 + j));
			struct vec3 wi = v3(0, 0, 1);
			if (k % 2)
				glint_sample_cosine(u + 1, &wi);
			else if (m->sample(p, wo, u, &wi) <= 0)
				glint_sample_cosine(u + 1, &wi);
			double pdf = 0.5 * (m->pdf(p, wo, wi) + wi.z / M_PI);
			d->wo[i] = wo;
			d->wi[i] = wi;
			d->w[i] = pdf > 0 ? wi.z / sqrt(pdf * NDIR) : 0;
			m->eval(p, wo, wi, d->f + 3 * i);
			for (int c = 0; c < 3; c++)
				sum += d->f[3 * i + c] * d->w[i] *
				       d->f[3 * i + c] * d->w[i];
		}
	}
	d->norm = sqrt(sum);
}

static void x_to_gltf(const double *x, double ior,
		      struct glint_gltf_material *g)
{
	for (int c = 0; c < 3; c++) {
		g->base[c] = x[B0 + c];
		g->specular_color[c] = x[SC0 + c];
	}
	g->roughness = x[ROUGH];
	g->specular = x[SPEC];
	g->ior = ior;
}

static double residuals_of(const struct dirs *d,
			   const struct glint_gltf_material *g, double *r)
{
	double sum = 0;
	for (int i = 0; i < NDIR; i++) {
		double f[3];
		glint_gltf_brdf(g, d->wo[i], d->wi[i], f);
		for (int c = 0; c < 3; c++) {
			double e = (f[c] - d->f[3 * i + c]) * d->w[i];
			if (r)
				r[3 * i + c] = e;
			sum += e * e;
		}
	}
	return sqrt(sum) / d->norm;
}

static int lm_residuals(void *ctx, const double *x, double *r)
{
	const struct dirs *d = ctx;
	struct glint_gltf_material g;

	x_to_gltf(x, d->ior, &g);
	residuals_of(d, &g, r);
	return 0;
}

/* The model's ior, or 1.5 when it has none. */
static double model_ior(const struct glint_model_ops *m, const double *p)
{
	for (int k = 0; k < m->nparams; k++)
		if (!strcmp(m->params[k].name, "ior"))
			return p[k];
	return 1.5;
}

int glint_gltf_refit(const struct glint_model_ops *model, const double *p,
		     struct glint_gltf_material *g, double *residual)
{
	if (model->transparent || !model->eval)
		return glint_error_set(EINVAL,
				       "%s: a transparent sphere has no glTF "
				       "export yet (opaque models only)",
				       model->name);
	struct dirs *d = malloc(sizeof(*d));
	if (!d)
		return glint_error_set(ENOMEM, "out of memory");
	dirs_build(model, p, d);
	d->ior = model_ior(model, p);

	/* Start: glint's albedos (specular x F(ior) is f0 x specular_color
	 * x specular with specular_color 1), GGX's a from the lobe width. */
	double x[NX], lo[NX], hi[NX];
	double ks = 0, rough = model->roughness_param >= 0
				       ? p[model->roughness_param]
				       : 0.5;
	int has_spec = model->nlobes > 1;
	for (int c = 0; c < 3; c++)
		ks += has_spec ? p[model->lobe_param[1] + c] / 3 : 0;
	for (int c = 0; c < 3; c++) {
		x[B0 + c] = p[model->lobe_param[0] + c];
		x[SC0 + c] = ks > 0 ? p[model->lobe_param[1] + c] / ks : 1;
		lo[B0 + c] = 0;
		hi[B0 + c] = 1;
		lo[SC0 + c] = 0;
		hi[SC0 + c] = 1 / schlick_f0(fmax(d->ior, 1.01));
	}
	x[ROUGH] = fmin(1, fmax(0.02, sqrt(rough)));
	lo[ROUGH] = 0.02;
	hi[ROUGH] = 1;
	x[SPEC] = ks;
	lo[SPEC] = 0;
	hi[SPEC] = 1;

	struct glint_lm_problem pr = { NX,	     3 * NDIR, lo, hi,
				       lm_residuals, NULL,     d };
	struct glint_lm_opts lo_;
	struct glint_lm_result lr;
	glint_lm_default_opts(&lo_);
	lo_.max_iter = 200;
	int ret = glint_lm_solve(&pr, &lo_, x, &lr);
	if (ret >= 0) {
		x_to_gltf(x, d->ior, g);
		*residual = residuals_of(d, g, NULL);
		ret = 0;
	}
	free(d);
	return ret;
}

double glint_gltf_residual(const struct glint_model_ops *model, const double *p,
			   const struct glint_gltf_material *g)
{
	struct dirs *d = malloc(sizeof(*d));
	double r = NAN;

	if (d) {
		dirs_build(model, p, d);
		r = residuals_of(d, g, NULL);
		free(d);
	}
	return r;
}

json_t *glint_gltf_document(const struct glint_gltf_material *g,
			    const char *name, const char *source,
			    const struct glint_model_ops *model,
			    double residual)
{
	json_t *glint = json_pack(
		"{s:s, s:s, s:f, s:s}", "source", source, "model", model->name,
		"refit_relative_rms", residual, "note",
		"glTF's model refitted to glint's BRDF by least squares over "
		"8 view angles x 512 incident directions; refit_relative_rms "
		"is the relative RMS difference of reflected radiance there "
		"(glint docs/export.md)");
	json_t *mat = json_pack(
		"{s:s, s:{s:[f,f,f,f], s:f, s:f}, s:{s:{s:f}, s:{s:f, "
		"s:[f,f,f]}}, s:{s:o}}",
		"name", name, "pbrMetallicRoughness", "baseColorFactor",
		g->base[0], g->base[1], g->base[2], 1.0, "metallicFactor", 0.0,
		"roughnessFactor", g->roughness, "extensions",
		"KHR_materials_ior", "ior", g->ior, "KHR_materials_specular",
		"specularFactor", g->specular, "specularColorFactor",
		g->specular_color[0], g->specular_color[1],
		g->specular_color[2], "extras", "glint", glint);
	return json_pack("{s:{s:s, s:s}, s:[s, s], s:[o]}", "asset", "version",
			 "2.0", "generator", "glint export", "extensionsUsed",
			 "KHR_materials_ior", "KHR_materials_specular",
			 "materials", mat);
}
