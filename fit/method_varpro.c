/* SPDX-License-Identifier: MIT */
/*
 * Variable projection: the albedos solved exactly inside the objective,
 * LM over the nonlinear parameters only (coarse and fine).
 */
#include "fit/internal.h"

#include "core/error.h"

#include <math.h>
#include <stdlib.h>

/* Variable projection: a log-spaced scan of the first nonlinear parameter
 * (roughness for Torrance-Sparrow), then LM over the nonlinear ones with
 * the albedos solved inside. */
static int varpro_pass(struct objective *ob, const struct selections *sl,
		       struct glint_fit_result *res)
{
	const struct glint_model *model = ob->m;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], nl = -1;

	if (!ob->cache)
		return glint_error_set(EINVAL, "variable projection needs the "
					       "shade cache (not --faithful)");
	for (int k = 0; k < model->nparams; k++) {
		freev[k] = ob->lobe_of[k] < 0;
		if (freev[k] && nl < 0)
			nl = k;
	}
	if (nl < 0)
		return 0;
	const struct glint_param *pi = &model->params[nl];
	double best = INFINITY, bestv = pi->def;
	double lo = fmax(pi->lo, 1e-3), hi = fmin(pi->hi, 0.6);
	if (nl == model->lobes->roughness_param)
		lo = fmax(lo, ob->rough_lo);
	double *scratch = malloc((size_t)3 * sl->ncoarse * sizeof(double));
	if (!scratch)
		return glint_error_set(ENOMEM, "out of memory");
	ob->sel = sl->coarse;
	ob->nsel = sl->ncoarse;
	ob->varpro = 1;
	ob->nfree = 0;
	for (int i = 0; i < 10; i++) {
		double v = lo * pow(hi / lo, i / 9.0);
		ob->p[nl] = v;
		ob->memo_valid = 0;
		fit_obj_residuals(ob, ob->p, scratch);
		double c = 0;
		for (int k = 0; k < 3 * sl->ncoarse; k++)
			c += scratch[k] * scratch[k];
		if (c < best) {
			best = c;
			bestv = v;
		}
	}
	free(scratch);
	ob->p[nl] = bestv;
	return fit_run_pass(ob, "varpro", sl->coarse, sl->ncoarse, freev, 1,
			    res, &lr);
}

static int varpro_coarse(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	return varpro_pass(ob, sl, res);
}

const struct fit_method fit_method_varpro = {
	.coarse = varpro_coarse,
	.linear_fine = 1,
};
