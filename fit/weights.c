/* SPDX-License-Identifier: MIT */
/*
 * Reweighting: residual z-scores against the noise model, the weights of pixels
 * the model cannot explain.
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

/* Each selected value's squared residual over the noise model's
 * variance at the prediction, z[3 t + c] (NAN without a weight or a
 * variance); with s2, the scale of a model known up to it,
 * (median sqrt z / 0.6745)^2 (1 when none).  From the model at the
 * prediction, not the current weights, so that a fit and an evaluation
 * at its parameters agree. */
static int residual_z(const struct objective *ob, const struct fit_data *d,
		      const double *r, double *z, double *s2)
{
	double *a = malloc((size_t)3 * (ob->nsel > 0 ? ob->nsel : 1) *
			   sizeof(double));
	int n = 0;

	if (!a)
		return glint_error_set(ENOMEM, "out of memory");
	for (int t = 0; t < ob->nsel; t++)
		for (int c = 0; c < 3; c++) {
			int i = 3 * ob->sel[t] + c;
			double e = d->sw[i] > 0 ? r[3 * t + c] / d->sw[i] : 0,
			       v = d->sw[i] > 0 ? fit_data_variance(d, i,
								    d->y[i] + e)
						: 0;
			z[3 * t + c] = v > 0 ? e * e / v : NAN;
			if (v > 0)
				a[n++] = z[3 * t + c];
		}
	if (s2) {
		qsort(a, (size_t)n, sizeof(double), fit_cmp_double);
		double med = n ? sqrt(a[n / 2]) / 0.6745 : 1;
		*s2 = med > 0 ? med * med : 1;
	}
	free(a);
	return 0;
}

/*
 * Weights from the noise model at the fit's prediction (fit_data.h), for
 * a photo whose weights came with it (a weight image: a real noise model)
 * or without (the default signal-proportional variance, known up to its
 * scale, which residual_z() estimates; evaluated at the photo's own
 * values alone, it would leave a dark photo's albedos 20 % low)
 * and for the values the fit explains to within 3 standard deviations:
 * there the photo's own noise is what is left, and weights made from it
 * bias the fit.  Elsewhere the misfit is far above the noise, its weight
 * correlates with nothing that matters, and moving the weights there
 * would move the optimum (a near-mirror's sharp reflections: copper
 * under the studio map ended 3x above the truth's cost).
 */
int fit_reweight(struct objective *ob, struct fit_data *d, double *r)
{
	double *pred, *z;
	int ret;

	if (!d->noise_model && !d->shape_only)
		return 0;
	pred = malloc((size_t)3 * d->n * sizeof(double));
	z = malloc((size_t)3 * (ob->nsel > 0 ? ob->nsel : 1) * sizeof(double));
	ret = pred && z ? 0 : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = fit_obj_residuals(ob, ob->p, r);
	for (int i = 0; i < 3 * d->n && ret == 0; i++)
		pred[i] = d->y[i];
	/* A model known up to its scale (no weight image): the scale from
	 * the residuals' median, robust to a misfit's; a weight image's
	 * model is the noise's own (scale 1). */
	double s2 = 1;
	if (ret == 0)
		ret = residual_z(ob, d, r, z, d->noise_model ? NULL : &s2);
	/* Within 3 standard deviations of the noise model at the
	 * prediction, not of the photo's own weight: a value that came out
	 * dark by chance has a small variance of its own and so a large
	 * weighted residual, and leaving it on its own weight kept the very
	 * bias this removes (every albedo low at 1 000 electrons). */
	for (int t = 0; t < ob->nsel && ret == 0; t++)
		for (int c = 0; c < 3; c++)
			if (z[3 * t + c] < 9 * s2) /* NAN: no weight */
				pred[3 * ob->sel[t] + c] +=
					r[3 * t + c] /
					d->sw[3 * ob->sel[t] + c];
	if (ret == 0)
		fit_data_reweight(d, pred);
	ob->memo_valid = 0;
	free(pred);
	free(z);
	return ret;
}

/* Weights from the noise model at the coarse result's prediction
 * before the fine pass, so that its iterations, not only the short
 * polish, go to the optimum on them: at 1 000 electrons the polish alone
 * left matte paint's diffuse 2-6 % low, 3.5 % above the truth's cost. */
int fit_reweight_all(struct objective *ob, struct fit_data *d,
		     const struct selections *sl)
{
	double *r;
	int ret;

	if ((!d->noise_model && !d->shape_only) || !ob->cache)
		return 0;
	r = malloc((size_t)3 * (sl->nall > 0 ? sl->nall : 1) * sizeof(double));
	if (!r)
		return glint_error_set(ENOMEM, "out of memory");
	fit_select_all(ob, sl);
	ret = fit_reweight(ob, d, r);
	free(r);
	return ret;
}
