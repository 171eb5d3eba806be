/* SPDX-License-Identifier: MIT */
/*
 * The fit's options and entry points: one photo, several views, or an
 * evaluation at given parameters (fit.h).
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

const char *const glint_fit_method_names[] = { "three-pass", "naive", "varpro",
					       NULL };
const char *const glint_fit_optimizer_names[] = { "auto", "lm", "anneal",
						  NULL };

const char *glint_fit_method_name(enum glint_fit_method m)
{
	return glint_fit_method_names[m];
}

int glint_fit_method_parse(const char *s, enum glint_fit_method *m)
{
	for (int i = 0; glint_fit_method_names[i]; i++)
		if (!strcmp(s, glint_fit_method_names[i])) {
			*m = (enum glint_fit_method)i;
			return 0;
		}
	const char *hint = glint_suggest_hint(s, glint_fit_method_names);
	return glint_error_set(EINVAL,
			       "fit method '%s': expected three-pass, naive or "
			       "varpro%s",
			       s, hint);
}

void glint_fit_default_opts(struct glint_fit_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->method = GLINT_FIT_THREE_PASS;
	o->coarse_to_fine = 1;
	o->mask_threshold = 0.1;
	/* 4096 pixels and 8 + 8 samples a hit at 4 hits a pixel: a 512 x 512
	 * fit in under 2 s here with roughness within 5 % (README,
	 * bench/fit).  The sample counts follow the scene's hits a pixel
	 * (glint_fit_resolve_samples()). */
	o->max_pixels = 4096;
	o->light_samples = 0;
	o->lobe_samples = 0;
	o->static_samples = 128;
	o->max_samples = 0;
	o->max_iter = 60;
	o->optimizer = GLINT_OPT_AUTO;
	o->seed = 1;
	o->anneal_evals = 150;
	o->mc_draws = 2;
	o->polish_iter = 8;
	o->level = 0.95;
}

static int samples_per_hit(int given, int per_pixel, int spp)
{
	if (given > 0)
		return given;
	int s = (int)lround((double)per_pixel / (spp > 4 ? spp : 4));
	return s > 1 ? s : 1;
}

void glint_fit_resolve_samples(struct glint_fit_opts *o, int spp)
{
	o->light_samples = samples_per_hit(o->light_samples, 32, spp);
	o->lobe_samples = samples_per_hit(o->lobe_samples, 32, spp);
	o->max_samples = samples_per_hit(o->max_samples, 256, spp);
}

void glint_fit_resolve_samples_views(struct glint_fit_opts *o,
				     const struct glint_fit_view *views,
				     int nviews)
{
	int spp = 0;
	for (int v = 0; v < nviews; v++)
		if (views[v].r->scene.spp > spp)
			spp = views[v].r->scene.spp;
	glint_fit_resolve_samples(o, spp);
}

int glint_fit_optimizer_parse(const char *s, enum glint_fit_optimizer *o)
{
	for (int i = 0; glint_fit_optimizer_names[i]; i++)
		if (!strcmp(s, glint_fit_optimizer_names[i])) {
			*o = (enum glint_fit_optimizer)i;
			return 0;
		}
	const char *hint = glint_suggest_hint(s, glint_fit_optimizer_names);
	return glint_error_set(EINVAL,
			       "optimizer '%s': expected lm, anneal or auto%s",
			       s, hint);
}

/* The evaluation at given parameters on the fit's terms: weights from the
 * noise model at the prediction and the mean of the same sample sets. */
static int eval_like_fit(struct objective *ob, struct fit_data *d,
			 const struct selections *sl)
{
	double *r = malloc((size_t)3 * (sl->nall > 0 ? sl->nall : 1) *
			   sizeof(double));
	int ret = r ? 0 : glint_error_set(ENOMEM, "out of memory");

	if (!ob->cache || ret < 0) {
		free(r);
		return ret;
	}
	fit_select_all(ob, sl);
	double p[GLINT_MAX_PARAMS];
	memcpy(p, ob->p, sizeof(p));
	if (ob->o->weights_at)
		memcpy(ob->p, ob->o->weights_at,
		       sizeof(double) * (size_t)ob->m->nparams);
	ret = fit_reweight(ob, d, r);
	memcpy(ob->p, p, sizeof(p));
	int nsets = 1 + ob->o->mc_draws;
	if (ret == 0)
		ret = fit_sample_sets(
			ob, nsets < MAX_SETS ? nsets - 1 : MAX_SETS - 1,
			ob->sets, &ob->nsets);
	free(r);
	return ret;
}

/* Each photo's pixels, joined into d, with where each lies in views[]. */
static int prepare_views(const struct glint_fit_view *in, int nviews,
			 const struct glint_fit_opts *o, struct fit_data *d,
			 struct view *views)
{
	struct fit_data_part parts[GLINT_FIT_MAX_VIEWS];
	int ret = fit_data_prepare_views(in, nviews, o, d, parts);

	for (int v = 0; v < nviews; v++) {
		memset(&views[v], 0, sizeof(views[v]));
		views[v].r = in[v].r;
		if (ret < 0)
			continue;
		views[v].off = parts[v].off;
		views[v].n = parts[v].n;
		views[v].interior = parts[v].interior;
		views[v].stride = parts[v].stride;
		views[v].frame_x = parts[v].frame_x;
		views[v].frame_y = parts[v].frame_y;
	}
	return ret;
}

static int fit_or_eval(const struct glint_fit_view *in, int nviews,
		       const struct glint_model *model,
		       const struct glint_fit_opts *o, const double *eval_p,
		       struct glint_fit_result *res)
{
	struct fit_data d = { 0 };
	struct objective ob = { 0 };
	struct selections sl = { 0 };
	struct view views[GLINT_FIT_MAX_VIEWS];
	struct glint_fit_opts ro = *o;
	int ret, interior = 0;
	double t0 = glint_clock_monotonic();

	if (nviews < 1 || nviews > GLINT_FIT_MAX_VIEWS)
		return glint_error_set(EINVAL,
				       "%d photos: a joint fit takes 1 to %d",
				       nviews, GLINT_FIT_MAX_VIEWS);
	glint_fit_resolve_samples_views(&ro, in, nviews);
	o = &ro;
	if (nviews > 1 && (glint_model_is_transparent(model) || o->faithful))
		return glint_error_set(
			EINVAL,
			"a joint fit of several photos needs the shade cache: "
			"not %s",
			o->faithful ? "--faithful" : "a transparent model");
	if (glint_model_is_transparent(model))
		return glint_fit_dielectric(in->r, model, in->photo, in->weight,
					    o, NULL, eval_p, res);
	memset(res, 0, sizeof(*res));
	res->model = model;
	if (model->bxdf->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "model %s cannot be fitted by LM here "
				       "(no linear lobes)",
				       model->name);
	ret = prepare_views(in, nviews, o, &d, views);
	if (ret < 0)
		goto out;
	for (int v = 0; v < nviews; v++)
		interior += views[v].interior;
	res->interior = interior;
	ret = fit_objective_init(&ob, views, nviews, model, &d, o);
	if (ret < 0)
		goto out;
	if (!eval_p && fit_sphere_px(&ob) < FIT_SYS_SMALLEST_PX)
		glint_log_warn(
			"the sphere is %.0f px in radius: the intervals' "
			"systematic terms were measured down to %.0f "
			"px and are extrapolated below "
			"(docs/fitting.md, \"Uncertainty\")",
			fit_sphere_px(&ob), FIT_SYS_SMALLEST_PX);
	res->setup_seconds = glint_clock_monotonic() - t0;
	if (eval_p) {
		memcpy(ob.p, eval_p, (size_t)model->nparams * sizeof(double));
		memcpy(res->p, ob.p, sizeof(res->p));
		sl.all = malloc((size_t)(d.n > 0 ? d.n : 1) * sizeof(int));
		if (!sl.all) {
			ret = glint_error_set(ENOMEM, "out of memory");
			goto out;
		}
		for (int i = 0; i < d.n; i++)
			sl.all[i] = i;
		sl.nall = d.n;
		ret = eval_like_fit(&ob, &d, &sl);
		if (ret < 0)
			goto out;
		fit_finish_stats(&ob, sl.all, d.n, res);
		res->seconds = glint_clock_monotonic() - t0;
		goto out;
	}
	ret = fit_make_selections(&ob, &sl);
	if (ret < 0)
		goto out;
	res->specular_pixels = sl.nspec;
	/*
	 * A level sampled every `spacing` pixels cannot tell lobes narrower
	 * than the reflected directions between its samples (about
	 * 2 spacing / R radians on a sphere R pixels in radius, i.e. a
	 * roughness of spacing / R): a mirror's glint can fall between
	 * samples and "mirror" becomes a false minimum.  Coarse passes keep
	 * roughness above that (the largest over the photos); the fine pass
	 * is free.
	 */
	double coarse_rough_lo = 0, footprint = INFINITY;
	for (int v = 0; v < nviews; v++) {
		double radius = sqrt(views[v].interior / M_PI);
		coarse_rough_lo =
			fmax(coarse_rough_lo, 4.0 * views[v].stride / radius);
		/* the finest photo's (fit/result.c) */
		footprint = fmin(footprint, 1 / radius);
	}
	if (sl.ncoarse < sl.nall)
		ob.rough_lo = coarse_rough_lo;
	ret = fit_coarse_passes(&ob, &sl, res);
	if (ret == 0)
		ret = fit_reweight_all(&ob, &d, &sl);
	if (ret == 0)
		ret = fit_fine_pass(&ob, &sl, coarse_rough_lo, footprint, res);
	if (ret == 0)
		ret = fit_uncertainty(&ob, &d, &sl, res);
	if (ret < 0)
		goto out;
	memcpy(res->p, ob.p, sizeof(res->p));
	fit_finish_stats(&ob, sl.all, sl.nall, res);
	fit_baselines(&ob, &d, res);
	/* A roughness the pixels do not resolve (an upper bound, not a
	 * value): a smoother surface looks the same, so its interval is
	 * from the model's smoothest to the bound. */
	int rk = glint_model_roughness_param(model);
	double bound = rk >= 0 ? glint_fit_roughness_bound(res) : NAN;
	if (isfinite(bound)) {
		res->unc.lo[rk] = model->params[rk].lo;
		res->unc.hi[rk] = bound;
	}
	res->seconds = glint_clock_monotonic() - t0;
out:
	fit_objective_free(&ob);
	fit_selections_free(&sl);
	free_data(&d);
	return ret;
}

int glint_fit(struct glint_renderer *r, const struct glint_model *model,
	      const struct glint_image *photo, const struct glint_image *weight,
	      const struct glint_fit_opts *o, struct glint_fit_result *res)
{
	struct glint_fit_view v = { r, photo, weight };

	return fit_or_eval(&v, 1, model, o, NULL, res);
}

int glint_fit_views(const struct glint_fit_view *views, int nviews,
		    const struct glint_model *model,
		    const struct glint_fit_opts *o,
		    struct glint_fit_result *res)
{
	return fit_or_eval(views, nviews, model, o, NULL, res);
}

int glint_fit_evaluate(struct glint_renderer *r,
		       const struct glint_model *model,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, const double *p,
		       struct glint_fit_result *res)
{
	struct glint_fit_view v = { r, photo, weight };

	return fit_or_eval(&v, 1, model, o, p, res);
}
