/* SPDX-License-Identifier: MIT */
/*
 * Simulated annealing over every parameter, then LM over every parameter:
 * the coarse stage --optimizer anneal puts in place of any method's.
 */
#include "fit/internal.h"

/* Annealing over everything, then LM over everything. */
static int anneal_coarse(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS];
	int ret = fit_anneal_pass(ob, sl->coarse, sl->ncoarse, res);
	for (int k = 0; k < ob->m->nparams; k++)
		freev[k] = 1;
	if (ret == 0)
		ret = fit_run_pass(ob, "anneal-polish", sl->coarse, sl->ncoarse,
				   freev, 0, res, &lr);
	return ret;
}

const struct fit_method fit_method_anneal = {
	.coarse = anneal_coarse,
};
