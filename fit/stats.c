/* SPDX-License-Identifier: MIT */
/*
 * The fit's statistics: baselines (backdrop, flat disc), the mean lobes, the
 * cost and RMSE of the result.
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

int fit_cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Median of v[0..n) (reorders v). */
double fit_median_of(double *v, int n)
{
	qsort(v, (size_t)n, sizeof(double), fit_cmp_double);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/*
 * Relative RMSE of the photo against the bare backdrop: the env map seen
 * along the same primary rays, as if there were no sphere.  A photo that
 * matches the backdrop better than any fitted sphere does not show the
 * sphere where the scene says.
 */
static double backdrop_error(const struct glint_gbuffer *gb,
			     const struct glint_envmap *env,
			     const struct fit_data *d, double sums[3])
{
	double se = 0, sy = 0;
	int n = 0;

	for (int i = 0; i < d->n; i++) {
		double bg[3] = { 0, 0, 0 }, l[3];
		for (int s = 0; s < gb->spp; s++) {
			const float *dir =
				glint_gbuffer_pixel(gb, (size_t)d->pix[i])[s].d;
			glint_envmap_lookup(env, v3(dir[0], dir[1], dir[2]), l);
			for (int c = 0; c < 3; c++)
				bg[c] += l[c] / gb->spp;
		}
		for (int c = 0; c < 3; c++) {
			if (d->sw[3 * i + c] <= 0)
				continue;
			double e = bg[c] - d->y[3 * i + c];
			se += e * e;
			sy += d->y[3 * i + c];
			n++;
		}
	}
	sums[0] += se;
	sums[1] += sy;
	sums[2] += n;
	return n && sy > 0 ? sqrt(se / n) / (sy / n) : INFINITY;
}

/* Photo v's pixels of the joint data d (borrowed: not to be freed). */
static struct fit_data view_data(const struct fit_data *d, const struct view *v)
{
	struct fit_data sub = *d;

	sub.n = v->n;
	sub.pix += v->off;
	sub.xy += 2 * (size_t)v->off;
	sub.y += 3 * (size_t)v->off;
	sub.sw += 3 * (size_t)v->off;
	sub.va += 3 * (size_t)v->off;
	sub.vb += 3 * (size_t)v->off;
	sub.stride = v->stride;
	sub.frame_x = v->frame_x;
	sub.frame_y = v->frame_y;
	return sub;
}

/* The baselines a fit is judged against (glint_fit_judge()), per photo
 * and over all. */
void fit_baselines(const struct objective *ob, const struct fit_data *d,
		   struct glint_fit_result *res)
{
	double sums[3] = { 0, 0, 0 };

	for (int v = 0; v < ob->nviews; v++) {
		const struct view *vw = &ob->views[v];
		struct glint_fit_view_stats *st = &res->view[v];
		struct fit_data sub = view_data(d, vw);
		st->backdrop_rel_rmse =
			backdrop_error(&vw->r->gb, vw->r->env, &sub, sums);
		fit_data_baselines(&sub, &st->flat_rel_rmse, &st->noise_rmse);
	}
	res->backdrop_rel_rmse =
		sums[2] && sums[1] > 0
			? sqrt(sums[0] / sums[2]) / (sums[1] / sums[2])
			: INFINITY;
	fit_data_baselines(d, &res->flat_rel_rmse, &res->noise_rmse);
}

/* Lobes at ob->p on sel: the mean over the sample sets when there are
 * several (a pixel is linear in its lobes), else the cache's. */
static void mean_lobes(struct objective *ob, const int *sel, int nsel,
		       double *lobes)
{
	size_t sz = (size_t)nsel * ob->m->bxdf->nlobes * 3;
	double *tmp = ob->nsets > 1 ? malloc(sz * sizeof(double)) : NULL;

	glint_shade_cache_lobes_sel(ob->cache, ob->p, sel, nsel, lobes);
	if (!tmp)
		return;
	for (int k = 1; k < ob->nsets; k++) {
		glint_shade_cache_lobes_sel(ob->sets[k], ob->p, sel, nsel, tmp);
		for (size_t i = 0; i < sz; i++)
			lobes[i] += tmp[i];
	}
	for (size_t i = 0; i < sz; i++)
		lobes[i] /= ob->nsets;
	free(tmp);
}

void fit_finish_stats(struct objective *ob, const int *sel, int nsel,
		      struct glint_fit_result *res)
{
	double se = 0, sy = 0, wcost = 0;
	double vse[GLINT_FIT_MAX_VIEWS] = { 0 },
	       vsy[GLINT_FIT_MAX_VIEWS] = { 0 },
	       vw[GLINT_FIT_MAX_VIEWS] = { 0 };
	int n = 0, vn[GLINT_FIT_MAX_VIEWS] = { 0 },
	    vp[GLINT_FIT_MAX_VIEWS] = { 0 };
	/* The uncertainty stage's residuals are these pixels' at ob->p. */
	const double *fr =
		ob->final_r && ob->final_rows == 3 * nsel ? ob->final_r : NULL;
	double *lobes = ob->cache && !fr
				? malloc((size_t)nsel * ob->m->bxdf->nlobes *
					 3 * sizeof(double))
				: NULL;

	if (ob->cache && lobes)
		mean_lobes(ob, sel, nsel, lobes);
	else if (!ob->cache)
		fit_render_full(ob, ob->p);
	for (int t = 0; t < nsel; t++) {
		int s = sel[t], view = fit_view_of(ob, s);
		vp[view]++;
		for (int c = 0; c < 3; c++) {
			if (ob->d->sw[3 * s + c] <= 0)
				continue;
			double v;
			if (fr)
				v = ob->d->y[3 * s + c] +
				    fr[3 * t + c] / ob->d->sw[3 * s + c];
			else if (lobes)
				v = fit_pixel_value(ob, ob->p, lobes, t, c);
			else
				v = glint_image_px(ob->img, ob->d->xy[2 * s],
						   ob->d->xy[2 * s + 1])[c];
			double e = v - ob->d->y[3 * s + c];
			double we = ob->d->sw[3 * s + c] * e;
			vw[view] += 0.5 * we * we;
			vse[view] += e * e;
			vsy[view] += ob->d->y[3 * s + c];
			vn[view]++;
		}
	}
	free(lobes);
	res->nviews = ob->nviews;
	for (int v = 0; v < ob->nviews; v++) {
		struct glint_fit_view_stats *st = &res->view[v];
		st->pixels = vp[v];
		st->interior = ob->views[v].interior;
		st->wcost = vw[v];
		st->rmse = vn[v] ? sqrt(vse[v] / vn[v]) : NAN;
		st->rel_rmse =
			vn[v] && vsy[v] > 0 ? st->rmse / (vsy[v] / vn[v]) : NAN;
		wcost += vw[v];
		se += vse[v];
		sy += vsy[v];
		n += vn[v];
	}
	res->rmse = n ? sqrt(se / n) : NAN;
	res->wcost = wcost;
	res->rel_rmse = n && sy > 0 ? res->rmse / (sy / n) : NAN;
	res->pixels = nsel;
}
