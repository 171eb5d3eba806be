/* SPDX-License-Identifier: MIT */
#include "model.h"

#include "microfacet.h"

#include "core/error.h"
#include "core/json.h"
#include "core/suggest.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const struct glint_model *const registry[] = {
	&glint_model_lambert,
	&glint_model_torrance_sparrow,
	&glint_model_ts_constant_fresnel,
	&glint_model_dielectric,
	&glint_model_ggx,
	&glint_model_oren_nayar,
	&glint_model_two_lobe,
};

#define NMODELS (sizeof(registry) / sizeof(registry[0]))

const struct glint_model *glint_model_find(const char *name)
{
	for (size_t i = 0; i < NMODELS; i++)
		if (!strcmp(registry[i]->name, name))
			return registry[i];
	return NULL;
}

const char *const *glint_model_list(void)
{
	static const char *names[NMODELS + 1];

	for (size_t i = 0; i < NMODELS; i++)
		names[i] = registry[i]->name;
	return names;
}

const char *glint_model_names(void)
{
	static char buf[256];

	if (!buf[0]) {
		for (size_t i = 0; i < NMODELS; i++) {
			strncat(buf, registry[i]->name,
				sizeof(buf) - strlen(buf) - 1);
			if (i + 1 < NMODELS)
				strncat(buf, ", ",
					sizeof(buf) - strlen(buf) - 1);
		}
	}
	return buf;
}

int glint_material_from_json(const char *file, const char *where, json_t *obj,
			     const struct glint_model **model, double *params)
{
	const struct glint_model *m;
	const char *name = NULL;
	const char *known[GLINT_MAX_PARAMS + 3] = { "model", "name" };
	int nk = 2, ret;

	ret = glint_json_string(file, where, obj, "model", 1, &name);
	if (ret < 0)
		return ret;
	m = glint_model_find(name);
	if (!m) {
		const char *hint = glint_suggest_hint(name, glint_model_list());
		return glint_error_set(EINVAL,
				       "%s: %s%smodel = \"%s\": expected one "
				       "of %s%s",
				       file, where, where[0] ? "." : "", name,
				       glint_model_names(), hint);
	}
	for (int i = 0; i < m->nparams; i++) {
		const struct glint_param *pi = &m->params[i];
		struct glint_range r = { pi->lo, pi->hi, 0, 0 };

		params[i] = pi->def;
		if (pi->json_index < 0) {
			ret = glint_json_number(file, where, obj, pi->json_key,
						0, r, &params[i]);
		} else if (pi->json_index == 0) {
			double v[3] = { params[i], m->params[i + 1].def,
					m->params[i + 2].def };
			ret = glint_json_numbers(file, where, obj, pi->json_key,
						 0, 3, r, v);
			params[i] = v[0];
			params[i + 1] = v[1];
			params[i + 2] = v[2];
			i += 2;
		}
		if (ret < 0)
			return ret;
		if (nk == 2 || strcmp(known[nk - 1], pi->json_key))
			known[nk++] = pi->json_key;
	}
	known[nk] = NULL;
	ret = glint_json_known_keys(file, where, obj, known);
	if (ret < 0)
		return ret;
	*model = m;
	return 0;
}

int glint_material_load(const char *path, const char *entry,
			const struct glint_model **model, double *params)
{
	json_t *root, *list;
	int ret = glint_json_load(path, &root);

	if (ret < 0)
		return ret;
	if (!entry) {
		/* A fit's params.json holds its material under "material"
		 * (beside its statistics): render a fit's result directly. */
		json_t *fitted = json_object_get(root, "material");
		if (json_is_object(fitted) &&
		    json_object_get(root, "parameters"))
			ret = glint_material_from_json(path, "material", fitted,
						       model, params);
		else
			ret = glint_material_from_json(path, "", root, model,
						       params);
		goto out;
	}
	list = json_object_get(root, "materials");
	if (!json_is_array(list)) {
		ret = glint_error_set(EINVAL,
				      "%s: no \"materials\" array: expected a "
				      "Table-1 style file to pick '%s' from",
				      path, entry);
		goto out;
	}
	for (size_t i = 0; i < json_array_size(list); i++) {
		json_t *e = json_array_get(list, i);
		json_t *n = json_object_get(e, "name");
		if (json_is_string(n) && !strcmp(json_string_value(n), entry)) {
			char where[64];
			snprintf(where, sizeof(where), "materials[%zu]", i);
			ret = glint_material_from_json(path, where, e, model,
						       params);
			goto out;
		}
	}
	/* the names it holds, for a "did you mean" and the list */
	const char *names[64];
	char known[512] = "";
	size_t nn = 0, kl = 0; /* kl == sizeof(known): full */
	for (size_t i = 0; i < json_array_size(list) && nn < 63; i++) {
		const char *nm = json_string_value(
			json_object_get(json_array_get(list, i), "name"));
		if (!nm)
			continue;
		names[nn++] = nm;
		int w = kl == sizeof(known)
				? 0
				: snprintf(known + kl, sizeof(known) - kl,
					   "%s%s", kl ? ", " : "", nm);
		if (w > 0 && (size_t)w < sizeof(known) - kl) {
			kl += (size_t)w;
		} else if (kl < sizeof(known)) {
			/* the list ends at a whole name */
			snprintf(known + kl, sizeof(known) - kl, ", ...");
			kl = sizeof(known);
		}
	}
	names[nn] = NULL;
	ret = glint_error_set(
		ENOENT, "%s: no material named '%s'%s: it holds %s", path,
		entry, glint_suggest_hint(entry, names), nn ? known : "none");
out:
	json_decref(root);
	return ret;
}

json_t *glint_material_to_json(const struct glint_model *model,
			       const double *params)
{
	json_t *o = json_object();

	json_object_set_new(o, "model", json_string(model->name));
	for (int i = 0; i < model->nparams; i++) {
		const struct glint_param *pi = &model->params[i];
		if (pi->json_index < 0) {
			json_object_set_new(o, pi->json_key,
					    json_real(params[i]));
			continue;
		}
		json_t *a = json_object_get(o, pi->json_key);
		if (!a) {
			a = json_array();
			json_object_set_new(o, pi->json_key, a);
		}
		json_array_append_new(a, json_real(params[i]));
	}
	return o;
}

void glint_lobes_eval(const struct glint_model *m, const double *p,
		      struct vec3 wo, struct vec3 wi, double f[3])
{
	double b[GLINT_MAX_PARAMS];

	f[0] = f[1] = f[2] = 0;
	if (!(wo.z > 0 && wi.z > 0))
		return;
	m->bxdf->eval_lobes(p, wo, wi, b);
	for (int j = 0; j < m->bxdf->nlobes; j++)
		for (int c = 0; c < 3; c++)
			f[c] += p[m->lobes->param[j] + c] * b[j];
}

double glint_lobe_value_pdf(const struct glint_model *m, const double *p, int j,
			    struct vec3 wo, struct vec3 wi, double *pdf,
			    double *dlog)
{
	double b[GLINT_MAX_PARAMS];

	if (m->lobes->value_pdf)
		return m->lobes->value_pdf(p, j, wo, wi, pdf, dlog);
	m->bxdf->eval_lobes(p, wo, wi, b);
	if (pdf)
		*pdf = m->bxdf->pdf_lobe(p, j, wo, wi);
	if (dlog)
		*dlog = m->lobes->factor_dlog
				? m->lobes->factor_dlog(p, j, wo, wi)
				: 0;
	return b[j];
}

void glint_lobe_values(const struct glint_model *m, const double *p, int j,
		       struct vec3 wo, int n, const double *x, const double *y,
		       const double *z, double *b, double *dlog)
{
	if (m->lobes->values) {
		m->lobes->values(p, j, wo, n, x, y, z, b, dlog);
		return;
	}
	for (int k = 0; k < n; k++)
		b[k] = glint_lobe_value_pdf(m, p, j, wo, v3(x[k], y[k], z[k]),
					    NULL, dlog ? &dlog[k] : NULL);
}

void glint_lobe_sample_values(const struct glint_model *m, const double *p,
			      int j, int n, const struct vec3 *wo,
			      const double *u0, const double *u1, double *x,
			      double *y, double *z, double *pdf, double *b,
			      double *dlog)
{
	if (m->lobes->sample_values &&
	    m->lobes->sample_values(p, j, n, wo, u0, u1, x, y, z, pdf, b, dlog))
		return;
	for (int k = 0; k < n; k++) {
		double u[2] = { u0[k], u1[k] };
		struct vec3 wi = v3(0, 0, 0);
		pdf[k] = glint_lobe_sample_value(m, p, j, wo[k], u, &wi, &b[k],
						 dlog ? &dlog[k] : NULL);
		x[k] = wi.x, y[k] = wi.y, z[k] = wi.z;
	}
}

double glint_lobe_sample_value(const struct glint_model *m, const double *p,
			       int j, struct vec3 wo, const double u[2],
			       struct vec3 *wi, double *bj, double *dlog)
{
	double b[GLINT_MAX_PARAMS];

	if (m->lobes->sample_value)
		return m->lobes->sample_value(p, j, wo, u, wi, bj, dlog);
	*bj = 0;
	if (dlog)
		*dlog = 0;
	double pdf = m->bxdf->sample_lobe(p, j, wo, u, wi);
	if (pdf > 0) {
		m->bxdf->eval_lobes(p, wo, *wi, b);
		*bj = b[j];
		if (dlog)
			*dlog = m->lobes->factor_dlog
					? m->lobes->factor_dlog(p, j, wo, *wi)
					: 0;
	}
	return pdf;
}

/* Lobe j's share of the samples: w[j] / sum w, at least 5 % for every
 * lobe with weight (none is starved), all alike when no lobe has any;
 * w[j] the luminance of lobe j's albedo, times spec_scale past lobe 0. */
static void lobe_probs(const struct glint_model *m, const double *p,
		       double spec_scale, double *prob)
{
	double w[GLINT_MAX_PARAMS], total = 0, floored = 0;
	int used = 0, n = m->bxdf->nlobes;

	for (int j = 0; j < n; j++) {
		const double *a = p + m->lobes->param[j];
		w[j] = rgb_luminance(a[0], a[1], a[2]) * (j ? spec_scale : 1);
	}
	for (int j = 0; j < n; j++)
		if (w[j] > 0) {
			total += w[j];
			used++;
		}
	for (int j = 0; j < n; j++) {
		prob[j] = !used	     ? 1.0 / n
			  : w[j] > 0 ? fmax(w[j] / total, 0.05)
				     : 0;
		floored += prob[j];
	}
	for (int j = 0; j < n; j++)
		prob[j] /= floored;
}

double glint_lobes_pdf(const struct glint_model *m, const double *p,
		       double spec_scale, struct vec3 wo, struct vec3 wi)
{
	double prob[GLINT_MAX_PARAMS], pdf = 0;

	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	lobe_probs(m, p, spec_scale, prob);
	for (int j = 0; j < m->bxdf->nlobes; j++)
		if (prob[j] > 0)
			pdf += prob[j] * m->bxdf->pdf_lobe(p, j, wo, wi);
	return pdf;
}

double glint_lobes_sample(const struct glint_model *m, const double *p,
			  double spec_scale, struct vec3 wo, const double u[3],
			  struct vec3 *wi)
{
	double prob[GLINT_MAX_PARAMS], acc = 0;
	int j = 0;

	if (!(wo.z > 0))
		return 0;
	lobe_probs(m, p, spec_scale, prob);
	while (j < m->bxdf->nlobes - 1 && u[0] >= acc + prob[j])
		acc += prob[j++];
	if (m->bxdf->sample_lobe(p, j, wo, u + 1, wi) <= 0 || !(wi->z > 0))
		return 0;
	return glint_lobes_pdf(m, p, spec_scale, wo, *wi);
}

double glint_lobe_extent(const struct glint_model *m, const double *p, int j)
{
	const struct glint_fit_lobes *l = m->lobes;
	int w = l->microfacet ? l->width_param[j] : -1;

	return w >= 0 ? l->microfacet->extent(p[w]) : -1;
}

double glint_lobe_width(const struct glint_model *m, const double *p, int j)
{
	const struct glint_fit_lobes *l = m->lobes;
	int w = l->microfacet ? l->width_param[j] : -1;

	return w >= 0 ? l->microfacet->core * p[w] : -1;
}

void glint_lobe_widen(const struct glint_model *m, double *p, int j, double s)
{
	const struct glint_fit_lobes *l = m->lobes;
	int w = l->microfacet ? l->width_param[j] : -1;

	if (w >= 0)
		p[w] = sqrt(p[w] * p[w] + s * s / l->microfacet->widen_div);
}
