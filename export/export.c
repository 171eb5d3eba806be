/* SPDX-License-Identifier: MIT */
/* The fitted material refitted in a renderer's model (export.h): what
 * every target shares; each target is a file of its own (target.h). */
#define _GNU_SOURCE /* strdup */
#include "export/target.h"

#include "fit/brdf/microfacet.h"
#include "fit/optim/lm.h"
#include "fit/render/sampling.h"

#include "core/error.h"
#include "core/path.h"
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

/* The targets, in the order of enum glint_export_format. */
static const struct glint_export_target *const targets[] = {
	&glint_export_target_gltf,	&glint_export_target_mitsuba,
	&glint_export_target_pbrt,	&glint_export_target_blender,
	&glint_export_target_materialx,
};
_Static_assert(sizeof(targets) / sizeof(targets[0]) == GLINT_EXPORT_NFORMATS,
	       "a target per format");

const struct glint_export_target *
glint_export_target_of(enum glint_export_format format)
{
	return (unsigned)format < GLINT_EXPORT_NFORMATS ? targets[format]
							: NULL;
}

double glint_export_schlick_f0(double ior)
{
	double r = (ior - 1) / (ior + 1);
	return r * r;
}

/* The target's f[3] at x: 0 below the surface. */
static void target_brdf(const struct glint_export_target *t,
			const struct glint_export *e, const double *x,
			const void *view, struct vec3 wo, struct vec3 wi,
			double f[3])
{
	f[0] = f[1] = f[2] = 0;
	if (!(wo.z > 0 && wi.z > 0))
		return;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	t->brdf(x, e, view, wo, wi, h, f);
}

void glint_export_brdf(const struct glint_export *e, struct vec3 wo,
		       struct vec3 wi, double f[3])
{
	const struct glint_export_target *t = glint_export_target_of(e->format);
	if (e->dielectric || !t) {
		f[0] = f[1] = f[2] = 0;
		return;
	}
	target_brdf(t, e, e->x, NULL, wo, wi, f);
}

/* The direction set and glint's BRDF on it. */
struct dirs {
	struct vec3 wo[NDIR], wi[NDIR];
	double w[NDIR];	    /* cos(theta_i) / sqrt(pdf N) */
	double f[NDIR * 3]; /* glint's f */
	double norm;	    /* sqrt(sum (f w)^2) */
	struct glint_export e;
};

static void dirs_build(const struct glint_model *m, const double *p,
		       struct dirs *d)
{
	struct glint_bxdf bx = glint_model_bxdf(m, p);
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
			else if (glint_bxdf_sample(&bx, wo, u, &wi) <= 0)
				glint_sample_cosine(u + 1, &wi);
			double pdf = 0.5 * (glint_bxdf_pdf(&bx, wo, wi) +
					    wi.z / M_PI);
			d->wo[i] = wo;
			d->wi[i] = wi;
			d->w[i] = pdf > 0 ? wi.z / sqrt(pdf * NDIR) : 0;
			glint_bxdf_eval(&bx, wo, wi, d->f + 3 * i);
			for (int c = 0; c < 3; c++)
				sum += d->f[3 * i + c] * d->w[i] *
				       d->f[3 * i + c] * d->w[i];
		}
	}
	d->norm = sqrt(sum);
}

static double residuals_of(const struct dirs *d, const double *x, double *r)
{
	const struct glint_export_target *t = targets[d->e.format];
	double sum = 0;
	double view[GLINT_EXPORT_VIEW_BYTES / sizeof(double)];
	for (int i = 0; i < NDIR; i++) {
		double f[3];
		if (t->view && i % NWI == 0)
			t->view(x, d->wo[i].z, view);
		target_brdf(t, &d->e, x, t->view ? view : NULL, d->wo[i],
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
double glint_export_model_param(const struct glint_model *m, const double *p,
				const char *name, double fallback)
{
	for (int k = 0; k < m->nparams; k++)
		if (!strcmp(m->params[k].name, name))
			return p[k];
	return fallback;
}

void glint_export_set(double *x, double *lo, double *hi, int k, double v,
		      double l, double h)
{
	x[k] = fmin(h, fmax(l, v));
	lo[k] = l;
	hi[k] = h;
}

void glint_export_lobes(const struct glint_model *model, const double *p,
			double kd[3], double ks[3], double *ksm, double *w)
{
	*w = model->lobes->roughness_param >= 0
		     ? p[model->lobes->roughness_param]
		     : 0.1;
	int has_spec = model->bxdf->nlobes > 1;
	*ksm = 0;
	for (int c = 0; c < 3; c++) {
		kd[c] = p[model->lobes->param[0] + c];
		ks[c] = has_spec ? p[model->lobes->param[1] + c] : 0;
		*ksm += ks[c] / 3;
	}
}

/* Schlick's reflectance against the exact Fresnel term's: the relative
 * RMS difference over a cosine-weighted hemisphere (midpoints in cos^2). */
static double schlick_residual(double ior)
{
	enum { N = 1024 };
	double f0 = glint_export_schlick_f0(ior), num = 0, den = 0;
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
			     const struct glint_model *model, const double *p,
			     double diameter_m, struct glint_export *e)
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
		e->x[c] = fmin(1, fmax(1e-6, glint_export_model_param(
						     model, p, t[c], 1)));
	e->ior = glint_export_model_param(model, p, "ior", 1.5);
	e->residual = targets[format]->schlick ? schlick_residual(e->ior) : 0;
	return 0;
}

/* The absorption coefficient per metre of channel c. */
double glint_export_sigma_a(const struct glint_export *e, int c)
{
	return -log(e->x[c]) / e->diameter_m;
}

double glint_export_sigma_a_max(const struct glint_export *e)
{
	return fmax(
		glint_export_sigma_a(e, 0),
		fmax(glint_export_sigma_a(e, 1), glint_export_sigma_a(e, 2)));
}

int glint_export_refit(enum glint_export_format format,
		       const struct glint_model *model, const double *p,
		       double diameter_m, struct glint_export *e)
{
	if ((unsigned)format >= GLINT_EXPORT_NFORMATS)
		return glint_error_set(EINVAL, "unknown export format %d",
				       (int)format);
	if (glint_model_is_transparent(model))
		return dielectric_export(format, model, p, diameter_m, e);
	if (!(model->bxdf->flags & GLINT_BXDF_LOBES) || model->bxdf->nlobes < 1)
		return glint_error_set(EINVAL,
				       "%s: the model has no BRDF to "
				       "export",
				       model->name);
	memset(e, 0, sizeof(*e));
	e->format = format;
	e->ior = glint_export_model_param(model, p, "ior", 1.5);
	e->ggx = model->lobes->microfacet == &glint_microfacet_ggx;

	double lo[GLINT_EXPORT_MAX_X], hi[GLINT_EXPORT_MAX_X];
	int nx = targets[format]->start(model, p, e, e->x, lo, hi);
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

double glint_export_residual(const struct glint_model *model, const double *p,
			     const struct glint_export *e)
{
	if (e->dielectric)
		return targets[e->format]->schlick ? schlick_residual(e->ior)
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
	const struct glint_export_target *t = glint_export_target_of(format);
	return t ? t->extension : "";
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

const char *glint_export_note_of(const struct glint_export *e)
{
	return e->dielectric ? dielectric_note : note;
}

/* The last component of path[0..*len) (trailing slashes dropped): its
 * start; *len becomes its length. */
static const char *last_component(const char *path, size_t *len)
{
	size_t e = *len;
	while (e > 1 && path[e - 1] == '/')
		e--;
	size_t b = e;
	while (b > 0 && path[b - 1] != '/')
		b--;
	*len = e - b;
	return path + b;
}

const char *glint_export_name_from_path(const char *path, char *buf, size_t n)
{
	/* Absolute, so that "." and "fit" have a parent: the path itself, or
	 * (one not made yet) its folder's and its last component. */
	char *abs = realpath(path, NULL), dir[GLINT_PATH_MAX], *da = NULL;
	if (!abs && glint_path_dirname(dir, sizeof(dir), path) == 0 &&
	    (da = realpath(dir, NULL))) {
		size_t l = strlen(path);
		const char *base = last_component(path, &l);
		if (asprintf(&abs, "%s/%.*s", da, (int)l, base) < 0)
			abs = NULL;
		free(da);
	}
	const char *p = abs ? abs : path;
	size_t len = strlen(p), l = len;
	const char *c = last_component(p, &l);

	if (l == 11 && !strncmp(c, "params.json", 11)) {
		len = (size_t)(c - p); /* its folder */
		l = len;
		c = last_component(p, &l);
	} else if (l > 5 && !strncmp(c + l - 5, ".json", 5)) {
		l -= 5;
		len = 0; /* a material file: its stem */
	}
	if (len && l == 3 && !strncmp(c, "fit", 3)) {
		len = (size_t)(c - p); /* a session's fit: the session */
		l = len;
		c = last_component(p, &l);
	}
	if (!l || (l == 1 && (*c == '.' || *c == '/')) ||
	    (l == 2 && !strncmp(c, "..", 2)))
		snprintf(buf, n, "material");
	else
		snprintf(buf, n, "%.*s", (int)l, c);
	free(abs);
	return buf;
}

char *glint_export_text(const struct glint_export *e, const char *name,
			const char *source, const struct glint_model *model)
{
	const struct glint_export_target *t = glint_export_target_of(e->format);
	char *safe = strdup(name && *name ? name : "material");
	char *text = NULL;

	if (!safe)
		return NULL;
	for (char *c = safe; *c; c++)
		if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
		      (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' ||
		      *c == '.'))
			*c = '_';
	if (t)
		text = t->text(e, safe, source, model);
	free(safe);
	return text;
}

json_t *glint_export_params_json(const struct glint_export *e)
{
	const double *x = e->x;
	const struct glint_export_target *t = glint_export_target_of(e->format);

	if (e->dielectric)
		return json_pack("{s:f, s:[f,f,f], s:f, s:[f,f,f]}", "ior",
				 e->ior, "transmission_per_diameter", x[0],
				 x[1], x[2], "diameter_m", e->diameter_m,
				 "absorption_per_m", glint_export_sigma_a(e, 0),
				 glint_export_sigma_a(e, 1),
				 glint_export_sigma_a(e, 2));
	return t ? t->params(e) : NULL;
}
