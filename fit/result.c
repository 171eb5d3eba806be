/* SPDX-License-Identifier: MIT */
/* A fit's result as JSON (the parameters and passes of params.json). */
#include "job.h"

#include <math.h>

json_t *glint_fit_params_json(const struct glint_fit_result *r)
{
	const struct glint_model_ops *m = r->model;
	json_t *list = json_array();

	for (int k = 0; k < m->nparams; k++) {
		const struct glint_param *pi = &m->params[k];
		json_array_append_new(
			list, json_pack("{s:s,s:f,s:o,s:b,s:[f,f]}", "name",
					pi->name, "value", r->p[k], "stderr",
					isfinite(r->se[k]) ? json_real(r->se[k])
							   : json_null(),
					"at_bound", r->at_bound[k], "bounds",
					pi->lo, pi->hi));
	}
	return list;
}

json_t *glint_fit_passes_json(const struct glint_fit_result *r)
{
	json_t *a = json_array();

	for (int i = 0; i < r->npasses; i++) {
		const struct glint_fit_pass *p = &r->passes[i];
		json_array_append_new(
			a,
			json_pack("{s:s,s:i,s:i,s:i,s:f,s:f,s:f}", "name",
				  p->name, "pixels", p->pixels, "iterations",
				  p->iterations, "evaluations", p->evaluations,
				  "cost_start", p->cost0, "cost_end", p->cost,
				  "seconds", p->seconds));
	}
	return a;
}
