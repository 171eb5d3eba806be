/* SPDX-License-Identifier: MIT */
/* Model selection by information criteria (select.h). */
#include "select.h"

#include "fit_data.h"
#include "fit/optim/lm.h"

#include "core/error.h"
#include "core/log.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The pixels, their lobes at the current parameters, and scratch. */
struct sel {
	const struct glint_fit_view *views; /* the photos, each in its scene */
	int nviews;
	struct fit_data_part parts[GLINT_FIT_MAX_VIEWS];
	struct fit_data d;
	struct glint_shade_cache *cache;
	const struct glint_model *cache_model; /* the model of cache */
	double *lobes; /* d.n x nlobes x 3 (up to 3 lobes) */
	double x[4];   /* grey: the linear unknowns at the last call */
	double xse[4];
};

static const char *const short_name[GLINT_SEL_N] = {
	[GLINT_SEL_RGB] = "RGB",
	[GLINT_SEL_GREY] = "grey specular",
	[GLINT_SEL_CONST_FRESNEL] = "constant Fresnel",
	[GLINT_SEL_LAMBERT] = "lambert",
	[GLINT_SEL_GGX] = "ggx",
	[GLINT_SEL_OREN_NAYAR] = "oren-nayar",
	[GLINT_SEL_TWO_LOBE] = "two-lobe",
};

/* Weighted residuals sw (y - sum albedo_j A_j) of model m's lobes in
 * s->lobes, the albedos at p[m->lobes->param[j]]. */
static double residuals(const struct sel *s, const struct glint_model *m,
			const double *p, double *r)
{
	int nj = m->bxdf->nlobes;
	double cost = 0;
	for (int i = 0; i < s->d.n; i++)
		for (int c = 0; c < 3; c++) {
			const double *a = s->lobes + (size_t)i * nj * 3;
			double v = s->d.y[i * 3 + c];
			for (int j = 0; j < nj; j++)
				v -= p[m->lobes->param[j] + c] * a[j * 3 + c];
			double e = s->d.sw[i * 3 + c] * v;
			if (r)
				r[i * 3 + c] = e;
			cost += e * e;
		}
	return cost / 2;
}

/*
 * The bounded linear least squares of the unknowns x (free[u] says which)
 * over sums M x = b, by a small active set: solve the free ones, fix any
 * that leave [0, 1] at the bound, again.  Small (4 unknowns).
 */
static void solve_box(int nu, const double *M, const double *b, double *x,
		      double *xse, double s2)
{
	int fixed[4] = { 0 };
	for (int round = 0; round < 8; round++) {
		int idx[4], nf = 0;
		double A[16], rhs[4];
		for (int u = 0; u < nu; u++)
			if (!fixed[u])
				idx[nf++] = u;
		for (int a = 0; a < nf; a++) {
			rhs[a] = b[idx[a]];
			for (int u = 0; u < nu; u++)
				if (fixed[u])
					rhs[a] -= M[idx[a] * nu + u] * x[u];
			for (int c = 0; c < nf; c++)
				A[a * nf + c] = M[idx[a] * nu + idx[c]];
		}
		gsl_matrix_view mv = gsl_matrix_view_array(A, nf, nf);
		gsl_vector_view bv = gsl_vector_view_array(rhs, nf);
		gsl_error_handler_t *old = gsl_set_error_handler_off();
		int st = nf ? gsl_linalg_cholesky_decomp1(&mv.matrix) : 0;
		if (!st && nf)
			st = gsl_linalg_cholesky_svx(&mv.matrix, &bv.vector);
		if (!st && nf)
			gsl_linalg_cholesky_invert(&mv.matrix);
		gsl_set_error_handler(old);
		int again = 0;
		for (int a = 0; a < nf; a++) {
			double v = st ? 0 : rhs[a];
			x[idx[a]] = v;
			xse[idx[a]] = st ? NAN : sqrt(s2 * A[a * nf + a]);
			if (v < 0 || v > 1) {
				x[idx[a]] = v < 0 ? 0 : 1;
				xse[idx[a]] = 0;
				fixed[idx[a]] = again = 1;
			}
		}
		for (int u = 0; u < nu; u++)
			if (fixed[u])
				xse[u] = 0;
		if (!again)
			return;
	}
}

/* Lambert: per channel, the diffuse albedo alone (lobe 0). */
static double fit_lambert(struct sel *s, double *alb, double *se, int nres)
{
	double M[3] = { 0 }, b[3] = { 0 };
	for (int i = 0; i < s->d.n; i++)
		for (int c = 0; c < 3; c++) {
			double w = s->d.sw[i * 3 + c] * s->d.sw[i * 3 + c];
			double a = s->lobes[(size_t)i * 6 + c];
			M[c] += w * a * a;
			b[c] += w * a * s->d.y[i * 3 + c];
		}
	for (int c = 0; c < 3; c++) {
		alb[c] = M[c] > 0 ? fmin(1, fmax(0, b[c] / M[c])) : 0;
		alb[3 + c] = 0;
	}
	double cost = residuals(s, &glint_model_torrance_sparrow, alb, NULL);
	for (int c = 0; c < 3; c++)
		se[c] = alb[c] > 0 && alb[c] < 1
				? sqrt(2 * cost / (nres - 3) / M[c])
				: 0;
	return cost;
}

/* Grey specular at (roughness, ior) = q: lobes there, then the four
 * albedos (RGB diffuse, one specular) by bounded linear least squares. */
static int grey_residuals(void *ctx, const double *q, double *r)
{
	struct sel *s = ctx;
	double p[8] = { 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, q[0], q[1] };
	double M[16] = { 0 }, b[4] = { 0 }, alb[6];
	glint_shade_cache_lobes(s->cache, p, s->lobes);
	for (int i = 0; i < s->d.n; i++)
		for (int c = 0; c < 3; c++) {
			double w = s->d.sw[i * 3 + c] * s->d.sw[i * 3 + c];
			double a0 = s->lobes[(size_t)i * 6 + c];
			double a1 = s->lobes[(size_t)i * 6 + 3 + c];
			double y = s->d.y[i * 3 + c];
			M[c * 4 + c] += w * a0 * a0;
			M[c * 4 + 3] += w * a0 * a1;
			M[3 * 4 + c] += w * a0 * a1;
			M[15] += w * a1 * a1;
			b[c] += w * a0 * y;
			b[3] += w * a1 * y;
		}
	solve_box(4, M, b, s->x, s->xse, 1);
	for (int c = 0; c < 3; c++) {
		alb[c] = s->x[c];
		alb[3 + c] = s->x[3];
	}
	residuals(s, &glint_model_torrance_sparrow, alb, r);
	return 0;
}

static void score(struct glint_select_candidate *c, int n)
{
	double l = n * log(2 * c->cost / n);
	c->bic = l + c->k * log(n);
	c->aic = l + 2.0 * c->k;
}

/* Grey specular: LM over roughness and ior from the full fit's, the
 * albedos solved exactly at each step (into s->x). */
static int fit_grey(struct sel *s, const struct glint_model *ts,
		    const struct glint_fit_result *full, int n, double *rv,
		    struct glint_select_candidate *c)
{
	double lo[2] = { ts->params[6].lo, ts->params[7].lo },
	       hi[2] = { ts->params[6].hi, ts->params[7].hi };
	double q[2] = { full->p[6], full->p[7] };
	struct glint_lm_problem pr = { 2,    3 * s->d.n, lo, hi, grey_residuals,
				       NULL, s };
	struct glint_lm_opts lo_ = { 0 };
	struct glint_lm_result lr;

	c->name = "torrance-sparrow, grey specular";
	c->k = 6;
	c->scored = 1;
	c->model = ts;
	glint_lm_default_opts(&lo_);
	lo_.max_iter = 40;
	int ret = glint_lm_solve(&pr, &lo_, q, &lr);
	if (ret < 0)
		return ret;
	grey_residuals(s, q, rv);
	c->cost = lr.cost;
	double s2 = 2 * lr.cost / (n - c->k);
	for (int u = 0; u < 4; u++)
		s->xse[u] *= sqrt(s2);
	for (int k = 0; k < 3; k++) {
		c->p[k] = s->x[k];
		c->se[k] = s->xse[k];
		c->p[3 + k] = s->x[3];
		c->se[3 + k] = s->xse[3];
	}
	c->p[6] = q[0];
	c->p[7] = q[1];
	c->se[6] = lr.se[0];
	c->se[7] = lr.se[1];
	return 0;
}

/* A candidate at its own fit, its cost by the same sums as the others'
 * (its lobes from a cache of its model). */
static int score_fitted(struct sel *s, const struct glint_shade_cache_opts *co,
			const struct glint_fit_result *fit,
			struct glint_select_candidate *c)
{
	struct glint_shade_cache *cache = s->cache;
	memcpy(c->p, fit->p, sizeof(c->p));
	memcpy(c->se, fit->se, sizeof(c->se));
	if (c->model != s->cache_model) {
		int ret =
			fit_data_cache_new(s->views, s->nviews, &s->d, s->parts,
					   c->model, co, NULL, &cache);
		if (ret < 0)
			return ret;
	}
	glint_shade_cache_lobes(cache, c->p, s->lobes);
	if (cache != s->cache)
		glint_shade_cache_free(cache);
	c->cost = residuals(s, c->model, c->p, NULL);
	c->scored = 1;
	return 0;
}

/* The lowest BIC (and AIC) wins; say why in the full fit's terms. */
static void choose(struct glint_selection *out, int n)
{
	out->chosen = out->chosen_aic = GLINT_SEL_RGB;
	for (int k = 0; k < GLINT_SEL_N; k++) {
		if (!out->c[k].scored)
			continue;
		score(&out->c[k], n);
		if (out->c[k].bic < out->c[out->chosen].bic)
			out->chosen = k;
		if (out->c[k].aic < out->c[out->chosen_aic].aic)
			out->chosen_aic = k;
	}
	const double *p = out->fit[GLINT_SEL_RGB].p,
		     *se = out->fit[GLINT_SEL_RGB].se;
	double spread = fmax(fabs(p[3] - p[4]),
			     fmax(fabs(p[4] - p[5]), fabs(p[3] - p[5])));
	double sse = sqrt(se[3] * se[3] + se[4] * se[4] + se[5] * se[5]);
	double spec = (p[3] + p[4] + p[5]) / 3;
	char above[384] = "";
	size_t len = 0;
	for (int k = 0; k < GLINT_SEL_N && len < sizeof(above); k++)
		if (out->c[k].scored && k != out->chosen)
			len += snprintf(
				above + len, sizeof(above) - len, "%s%s %+.1f",
				len ? ", " : "", short_name[k],
				out->c[k].bic - out->c[out->chosen].bic);
	snprintf(out->why, sizeof(out->why),
		 "lowest BIC: %s (BIC above it: %s; n = %d residuals). Full "
		 "fit: specular channels spread %.4f against standard errors "
		 "about %.4f; mean specular %.4f +- %.4f",
		 out->c[out->chosen].name, above, n, spread, sse, spec,
		 sse / 3);
}

/* A candidate with a fit of its own: fit it, then score it. */
static int fit_and_score(struct sel *s, const struct glint_shade_cache_opts *co,
			 const struct glint_fit_opts *o,
			 struct glint_selection *out, int k)
{
	struct glint_select_candidate *c = &out->c[k];
	struct glint_fit_opts oo = *o;
	/* The richer models by variable projection (their albedos solved
	 * exactly at every step): the three-pass method's pass holding the
	 * diffuse fixed loses a broad second lobe to it (two-lobe nickel:
	 * roughness2 ran to its bound, cost 35188 against 24970). */
	if (k > GLINT_SEL_LAMBERT)
		oo.method = GLINT_FIT_VARPRO;
	int ret = glint_fit_views(s->views, s->nviews, c->model, &oo,
				  &out->fit[k]);

	if (ret < 0)
		return glint_error_prefix(ret, "fitting %s", c->model->name);
	out->has_fit[k] = 1;
	return score_fitted(s, co, &out->fit[k], c);
}

int glint_select_model(struct glint_renderer *r,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, int richer,
		       struct glint_selection *out)
{
	struct glint_fit_view v = { r, photo, weight };
	return glint_select_model_views(&v, 1, o, richer, out);
}

int glint_select_model_views(const struct glint_fit_view *views, int nviews,
			     const struct glint_fit_opts *o, int richer,
			     struct glint_selection *out)
{
	const struct glint_model *ts = &glint_model_torrance_sparrow;
	struct sel s = { .views = views, .nviews = nviews };
	int ret;
	double *rv = NULL;
	static const struct {
		int k, n;
		const char *name;
		const struct glint_model *m;
	} fitted[] = {
		{ GLINT_SEL_RGB, 8, "torrance-sparrow (RGB specular)",
		  &glint_model_torrance_sparrow },
		{ GLINT_SEL_CONST_FRESNEL, 7,
		  "torrance-sparrow, constant Fresnel",
		  &glint_model_ts_constant_fresnel },
		{ GLINT_SEL_GGX, 8, "ggx (Trowbridge-Reitz lobe)",
		  &glint_model_ggx },
		{ GLINT_SEL_OREN_NAYAR, 9,
		  "oren-nayar (rough diffuse, Beckmann lobe)",
		  &glint_model_oren_nayar },
		{ GLINT_SEL_TWO_LOBE, 12, "two-lobe (two Beckmann lobes)",
		  &glint_model_two_lobe },
	};

	memset(out, 0, sizeof(*out));
	for (size_t f = 0; f < sizeof(fitted) / sizeof(fitted[0]); f++)
		out->c[fitted[f].k] = (struct glint_select_candidate){
			.name = fitted[f].name,
			.k = fitted[f].n,
			.model = fitted[f].m,
		};
	if (nviews < 1 || nviews > GLINT_FIT_MAX_VIEWS)
		return glint_error_set(EINVAL,
				       "%d photos: a joint fit takes 1 to %d",
				       nviews, GLINT_FIT_MAX_VIEWS);
	ret = fit_data_prepare_views(views, nviews, o, &s.d, s.parts);
	if (ret < 0)
		return ret;
	struct glint_fit_opts ro = *o;
	glint_fit_resolve_samples_views(&ro, views, nviews);
	struct glint_shade_cache_opts co = {
		.light_samples = ro.light_samples,
		.lobe_samples = ro.lobe_samples,
		.static_samples = o->static_samples,
		.no_footprint = o->no_footprint,
		.nthreads = o->nthreads,
	};
	ret = fit_data_cache_new(views, nviews, &s.d, s.parts, ts, &co, NULL,
				 &s.cache);
	s.cache_model = ts;
	s.lobes = malloc((size_t)s.d.n * 9 * sizeof(double));
	rv = malloc((size_t)s.d.n * 3 * sizeof(double));
	if (!ret && (!s.lobes || !rv))
		ret = glint_error_set(ENOMEM, "out of memory");
	if (ret < 0)
		goto out;
	int n = 0;
	for (int i = 0; i < 3 * s.d.n; i++)
		n += s.d.sw[i] > 0;
	out->n = n;

	/* RGB first: grey starts from it, and lambert and grey use the
	 * torrance-sparrow lobes it leaves in s.lobes. */
	ret = fit_and_score(&s, &co, o, out, GLINT_SEL_RGB);
	if (ret < 0)
		goto out;
	struct glint_select_candidate *c = &out->c[GLINT_SEL_LAMBERT];
	c->name = "lambert";
	c->k = 3;
	c->model = &glint_model_lambert;
	c->cost = fit_lambert(&s, c->p, c->se, n);
	c->scored = 1;
	ret = fit_grey(&s, ts, &out->fit[GLINT_SEL_RGB], n, rv,
		       &out->c[GLINT_SEL_GREY]);
	for (int k = GLINT_SEL_CONST_FRESNEL; k < GLINT_SEL_N && !ret; k++)
		if (k == GLINT_SEL_CONST_FRESNEL ||
		    (richer && k > GLINT_SEL_LAMBERT))
			ret = fit_and_score(&s, &co, o, out, k);
	if (ret < 0)
		goto out;
	choose(out, n);
	ret = 0;
out:
	free(rv);
	free(s.lobes);
	glint_shade_cache_free(s.cache);
	free_data(&s.d);
	return ret;
}

json_t *glint_selection_to_json(const struct glint_selection *s)
{
	json_t *cands = json_array();
	for (int k = 0; k < GLINT_SEL_N; k++) {
		const struct glint_select_candidate *c = &s->c[k];
		if (!c->scored)
			continue;
		json_t *ps = json_object();
		for (int j = 0; j < c->model->nparams; j++)
			json_object_set_new(
				ps, c->model->params[j].name,
				json_pack("{s:f, s:o}", "value", c->p[j],
					  "stderr",
					  isfinite(c->se[j])
						  ? json_real(c->se[j])
						  : json_null()));
		json_array_append_new(
			cands,
			json_pack("{s:s, s:s, s:i, s:f, s:f, s:f, s:o}", "name",
				  c->name, "model", c->model->name, "k", c->k,
				  "cost", c->cost, "bic", c->bic, "aic", c->aic,
				  "parameters", ps));
	}
	return json_pack("{s:s, s:s, s:i, s:s, s:o}", "chosen",
			 s->c[s->chosen].name, "chosen_by_aic",
			 s->c[s->chosen_aic].name, "residuals", s->n, "why",
			 s->why, "candidates", cands);
}
