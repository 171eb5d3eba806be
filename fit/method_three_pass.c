/* SPDX-License-Identifier: MIT */
/*
 * The paper's method (Joshi & Jensen): three passes on the coarse pixel
 * set — the constant (diffuse) lobes alone, then the rest from a scanned
 * start with the diffuse held, then everything.
 */
#include "fit/internal.h"

#include <string.h>

/* The paper's three passes on the coarse set. */
static int three_pass(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res)
{
	const struct glint_model *model = ob->m;
	const struct glint_fit_opts *o = ob->o;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], any = 0, ret;

	/* Pass 1: constant lobes only, the others switched off. */
	for (int k = 0; k < model->nparams; k++) {
		int j = ob->lobe_of[k];
		freev[k] = j >= 0 && !model->lobes->varies[j];
		if (j >= 0 && model->lobes->varies[j])
			ob->p[k] = 0;
	}
	if (sl->ndiff < 8) {
		memcpy(sl->diff, sl->coarse, (size_t)sl->ncoarse * sizeof(int));
		sl->ndiff = sl->ncoarse;
	}
	ret = fit_run_pass(ob, "1 diffuse", sl->diff, sl->ndiff, freev, 0, res,
			   &lr);
	if (ret < 0)
		return ret;
	/* Pass 2: the rest from the paper's values, diffuse held. */
	for (int k = 0; k < model->nparams; k++) {
		int j = ob->lobe_of[k];
		freev[k] = !(j >= 0 && !model->lobes->varies[j]);
		any |= freev[k];
		if (freev[k])
			ob->p[k] =
				o->start ? o->start[k] : model->params[k].def;
	}
	if (any) {
		const int *sel = sl->nspec >= 8 ? sl->spec : sl->coarse;
		int nsel = sl->nspec >= 8 ? sl->nspec : sl->ncoarse;
		ret = fit_scan_start(ob, sel, nsel);
		if (ret == 0)
			ret = fit_run_pass(ob, "2 specular", sel, nsel, freev,
					   0, res, &lr);
		if (ret < 0)
			return ret;
	}
	/* Pass 3: everything, all pixels. */
	for (int k = 0; k < model->nparams; k++)
		freev[k] = 1;
	return fit_run_pass(ob, "3 all", sl->coarse, sl->ncoarse, freev, 0, res,
			    &lr);
}

const struct fit_method fit_method_three_pass = {
	.coarse = three_pass,
};
