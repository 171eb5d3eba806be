/* SPDX-License-Identifier: MIT */
/*
 * The objective: a model's render of the selected pixels against the photo, its
 * residuals and Jacobian, the albedos solved in closed form, the render caches.
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

/* The photo holding fitted pixel s. */
int fit_view_of(const struct objective *ob, int s)
{
	int v = 0;

	while (v + 1 < ob->nviews && s >= ob->views[v + 1].off)
		v++;
	return v;
}

int fit_nonlinear_same(const struct objective *ob, const double *a,
		       const double *b)
{
	for (int k = 0; k < ob->m->nparams; k++)
		if (ob->lobe_of[k] < 0 && a[k] != b[k])
			return 0;
	return 1;
}

int fit_wants_dlobes(const struct objective *ob)
{
	const struct glint_fit_lobes *l = ob->m->lobes;

	if (!ob->cache || ob->varpro || !l || !l->factor_dlog)
		return 0;
	for (int k = 0; k < ob->nfree; k++)
		if (ob->free_idx[k] == l->factor_param)
			return 1;
	return 0;
}

static void lobes_at(struct objective *ob, const double *p, double *dst)
{
	glint_shade_cache_lobes_sel(ob->cache, p, ob->sel, ob->nsel, dst);
}

/* The lobes at p (and their derivatives in ob->dlobes where
 * fit_wants_dlobes()), memoised: LM asks for the Jacobian where it last
 * evaluated the residuals. */
static const double *memo_lobes(struct objective *ob, const double *p)
{
	int want = fit_wants_dlobes(ob);

	if (!ob->memo_valid || ob->memo_cache != ob->cache ||
	    ob->memo_sel != ob->sel || ob->memo_nsel != ob->nsel ||
	    !fit_nonlinear_same(ob, p, ob->memo_p) || (want && !ob->memo_d)) {
		if (want)
			glint_shade_cache_lobes_d(ob->cache, p, ob->sel,
						  ob->nsel, ob->lobes,
						  ob->dlobes);
		else
			lobes_at(ob, p, ob->lobes);
		memcpy(ob->memo_p, p, sizeof(ob->memo_p));
		ob->memo_valid = 1;
		ob->memo_d = want;
		ob->memo_cache = ob->cache;
		ob->memo_sel = ob->sel;
		ob->memo_nsel = ob->nsel;
	}
	return ob->lobes;
}

double fit_pixel_value(const struct objective *ob, const double *p,
		       const double *lobes, int s, int c)
{
	int nj = ob->m->bxdf->nlobes;
	double v = 0;
	for (int j = 0; j < nj; j++)
		v += p[ob->m->lobes->param[j] + c] *
		     lobes[((size_t)s * nj + j) * 3 + c];
	return v;
}

/*
 * Bounded linear least squares for the albedos of one channel, k <= 3
 * unknowns: every assignment of each unknown to {free, lower, upper} is
 * tried, the free ones solved from the normal equations, and the best
 * feasible one kept (exact for a convex quadratic over a box).
 */
static void solve_albedos(struct objective *ob, double *p, const double *lobes,
			  int c)
{
	const struct glint_model *m = ob->m;
	int nj = m->bxdf->nlobes;
	double g[3][3] = { { 0 } }, b[3] = { 0 }, yy = 0;

	for (int t = 0; t < ob->nsel; t++) {
		int s = ob->sel[t];
		double w = ob->d->sw[3 * s + c] * ob->d->sw[3 * s + c];
		double y = ob->d->y[3 * s + c];
		const double *a = lobes + (size_t)t * nj * 3;
		for (int j = 0; j < nj; j++) {
			b[j] += w * a[j * 3 + c] * y;
			for (int k = 0; k < nj; k++)
				g[j][k] += w * a[j * 3 + c] * a[k * 3 + c];
		}
		yy += w * y * y;
	}
	int combos = 1;
	for (int j = 0; j < nj; j++)
		combos *= 3;
	double best = INFINITY, best_a[3] = { 0 };
	for (int code = 0; code < combos; code++) {
		double a[3], lo[3], hi[3];
		int st[3], fr[3], nf = 0, cc = code;
		for (int j = 0; j < nj; j++) {
			const struct glint_param *pi =
				&m->params[m->lobes->param[j] + c];
			lo[j] = pi->lo;
			hi[j] = pi->hi;
			st[j] = cc % 3;
			cc /= 3;
			a[j] = st[j] == 1 ? lo[j] : hi[j];
			if (st[j] == 0)
				fr[nf++] = j;
		}
		if (nf) {
			/* Solve G_ff a_f = b_f - G_fb a_b by Gaussian
			 * elimination (nf <= 3). */
			double mm[3][4];
			for (int u = 0; u < nf; u++) {
				double rhs = b[fr[u]];
				for (int j = 0; j < nj; j++)
					if (st[j])
						rhs -= g[fr[u]][j] * a[j];
				for (int v = 0; v < nf; v++)
					mm[u][v] = g[fr[u]][fr[v]];
				mm[u][nf] = rhs;
			}
			int ok = 1;
			for (int u = 0; u < nf && ok; u++) {
				int piv = u;
				for (int v = u + 1; v < nf; v++)
					if (fabs(mm[v][u]) > fabs(mm[piv][u]))
						piv = v;
				if (fabs(mm[piv][u]) < 1e-300) {
					ok = 0;
					break;
				}
				for (int k = 0; k <= nf; k++) {
					double tmp = mm[u][k];
					mm[u][k] = mm[piv][k];
					mm[piv][k] = tmp;
				}
				for (int v = 0; v < nf; v++) {
					if (v == u)
						continue;
					double f = mm[v][u] / mm[u][u];
					for (int k = u; k <= nf; k++)
						mm[v][k] -= f * mm[u][k];
				}
			}
			if (!ok)
				continue;
			for (int u = 0; u < nf; u++) {
				double v = mm[u][nf] / mm[u][u];
				if (v < lo[fr[u]] || v > hi[fr[u]])
					ok = 0;
				a[fr[u]] = v;
			}
			if (!ok)
				continue;
		}
		double cost = yy;
		for (int j = 0; j < nj; j++) {
			cost -= 2 * a[j] * b[j];
			for (int k = 0; k < nj; k++)
				cost += a[j] * g[j][k] * a[k];
		}
		if (cost < best) {
			best = cost;
			memcpy(best_a, a, sizeof(best_a));
		}
	}
	for (int j = 0; j < nj; j++)
		p[m->lobes->param[j] + c] = best_a[j];
}

int fit_render_full(struct objective *ob, const double *p)
{
	struct glint_renderer *r = ob->r;
	struct glint_gbuffer gb;
	struct glint_shade_opts so = {
		.light_samples = r->scene.light_samples,
		.brdf_samples = r->scene.brdf_samples,
		.nthreads = ob->o->nthreads,
	};
	/* The paper's way: trace and render the whole image each time. */
	int ret = glint_tracer_primary(r->tracer, &r->scene.cam, r->scene.spp,
				       ob->o->nthreads, NULL, &gb);
	if (ret < 0)
		return ret;
	ret = glint_render_shade(&gb, r->tracer, r->env, ob->m, p, &so, ob->img,
				 NULL);
	glint_gbuffer_free(&gb);
	return ret;
}

int fit_obj_residuals(void *ctx, const double *q, double *res)
{
	struct objective *ob = ctx;
	double p[GLINT_MAX_PARAMS];

	memcpy(p, ob->p, sizeof(p));
	for (int k = 0; k < ob->nfree; k++)
		p[ob->free_idx[k]] = q[k];
	ob->evals++;
	if (!ob->cache) {
		int ret = fit_render_full(ob, p);
		if (ret < 0)
			return ret;
		for (int t = 0; t < ob->nsel; t++) {
			int s = ob->sel[t];
			const float *v =
				glint_image_px(ob->img, ob->d->xy[2 * s],
					       ob->d->xy[2 * s + 1]);
			for (int c = 0; c < 3; c++)
				res[3 * t + c] = ob->d->sw[3 * s + c] *
						 (v[c] - ob->d->y[3 * s + c]);
		}
		return 0;
	}
	const double *lobes = memo_lobes(ob, p);
	if (ob->varpro) {
		for (int c = 0; c < 3; c++)
			solve_albedos(ob, p, lobes, c);
		memcpy(ob->p, p, sizeof(p)); /* keep the albedos found */
	}
	for (int t = 0; t < ob->nsel; t++) {
		int s = ob->sel[t];
		for (int c = 0; c < 3; c++)
			res[3 * t + c] = ob->d->sw[3 * s + c] *
					 (fit_pixel_value(ob, p, lobes, t, c) -
					  ob->d->y[3 * s + c]);
	}
	return 0;
}

/*
 * Forward-difference step for the nonlinear parameters, relative.  The
 * objective is a Monte Carlo estimate on fixed samples: smooth, but with a
 * fine-scale ripple (lobe samples move with the roughness); 1e-4 steps
 * pick the ripple up and stalled LM in flat valleys (silver under Venice
 * ended 8 % above the truth's cost), 1e-2 steps see the trend.
 */
#define FD_REL_STEP 1e-2

/* Analytic columns for albedos and the factor parameter (an ior: its
 * derivative shaded with the lobes, memo_lobes()), forward differences
 * for the rest. */
int fit_obj_jacobian(void *ctx, const double *q, const double *r, double *jac)
{
	struct objective *ob = ctx;
	int nf = ob->nfree, nj = ob->m->bxdf->nlobes;
	double p[GLINT_MAX_PARAMS];

	(void)r;
	memcpy(p, ob->p, sizeof(p));
	for (int k = 0; k < nf; k++)
		p[ob->free_idx[k]] = q[k];
	const double *lobes = memo_lobes(ob, p);
	for (int k = 0; k < nf; k++) {
		int pk = ob->free_idx[k];
		if (ob->lobe_of[pk] >= 0) {
			int j = ob->lobe_of[pk], c = ob->chan_of[pk];
			for (int t = 0; t < ob->nsel; t++) {
				int s = ob->sel[t];
				for (int cc = 0; cc < 3; cc++)
					jac[(size_t)(3 * t + cc) * nf + k] =
						cc != c ? 0
							: ob->d->sw[3 * s + c] *
								  lobes[((size_t)t *
										 nj +
									 j) * 3 +
									c];
			}
			continue;
		}
		if (ob->memo_d && pk == ob->m->lobes->factor_param) {
			for (int t = 0; t < ob->nsel; t++) {
				int s = ob->sel[t];
				for (int c = 0; c < 3; c++)
					jac[(size_t)(3 * t + c) * nf + k] =
						ob->d->sw[3 * s + c] *
						fit_pixel_value(ob, p,
								ob->dlobes, t,
								c);
			}
			continue;
		}
		const struct glint_param *pi = &ob->m->params[pk];
		double h = FD_REL_STEP * fmax(fabs(p[pk]), 1e-2);
		if (p[pk] + h > pi->hi)
			h = -h;
		double pp[GLINT_MAX_PARAMS];
		memcpy(pp, p, sizeof(pp));
		pp[pk] += h;
		lobes_at(ob, pp, ob->lobes2);
		ob->evals++;
		for (int t = 0; t < ob->nsel; t++) {
			int s = ob->sel[t];
			for (int c = 0; c < 3; c++)
				jac[(size_t)(3 * t + c) * nf + k] =
					ob->d->sw[3 * s + c] *
					(fit_pixel_value(ob, p, ob->lobes2, t,
							 c) -
					 fit_pixel_value(ob, p, lobes, t, c)) /
					h;
		}
	}
	return 0;
}

void fit_objective_free(struct objective *ob)
{
	for (int k = 1; k < ob->nsets; k++)
		glint_shade_cache_free(ob->sets[k]);
	glint_shade_cache_free(ob->cache);
	for (int v = 0; v < ob->nviews; v++)
		glint_shade_light_free(ob->views[v].light);
	free(ob->final_r);
	glint_image_free(ob->img);
	free(ob->lobes);
	free(ob->lobes2);
	free(ob->dlobes);
	free(ob->set_jac);
	for (int k = 0; k < MAX_SETS; k++) {
		free(ob->set_lobes[k]);
		free(ob->set_dlobes[k]);
	}
}

/* A shade cache over every fitted pixel at the objective's sample counts
 * (one per photo, joined); seed 0 is glint's fixed set, others
 * independent ones. */
int fit_new_cache(const struct objective *ob, uint32_t seed,
		  struct glint_shade_cache **out)
{
	const struct glint_fit_opts *o = ob->o;
	struct glint_shade_cache_opts co = {
		.light_samples = o->light_samples * ob->sample_scale,
		.lobe_samples = o->lobe_samples * ob->sample_scale,
		.static_samples = o->static_samples,
		.no_footprint = o->no_footprint,
		.seed = seed,
		.nthreads = o->nthreads,
	};
	struct glint_fit_view in[GLINT_FIT_MAX_VIEWS];
	struct fit_data_part parts[GLINT_FIT_MAX_VIEWS];
	struct glint_shade_light *lights[GLINT_FIT_MAX_VIEWS];

	for (int v = 0; v < ob->nviews; v++) {
		const struct view *vw = &ob->views[v];
		in[v] = (struct glint_fit_view){ .r = vw->r };
		parts[v] = (struct fit_data_part){ .off = vw->off, .n = vw->n };
		lights[v] = vw->light;
	}
	return fit_data_cache_new(in, ob->nviews, ob->d, parts, ob->m, &co,
				  lights, out);
}

/* The objective over d at the start values: lobe buffers and the shade
 * cache (or the faithful path's image). */
int fit_objective_init(struct objective *ob, const struct view *views,
		       int nviews, const struct glint_model *model,
		       const struct fit_data *d, const struct glint_fit_opts *o)
{
	memset(ob, 0, sizeof(*ob));
	memcpy(ob->views, views, (size_t)nviews * sizeof(*views));
	ob->nviews = nviews;
	ob->r = views[0].r;
	ob->m = model;
	ob->d = d;
	ob->o = o;
	ob->sample_scale = 1;
	for (int k = 0; k < model->nparams; k++) {
		ob->p[k] = o->start ? o->start[k] : model->params[k].def;
		ob->lobe_of[k] = ob->chan_of[k] = -1;
	}
	for (int j = 0; j < model->bxdf->nlobes; j++)
		for (int c = 0; c < 3; c++) {
			ob->lobe_of[model->lobes->param[j] + c] = j;
			ob->chan_of[model->lobes->param[j] + c] = c;
		}
	size_t nl = (size_t)d->n * model->bxdf->nlobes * 3;
	ob->lobes = malloc(nl * sizeof(double));
	ob->lobes2 = malloc(nl * sizeof(double));
	ob->dlobes = malloc(nl * sizeof(double));
	if (!ob->lobes || !ob->lobes2 || !ob->dlobes)
		return glint_error_set(ENOMEM, "out of memory");
	if (o->faithful) {
		ob->img = glint_image_new(ob->r->gb.width, ob->r->gb.height);
		return ob->img ? 0 : glint_error_set(ENOMEM, "out of memory");
	}
	struct glint_shade_cache_opts co = { .nthreads = o->nthreads };
	int ret = 0;
	for (int v = 0; v < nviews && ret == 0; v++)
		ret = glint_shade_light_new(views[v].r->env, &co,
					    &ob->views[v].light);
	return ret < 0 ? ret : fit_new_cache(ob, 0, &ob->cache);
}

/* The Jacobian of the residuals by forward differences of obj_residuals
 * (the faithful path, which has no cache to difference). */
int fit_jacobian_fd(struct objective *ob, const double *q, const double *r,
		    double *jac)
{
	int nf = ob->nfree, m = 3 * ob->nsel, ret = 0;
	double *r2 = malloc((size_t)m * sizeof(double));
	double qq[GLINT_MAX_PARAMS];

	if (!r2)
		return glint_error_set(ENOMEM, "out of memory");
	for (int k = 0; k < nf && !ret; k++) {
		const struct glint_param *pi = &ob->m->params[ob->free_idx[k]];
		double h = FD_REL_STEP * fmax(fabs(q[k]), 1e-2);
		if (q[k] + h > pi->hi)
			h = -h;
		memcpy(qq, q, sizeof(double) * (size_t)nf);
		qq[k] += h;
		ret = fit_obj_residuals(ob, qq, r2);
		for (int i = 0; i < m && !ret; i++)
			jac[(size_t)i * nf + k] = (r2[i] - r[i]) / h;
	}
	free(r2);
	return ret;
}
