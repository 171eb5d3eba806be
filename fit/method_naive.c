/* SPDX-License-Identifier: MIT */
/*
 * The naive method: every parameter at once from a scanned start.
 */
#include "fit/internal.h"

/* Every parameter at once from a scanned start (the naive method). */
static int naive_coarse(struct objective *ob, struct selections *sl,
			struct glint_fit_result *res)
{
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS];
	int ret = fit_scan_start(ob, sl->coarse, sl->ncoarse);
	if (ret < 0)
		return ret;
	for (int k = 0; k < ob->m->nparams; k++)
		freev[k] = 1;
	return fit_run_pass(ob, "all at once", sl->coarse, sl->ncoarse, freev,
			    0, res, &lr);
}

const struct fit_method fit_method_naive = {
	.coarse = naive_coarse,
};
