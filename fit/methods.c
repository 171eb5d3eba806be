/* SPDX-License-Identifier: MIT */
/*
 * The coarse-stage methods (three-pass, naive, varpro, annealing) and the table
 * that picks one by name.
 */
#include "fit/internal.h"
#include "fit/fit_data.h"
#include "fit/misfit.h"
#include "fit/optim/anneal.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/suggest.h"
#include "core/log.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The paper's three passes on the coarse set. */
static int three_pass(struct objective *ob, struct selections *sl,
		      struct glint_fit_result *res)
{
	const struct glint_model_ops *model = ob->m;
	const struct glint_fit_opts *o = ob->o;
	struct glint_lm_result lr;
	int freev[GLINT_MAX_PARAMS], any = 0, ret;

	/* Pass 1: constant lobes only, the others switched off. */
	for (int k = 0; k < model->nparams; k++) {
		int j = ob->lobe_of[k];
		freev[k] = j >= 0 && !model->lobe_varies[j];
		if (j >= 0 && model->lobe_varies[j])
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
		freev[k] = !(j >= 0 && !model->lobe_varies[j]);
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

/* Variable projection: a log-spaced scan of the first nonlinear parameter
 * (roughness for Torrance-Sparrow), then LM over the nonlinear ones with
 * the albedos solved inside. */
static int varpro_pass(struct objective *ob, const struct selections *sl,
		       struct glint_fit_result *res)
{
	const struct glint_model_ops *model = ob->m;
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
	if (nl == model->roughness_param)
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

static int varpro_coarse(struct objective *ob, struct selections *sl,
			 struct glint_fit_result *res)
{
	return varpro_pass(ob, sl, res);
}

static const struct fit_method methods[] = {
	[GLINT_FIT_THREE_PASS] = { three_pass, 0 },
	[GLINT_FIT_NAIVE] = { naive_coarse, 0 },
	[GLINT_FIT_VARPRO] = { varpro_coarse, 1 },
};

static const struct fit_method annealing = { anneal_coarse, 0 };

const struct fit_method *fit_method_of(const struct glint_fit_opts *o)
{
	if (o->optimizer == GLINT_OPT_ANNEAL)
		return &annealing;
	if ((unsigned)o->method >= sizeof(methods) / sizeof(methods[0]))
		return NULL;
	return &methods[o->method];
}

const struct fit_method *fit_method_named(enum glint_fit_method m)
{
	return &methods[m];
}
