/* SPDX-License-Identifier: MIT */
/* The fitted material refitted in a renderer's model (export.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/export.h"

#include "fit/brdf/microfacet.h"
#include "fit/optim/lm.h"
#include "fit/render/sampling.h"

#include "core/error.h"
#include "core/suggest.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NWO  8
#define NWI  512
#define NDIR (NWO * NWI)

const char *const glint_export_format_names[] = { "gltf",      "mitsuba",
						  "pbrt",      "blender",
						  "materialx", NULL };

int glint_export_formats_parse(const char *list, unsigned *formats)
{
	unsigned set = 0;
	const char *t = list;

	for (;;) {
		size_t n = strcspn(t, ",");
		int k = 0;
		while (glint_export_format_names[k] &&
		       (strlen(glint_export_format_names[k]) != n ||
			strncmp(glint_export_format_names[k], t, n)))
			k++;
		if (!glint_export_format_names[k]) {
			char word[64];
			snprintf(word, sizeof(word), "%.*s", (int)n, t);
			return glint_error_set(
				EINVAL,
				"unknown export format '%s': expected gltf, "
				"mitsuba, pbrt, blender or materialx, "
				"comma-separated%s",
				word,
				glint_suggest_hint(word,
						   glint_export_format_names));
		}
		set |= 1u << k;
		if (!t[n])
			break;
		t += n + 1;
	}
	*formats = set;
	return 0;
}

/* Parameter layouts (export.h). */
enum { G_BASE = 0, G_ROUGH = 3, G_SPEC = 4, G_SCOL = 5, G_NX = 8 };
enum { M_KD = 0, M_ALPHA = 3, M_KS = 4, M_NX = 7 };
enum { P_R = 0, P_AMOUNT = 3, P_ALPHA = 4, P_ETA = 5, P_NX = 8 };
enum { B_KD = 0, B_ALPHA = 3, B_KS = 4, B_IOR = 7, B_NX = 8 };
enum {
	X_BASE = 0,
	X_DR = 3,
	X_ROUGH = 4,
	X_SPEC = 5,
	X_SCOL = 6,
	X_IOR = 9,
	X_NX = 10
};

static double schlick_f0(double ior)
{
	double r = (ior - 1) / (ior + 1);
	return r * r;
}

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
	double f0 = schlick_f0(ior), s = x[G_SPEC];

	for (int c = 0; c < 3; c++) {
		double c0 = fmin(f0 * x[G_SCOL + c], 1) * s;
		double F = c0 + (s - c0) * w5;
		f[c] = (1 - F) * x[G_BASE + c] / M_PI + F * dv;
	}
}

/* Mitsuba 3's Smith G1 for direction v and microfacet normal h. */
static double mitsuba_g1(int ggx, double alpha, struct vec3 v, struct vec3 h)
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

static double mitsuba_d(int ggx, double alpha, double cos_h)
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
	double s = mitsuba_d(ggx, alpha, h.z) * mitsuba_g1(ggx, alpha, wi, h) *
		   mitsuba_g1(ggx, alpha, wo, h) *
		   glint_fresnel_dielectric(v3_dot(wi, h), ior) /
		   (4 * wi.z * wo.z);

	for (int c = 0; c < 3; c++)
		f[c] = x[M_KD + c] / M_PI + x[M_KS + c] * s;
}

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

/* Blender's node material: Cycles's Beckmann glossy (its G1 is Mitsuba's
 * rational approximation; o.h > 0 for every reflection), or its GGX one
 * with the separable Smith G1, weighed by the Fresnel node's F at the
 * view direction. */
static void blender_brdf(const double *x, int ggx, struct vec3 wo,
			 struct vec3 wi, struct vec3 h, double f[3])
{
	double alpha = x[B_ALPHA];
	double s = mitsuba_d(ggx, alpha, h.z) * mitsuba_g1(ggx, alpha, wi, h) *
		   mitsuba_g1(ggx, alpha, wo, h) *
		   glint_fresnel_dielectric(wo.z, x[B_IOR]) / (4 * wi.z * wo.z);

	for (int c = 0; c < 3; c++)
		f[c] = x[B_KD + c] / M_PI + x[B_KS + c] * s;
}

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
	double f0 = schlick_f0(ior), e = 0, ess = 0;
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

static void target_brdf(enum glint_export_format format, const double *x,
			double ior, int ggx, const struct mx_albedo *mx,
			struct vec3 wo, struct vec3 wi, double f[3])
{
	f[0] = f[1] = f[2] = 0;
	if (!(wo.z > 0 && wi.z > 0))
		return;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	struct mx_albedo own;
	switch (format) {
	case GLINT_EXPORT_GLTF:
		gltf_brdf(x, ior, wo, wi, h, f);
		break;
	case GLINT_EXPORT_MITSUBA:
		mitsuba_brdf(x, ior, ggx, wo, wi, h, f);
		break;
	case GLINT_EXPORT_PBRT:
		pbrt_brdf(x, wo, wi, f);
		break;
	case GLINT_EXPORT_BLENDER:
		blender_brdf(x, ggx, wo, wi, h, f);
		break;
	case GLINT_EXPORT_MATERIALX:
		if (!mx || mx->mu != wo.z) {
			mx_albedo_at(wo.z, fmax(x[X_ROUGH] * x[X_ROUGH], 1e-6),
				     x[X_IOR], &own);
			mx = &own;
		}
		materialx_brdf(x, mx, wo, wi, h, f);
		break;
	default:
		break;
	}
}

void glint_export_brdf(const struct glint_export *e, struct vec3 wo,
		       struct vec3 wi, double f[3])
{
	if (e->dielectric) {
		f[0] = f[1] = f[2] = 0;
		return;
	}
	target_brdf(e->format, e->x, e->ior, e->ggx, NULL, wo, wi, f);
}

/* The direction set and glint's BRDF on it. */
struct dirs {
	struct vec3 wo[NDIR], wi[NDIR];
	double w[NDIR];	    /* cos(theta_i) / sqrt(pdf N) */
	double f[NDIR * 3]; /* glint's f */
	double norm;	    /* sqrt(sum (f w)^2) */
	struct glint_export e;
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

static double residuals_of(const struct dirs *d, const double *x, double *r)
{
	double sum = 0;
	struct mx_albedo mx = { -1, 0, 0 };
	for (int i = 0; i < NDIR; i++) {
		double f[3];
		if (d->e.format == GLINT_EXPORT_MATERIALX && i % NWI == 0)
			mx_albedo_at(d->wo[i].z,
				     fmax(x[X_ROUGH] * x[X_ROUGH], 1e-6),
				     x[X_IOR], &mx);
		target_brdf(d->e.format, x, d->e.ior, d->e.ggx, &mx, d->wo[i],
			    d->wi[i], f);
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
	residuals_of(ctx, x, r);
	return 0;
}

/* The model's parameter called name, or fallback when it has none. */
static double model_param(const struct glint_model_ops *m, const double *p,
			  const char *name, double fallback)
{
	for (int k = 0; k < m->nparams; k++)
		if (!strcmp(m->params[k].name, name))
			return p[k];
	return fallback;
}

static void set(double *x, double *lo, double *hi, int k, double v, double l,
		double h)
{
	x[k] = fmin(h, fmax(l, v));
	lo[k] = l;
	hi[k] = h;
}

/*
 * The start and bounds: glint's albedos, the lobe's width (GGX's a is
 * near Beckmann's m for the same highlight; glTF's roughness is its
 * square root), the specular weights from glint's.
 */
static int start(const struct glint_model_ops *model, const double *p,
		 const struct glint_export *e, double *x, double *lo,
		 double *hi)
{
	double kd[3], ks[3], ksm = 0;
	double w =
		model->roughness_param >= 0 ? p[model->roughness_param] : 0.1;
	int has_spec = model->nlobes > 1;
	for (int c = 0; c < 3; c++) {
		kd[c] = p[model->lobe_param[0] + c];
		ks[c] = has_spec ? p[model->lobe_param[1] + c] : 0;
		ksm += ks[c] / 3;
	}
	switch (e->format) {
	case GLINT_EXPORT_GLTF:
		for (int c = 0; c < 3; c++) {
			set(x, lo, hi, G_BASE + c, kd[c], 0, 1);
			set(x, lo, hi, G_SCOL + c, ksm > 0 ? ks[c] / ksm : 1, 0,
			    1 / schlick_f0(fmax(e->ior, 1.01)));
		}
		set(x, lo, hi, G_ROUGH, sqrt(w), 0.02, 1);
		set(x, lo, hi, G_SPEC, ksm, 0, 1);
		return G_NX;
	case GLINT_EXPORT_MITSUBA:
		for (int c = 0; c < 3; c++) {
			set(x, lo, hi, M_KD + c, kd[c], 0, 1);
			set(x, lo, hi, M_KS + c, ks[c], 0, 2);
		}
		set(x, lo, hi, M_ALPHA, w, 1e-3, 1);
		return M_NX;
	case GLINT_EXPORT_PBRT: {
		double a = fmin(0.95, fmax(0.05, ksm));
		for (int c = 0; c < 3; c++) {
			set(x, lo, hi, P_R + c, kd[c] / (1 - a), 0, 1);
			set(x, lo, hi, P_ETA + c, e->ior, 1.01, 10);
		}
		set(x, lo, hi, P_AMOUNT, a, 0, 1);
		/* pbrt-v4 treats alpha below 1e-3 as a mirror. */
		set(x, lo, hi, P_ALPHA, w, 2e-3, 1);
		return P_NX;
	}
	case GLINT_EXPORT_BLENDER:
		for (int c = 0; c < 3; c++) {
			set(x, lo, hi, B_KD + c, kd[c], 0, 1);
			set(x, lo, hi, B_KS + c, ks[c], 0, 10);
		}
		set(x, lo, hi, B_ALPHA, w, 1e-3, 1);
		set(x, lo, hi, B_IOR, e->ior, 1.01, 10);
		return B_NX;
	case GLINT_EXPORT_MATERIALX:
		for (int c = 0; c < 3; c++) {
			set(x, lo, hi, X_BASE + c, kd[c], 0, 1);
			set(x, lo, hi, X_SCOL + c, ks[c], 0, 1);
		}
		set(x, lo, hi, X_DR,
		    model_param(model, p, "diffuse_roughness", 0), 0, 1);
		set(x, lo, hi, X_ROUGH, sqrt(w), 0.02, 1);
		set(x, lo, hi, X_SPEC, ksm > 0 ? 1 : 0, 0, 1);
		set(x, lo, hi, X_IOR, e->ior, 1.01, 10);
		return X_NX;
	default:
		return glint_error_set(EINVAL, "unknown export format %d",
				       (int)e->format);
	}
}

/* Schlick's reflectance against the exact Fresnel term's: the relative
 * RMS difference over a cosine-weighted hemisphere (midpoints in cos^2). */
static double schlick_residual(double ior)
{
	enum { N = 1024 };
	double f0 = schlick_f0(ior), num = 0, den = 0;
	for (int i = 0; i < N; i++) {
		double mu = sqrt((i + 0.5) / N);
		double r = glint_fresnel_dielectric(mu, ior);
		double rs = f0 + (1 - f0) * pow(1 - mu, 5);
		num += (rs - r) * (rs - r);
		den += r * r;
	}
	return sqrt(num / den);
}

/* A transparent sphere's parameters carried across (export.h). */
static int dielectric_export(enum glint_export_format format,
			     const struct glint_model_ops *model,
			     const double *p, double diameter_m,
			     struct glint_export *e)
{
	static const char *const t[] = { "transmission.r", "transmission.g",
					 "transmission.b" };
	if (!(diameter_m > 0 && isfinite(diameter_m)))
		return glint_error_set(
			EINVAL,
			"%s: a transparent sphere's export needs the sphere's "
			"diameter (its absorption is per diameter): give "
			"--diameter-m D, or export a fit's params.json, which "
			"records it",
			model->name);
	memset(e, 0, sizeof(*e));
	e->format = format;
	e->dielectric = 1;
	e->diameter_m = diameter_m;
	for (int c = 0; c < 3; c++)
		e->x[c] = fmin(1, fmax(1e-6, model_param(model, p, t[c], 1)));
	e->ior = model_param(model, p, "ior", 1.5);
	e->residual =
		format == GLINT_EXPORT_GLTF ? schlick_residual(e->ior) : 0;
	return 0;
}

/* The absorption coefficient per metre of channel c. */
static double sigma_a(const struct glint_export *e, int c)
{
	return -log(e->x[c]) / e->diameter_m;
}

static double sigma_a_max(const struct glint_export *e)
{
	return fmax(sigma_a(e, 0), fmax(sigma_a(e, 1), sigma_a(e, 2)));
}

int glint_export_refit(enum glint_export_format format,
		       const struct glint_model_ops *model, const double *p,
		       double diameter_m, struct glint_export *e)
{
	if ((unsigned)format >= GLINT_EXPORT_NFORMATS)
		return glint_error_set(EINVAL, "unknown export format %d",
				       (int)format);
	if (model->transparent)
		return dielectric_export(format, model, p, diameter_m, e);
	if (!model->eval || model->nlobes < 1)
		return glint_error_set(EINVAL,
				       "%s: the model has no BRDF to "
				       "export",
				       model->name);
	memset(e, 0, sizeof(*e));
	e->format = format;
	e->ior = model_param(model, p, "ior", 1.5);
	e->ggx = model->name && strstr(model->name, "ggx") != NULL;

	double lo[GLINT_EXPORT_MAX_X], hi[GLINT_EXPORT_MAX_X];
	int nx = start(model, p, e, e->x, lo, hi);
	if (nx < 0)
		return nx;
	struct dirs *d = malloc(sizeof(*d));
	if (!d)
		return glint_error_set(ENOMEM, "out of memory");
	d->e = *e;
	dirs_build(model, p, d);

	struct glint_lm_problem pr = { nx,	     3 * NDIR, lo, hi,
				       lm_residuals, NULL,     d };
	struct glint_lm_opts o;
	struct glint_lm_result lr;
	glint_lm_default_opts(&o);
	o.max_iter = 200;
	int ret = glint_lm_solve(&pr, &o, e->x, &lr);
	if (ret >= 0) {
		e->residual = residuals_of(d, e->x, NULL);
		ret = 0;
	}
	free(d);
	return ret;
}

double glint_export_residual(const struct glint_model_ops *model,
			     const double *p, const struct glint_export *e)
{
	if (e->dielectric)
		return e->format == GLINT_EXPORT_GLTF ? schlick_residual(e->ior)
						      : 0;
	struct dirs *d = malloc(sizeof(*d));
	double r = NAN;

	if (d) {
		d->e = *e;
		dirs_build(model, p, d);
		r = residuals_of(d, e->x, NULL);
		free(d);
	}
	return r;
}

const char *glint_export_extension(enum glint_export_format format)
{
	static const char *const ext[] = { ".gltf", ".xml", ".pbrt", ".py",
					   ".mtlx" };
	return (unsigned)format < GLINT_EXPORT_NFORMATS ? ext[format] : "";
}

static const char note[] =
	"the target's model refitted to glint's BRDF by least squares over 8 "
	"view angles x 512 incident directions; refit_relative_rms is the "
	"relative RMS difference of reflected radiance there (glint "
	"docs/export.md)";

static const char dielectric_note[] =
	"a smooth dielectric with a Beer-Lambert interior: ior and the "
	"absorption -ln(transmission) / diameter carry across exactly; "
	"refit_relative_rms is the relative RMS difference of the "
	"interface's reflectance from the exact Fresnel term (glint "
	"docs/export.md)";

static const char *note_of(const struct glint_export *e)
{
	return e->dielectric ? dielectric_note : note;
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
			     const struct glint_model_ops *model)
{
	const double *x = e->x;
	json_t *glint = json_pack("{s:s, s:s, s:f, s:s}", "source", source,
				  "model", model->name, "refit_relative_rms",
				  e->residual, "note", note_of(e));
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
				const struct glint_model_ops *model)
{
	/* sigma_t as a colour within [0, 1] (a bounded RGB in spectral
	 * variants) times scale. */
	double top = fmax(sigma_a_max(e), 1e-12);
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
		     source, model->name, e->residual, dielectric_note,
		     e->diameter_m / 2, name, name, name, e->ior, name,
		     sigma_a(e, 0) / top, sigma_a(e, 1) / top,
		     sigma_a(e, 2) / top, top) < 0)
		return NULL;
	return s;
}

static char *mitsuba_text(const struct glint_export *e, const char *name,
			  const char *source,
			  const struct glint_model_ops *model)
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
		     source, model->name, e->residual, note, name, name, w,
		     kd[0], kd[1], kd[2], e->ggx ? "ggx" : "beckmann",
		     e->x[M_ALPHA], e->ior, ks[0], ks[1], ks[2],
		     unbounded ? "                <boolean name=\"unbounded\" "
				 "value=\"true\"/>\n"
			       : "") < 0)
		return NULL;
	return s;
}

static char *pbrt_dielectric(const struct glint_export *e, const char *name,
			     const char *source,
			     const struct glint_model_ops *model)
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
		     source, model->name, e->residual, dielectric_note, name,
		     name, e->diameter_m / 2, name, sigma_a(e, 0),
		     sigma_a(e, 1), sigma_a(e, 2), name, e->ior) < 0)
		return NULL;
	return s;
}

static char *pbrt_text(const struct glint_export *e, const char *name,
		       const char *source, const struct glint_model_ops *model)
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
		     source, model->name, e->residual, note, name, name, x[P_R],
		     x[P_R + 1], x[P_R + 2], name, x[P_ALPHA], x[P_ETA],
		     x[P_ETA + 1], x[P_ETA + 2], name, name, name,
		     x[P_AMOUNT]) < 0)
		return NULL;
	return s;
}

/* The Blender script after its constants (export.h). */
static const char blender_body[] =
	"import math\n"
	"import os\n"
	"import sys\n"
	"\n"
	"import bpy\n"
	"\n"
	"\n"
	"def build_material(name=NAME):\n"
	"    \"\"\"Create (or rebuild) the material NAME in the open file; "
	"return it.\"\"\"\n"
	"    mat = bpy.data.materials.get(name) or "
	"bpy.data.materials.new(name)\n"
	"    mat.use_nodes = True\n"
	"    nodes, links = mat.node_tree.nodes, mat.node_tree.links\n"
	"    nodes.clear()\n"
	"    out = nodes.new(\"ShaderNodeOutputMaterial\")\n"
	"    if KIND == \"dielectric\":\n"
	"        # Cycles: absorption = (1 - Color) * Density per metre.\n"
	"        glass = nodes.new(\"ShaderNodeBsdfGlass\")\n"
	"        glass.distribution = \"SHARP\"\n"
	"        glass.inputs[\"Color\"].default_value = (1.0, 1.0, 1.0, "
	"1.0)\n"
	"        glass.inputs[\"IOR\"].default_value = IOR\n"
	"        absorb = nodes.new(\"ShaderNodeVolumeAbsorption\")\n"
	"        absorb.inputs[\"Color\"].default_value = "
	"(*ABSORPTION_COLOR, 1.0)\n"
	"        absorb.inputs[\"Density\"].default_value = DENSITY\n"
	"        links.new(glass.outputs[\"BSDF\"], "
	"out.inputs[\"Surface\"])\n"
	"        links.new(absorb.outputs[\"Volume\"], "
	"out.inputs[\"Volume\"])\n"
	"        glass.location, absorb.location = (-300, 100), (-300, "
	"-100)\n"
	"        return mat\n"
	"    diffuse = nodes.new(\"ShaderNodeBsdfDiffuse\")\n"
	"    diffuse.inputs[\"Color\"].default_value = (*DIFFUSE, 1.0)\n"
	"    diffuse.inputs[\"Roughness\"].default_value = 0.0\n"
	"    glossy = nodes.new(\"ShaderNodeBsdfGlossy\")\n"
	"    glossy.distribution = DISTRIBUTION\n"
	"    glossy.inputs[\"Color\"].default_value = (*SPECULAR, 1.0)\n"
	"    glossy.inputs[\"Roughness\"].default_value = ROUGHNESS\n"
	"    black = nodes.new(\"ShaderNodeBsdfDiffuse\")\n"
	"    black.inputs[\"Color\"].default_value = (0.0, 0.0, 0.0, 1.0)\n"
	"    fresnel = nodes.new(\"ShaderNodeFresnel\")\n"
	"    fresnel.inputs[\"IOR\"].default_value = IOR\n"
	"    mix = nodes.new(\"ShaderNodeMixShader\")\n"
	"    add = nodes.new(\"ShaderNodeAddShader\")\n"
	"    links.new(fresnel.outputs[\"Fac\"], mix.inputs[\"Fac\"])\n"
	"    links.new(black.outputs[\"BSDF\"], mix.inputs[1])\n"
	"    links.new(glossy.outputs[\"BSDF\"], mix.inputs[2])\n"
	"    links.new(diffuse.outputs[\"BSDF\"], add.inputs[0])\n"
	"    links.new(mix.outputs[\"Shader\"], add.inputs[1])\n"
	"    links.new(add.outputs[\"Shader\"], out.inputs[\"Surface\"])\n"
	"    for i, n in enumerate((fresnel, black, glossy, diffuse, mix, add, "
	"out)):\n"
	"        n.location = (200 * i - 600, 0)\n"
	"    return mat\n"
	"\n"
	"\n"
	"def preview_scene(mat, env=None, samples=64, size=512):\n"
	"    \"\"\"A new scene (the open file's scenes are left as they are) "
	"with a\n"
	"    sphere of the material, a camera and light: the environment map "
	"env\n"
	"    (equirectangular) or a sun and a grey sky.  Returns it.\"\"\"\n"
	"    import bmesh\n"
	"    scene = bpy.data.scenes.new(\"glint-preview\")\n"
	"    mesh = bpy.data.meshes.new(\"glint-sphere\")\n"
	"    bm = bmesh.new()\n"
	"    bmesh.ops.create_uvsphere(bm, u_segments=128, v_segments=64, "
	"radius=RADIUS)\n"
	"    bm.to_mesh(mesh)\n"
	"    bm.free()\n"
	"    mesh.polygons.foreach_set(\"use_smooth\", [True] * "
	"len(mesh.polygons))\n"
	"    mesh.materials.append(mat)\n"
	"    scene.collection.objects.link(bpy.data.objects.new(\"sphere\", "
	"mesh))\n"
	"    cam = bpy.data.objects.new(\"camera\", "
	"bpy.data.cameras.new(\"camera\"))\n"
	"    cam.location = (0.0, -6.0 * RADIUS, 0.0)\n"
	"    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)\n"
	"    cam.data.lens = 100\n"
	"    scene.collection.objects.link(cam)\n"
	"    scene.camera = cam\n"
	"    world = bpy.data.worlds.new(\"glint-preview\")\n"
	"    world.use_nodes = True\n"
	"    bg = world.node_tree.nodes[\"Background\"]\n"
	"    if env:\n"
	"        tex = "
	"world.node_tree.nodes.new(\"ShaderNodeTexEnvironment\")\n"
	"        tex.image = bpy.data.images.load(env)\n"
	"        world.node_tree.links.new(tex.outputs[\"Color\"], "
	"bg.inputs[\"Color\"])\n"
	"    else:\n"
	"        bg.inputs[\"Color\"].default_value = (0.05, 0.05, 0.05, 1.0)\n"
	"        sun = bpy.data.objects.new(\"sun\", "
	"bpy.data.lights.new(\"sun\", \"SUN\"))\n"
	"        sun.data.energy = 3.0\n"
	"        sun.rotation_euler = (math.radians(40), 0.0, "
	"math.radians(30))\n"
	"        scene.collection.objects.link(sun)\n"
	"    scene.world = world\n"
	"    scene.render.engine = \"CYCLES\"\n"
	"    scene.cycles.device = \"CPU\"\n"
	"    scene.cycles.samples = samples\n"
	"    # Debian's Blender is built without OpenImageDenoise.\n"
	"    scene.cycles.use_denoising = False\n"
	"    for layer in scene.view_layers:\n"
	"        layer.cycles.use_denoising = False\n"
	"    scene.render.resolution_x = scene.render.resolution_y = size\n"
	"    scene.render.resolution_percentage = 100\n"
	"    return scene\n"
	"\n"
	"\n"
	"def main(argv):\n"
	"    import argparse\n"
	"    ap = argparse.ArgumentParser(\n"
	"        prog=\"blender --background --python \" + __file__ + \" "
	"--\",\n"
	"        description=\"Build the material \" + NAME + \"; optionally "
	"render a \"\n"
	"        \"preview sphere or save the .blend file.\")\n"
	"    ap.add_argument(\"--render\", metavar=\"OUT.png\",\n"
	"                    help=\"render a sphere of the material (Cycles) "
	"to OUT\")\n"
	"    ap.add_argument(\"--env\", metavar=\"MAP\",\n"
	"                    help=\"light the preview with this environment "
	"map\")\n"
	"    ap.add_argument(\"--samples\", type=int, default=64)\n"
	"    ap.add_argument(\"--size\", type=int, default=512)\n"
	"    ap.add_argument(\"--save\", metavar=\"OUT.blend\",\n"
	"                    help=\"save the file with the material (and "
	"preview)\")\n"
	"    args = ap.parse_args(argv)\n"
	"    mat = build_material()\n"
	"    print(\"glint: material '%s' built\" % mat.name)\n"
	"    if args.save and os.path.lexists(args.save):\n"
	"        sys.exit(\"glint: %s exists: refusing to replace it\" % "
	"args.save)\n"
	"    if args.render:\n"
	"        scene = preview_scene(mat, args.env, args.samples, "
	"args.size)\n"
	"        scene.render.filepath = args.render\n"
	"        bpy.ops.render.render(write_still=True, scene=scene.name)\n"
	"        print(\"glint: rendered\", args.render)\n"
	"    if args.save:\n"
	"        bpy.ops.wm.save_as_mainfile(filepath=args.save, copy=True)\n"
	"        print(\"glint: saved\", args.save)\n"
	"\n"
	"\n"
	"if __name__ == \"__main__\":\n"
	"    main(sys.argv[sys.argv.index(\"--\") + 1:] if \"--\" in sys.argv "
	"else [])\n";

static char *blender_text(const struct glint_export *e, const char *name,
			  const char *source,
			  const struct glint_model_ops *model)
{
	const double *x = e->x;
	char *s = NULL;

	if (e->dielectric) {
		double dens = sigma_a_max(e), col[3];
		for (int c = 0; c < 3; c++)
			col[c] = dens > 0 ? 1 - sigma_a(e, c) / dens : 1;
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
			     source, model->name, e->residual, dielectric_note,
			     e->diameter_m, name, e->ior, x[0], x[1], x[2],
			     e->diameter_m, col[0], col[1], col[2], dens,
			     e->residual, blender_body) < 0)
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
		     source, model->name, e->residual, note, name,
		     e->ggx ? "GGX" : "BECKMANN", x[B_KD], x[B_KD + 1],
		     x[B_KD + 2], x[B_KS], x[B_KS + 1], x[B_KS + 2], x[B_ALPHA],
		     sqrt(x[B_ALPHA]), x[B_IOR], e->residual, blender_body) < 0)
		return NULL;
	return s;
}

/* One standard_surface input: a float (n = 1) or a colour3 (n = 3). */
struct mx_input {
	const char *name;
	int n;
	double v[3];
};

static char *materialx_text(const struct glint_export *e, const char *name,
			    const char *source,
			    const struct glint_model_ops *model)
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
		source, model->name, e->residual, note_of(e),
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

char *glint_export_text(const struct glint_export *e, const char *name,
			const char *source, const struct glint_model_ops *model)
{
	char *safe = strdup(name && *name ? name : "material");
	char *text = NULL;

	if (!safe)
		return NULL;
	for (char *c = safe; *c; c++)
		if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
		      (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' ||
		      *c == '.'))
			*c = '_';
	switch (e->format) {
	case GLINT_EXPORT_GLTF: {
		json_t *doc = gltf_document(e, safe, source, model);
		text = doc ? json_dumps(doc, JSON_INDENT(2)) : NULL;
		json_decref(doc);
		break;
	}
	case GLINT_EXPORT_MITSUBA:
		text = mitsuba_text(e, safe, source, model);
		break;
	case GLINT_EXPORT_PBRT:
		text = pbrt_text(e, safe, source, model);
		break;
	case GLINT_EXPORT_BLENDER:
		text = blender_text(e, safe, source, model);
		break;
	case GLINT_EXPORT_MATERIALX:
		text = materialx_text(e, safe, source, model);
		break;
	default:
		break;
	}
	free(safe);
	return text;
}

json_t *glint_export_params_json(const struct glint_export *e)
{
	const double *x = e->x;

	if (e->dielectric)
		return json_pack("{s:f, s:[f,f,f], s:f, s:[f,f,f]}", "ior",
				 e->ior, "transmission_per_diameter", x[0],
				 x[1], x[2], "diameter_m", e->diameter_m,
				 "absorption_per_m", sigma_a(e, 0),
				 sigma_a(e, 1), sigma_a(e, 2));
	switch (e->format) {
	case GLINT_EXPORT_GLTF:
		return json_pack("{s:[f,f,f], s:f, s:f, s:f, s:[f,f,f]}",
				 "base_color", x[G_BASE], x[G_BASE + 1],
				 x[G_BASE + 2], "roughness", x[G_ROUGH], "ior",
				 e->ior, "specular", x[G_SPEC],
				 "specular_color", x[G_SCOL], x[G_SCOL + 1],
				 x[G_SCOL + 2]);
	case GLINT_EXPORT_MITSUBA: {
		double kd[3], ks[3], w = mitsuba_split(e, kd, ks);
		return json_pack(
			"{s:f, s:[f,f,f], s:s, s:f, s:f, s:[f,f,f]}", "weight",
			w, "reflectance", kd[0], kd[1], kd[2], "distribution",
			e->ggx ? "ggx" : "beckmann", "alpha", x[M_ALPHA], "eta",
			e->ior, "specular_reflectance", ks[0], ks[1], ks[2]);
	}
	case GLINT_EXPORT_PBRT:
		return json_pack("{s:[f,f,f], s:f, s:f, s:[f,f,f]}",
				 "reflectance", x[P_R], x[P_R + 1], x[P_R + 2],
				 "amount", x[P_AMOUNT], "roughness", x[P_ALPHA],
				 "eta", x[P_ETA], x[P_ETA + 1], x[P_ETA + 2]);
	case GLINT_EXPORT_BLENDER:
		return json_pack("{s:[f,f,f], s:[f,f,f], s:f, s:f}", "diffuse",
				 x[B_KD], x[B_KD + 1], x[B_KD + 2], "glossy",
				 x[B_KS], x[B_KS + 1], x[B_KS + 2], "roughness",
				 sqrt(x[B_ALPHA]), "fresnel_ior", x[B_IOR]);
	case GLINT_EXPORT_MATERIALX:
		return json_pack("{s:[f,f,f], s:f, s:f, s:[f,f,f], s:f, s:f}",
				 "base_color", x[X_BASE], x[X_BASE + 1],
				 x[X_BASE + 2], "diffuse_roughness", x[X_DR],
				 "specular", x[X_SPEC], "specular_color",
				 x[X_SCOL], x[X_SCOL + 1], x[X_SCOL + 2],
				 "specular_roughness", x[X_ROUGH],
				 "specular_IOR", x[X_IOR]);
	default:
		return NULL;
	}
}
