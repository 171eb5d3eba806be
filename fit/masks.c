/* SPDX-License-Identifier: MIT */
/*
 * Pixel selections: the white render, the specular mask, the three-pass
 * method's selections.
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

void fit_selections_free(struct selections *s)
{
	free(s->all);
	free(s->coarse);
	free(s->spec);
	free(s->diff);
}

/* The white render at every fitted pixel: the constant lobes at albedo 1
 * (the faithful path renders a white Lambertian sphere in full). */
static int white_render(struct objective *ob, const int *all, double *white)
{
	const struct fit_data *d = ob->d;
	const struct glint_model *model = ob->m;

	if (!ob->cache) {
		double white_p[GLINT_MAX_PARAMS] = { 1, 1, 1 };
		struct objective wob = *ob;
		wob.m = &glint_model_lambert;
		int ret = fit_render_full(&wob, white_p);
		for (int s = 0; s < d->n && !ret; s++)
			for (int c = 0; c < 3; c++)
				white[3 * s + c] =
					glint_image_px(ob->img, d->xy[2 * s],
						       d->xy[2 * s + 1])[c];
		return ret;
	}
	int nj = model->bxdf->nlobes;
	double *wl = malloc((size_t)d->n * nj * 3 * sizeof(double));
	if (!wl)
		return glint_error_set(ENOMEM, "out of memory");
	glint_shade_cache_constant_lobes_sel(ob->cache, all, d->n, wl);
	for (int s = 0; s < d->n; s++)
		for (int c = 0; c < 3; c++) {
			double w = 0;
			for (int j = 0; j < nj; j++)
				if (!model->lobes->varies[j])
					w += wl[((size_t)s * nj + j) * 3 + c];
			white[3 * s + c] = w;
		}
	free(wl);
	return 0;
}

/*
 * The specular mask.  The paper marks pixels where the photo exceeds the
 * white render by more than a threshold; but a dark glossy material's
 * highlights never outshine a white sphere (satin paint: 0.27 against
 * 1.5), which leaves the mask empty and pass 1 fitting diffuse albedo on
 * highlights.  A Lambertian surface of unknown albedo a shows photo = a x
 * white everywhere, so glint marks the pixels whose ratio photo / white
 * exceeds the median ratio by more than the threshold; the paper's rule is
 * the case a = 1.
 */
static int specular_mask(struct objective *ob, const int *all,
			 unsigned char *is_spec)
{
	const struct fit_data *d = ob->d;
	double *white = malloc((size_t)d->n * 3 * sizeof(double));
	double *ratio = malloc((size_t)d->n * sizeof(double));
	double *tmp = malloc((size_t)d->n * sizeof(double));
	int ret = white && ratio && tmp
			  ? 0
			  : glint_error_set(ENOMEM, "out of memory");

	if (!ret)
		ret = white_render(ob, all, white);
	for (int s = 0; s < d->n && !ret; s++) {
		double pw = rgb_luminance(d->y[3 * s], d->y[3 * s + 1],
					  d->y[3 * s + 2]);
		double ww = rgb_luminance(white[3 * s], white[3 * s + 1],
					  white[3 * s + 2]);
		ratio[s] = ww > 0 ? pw / ww : 0;
	}
	/* Each photo's median: their lights differ. */
	for (int v = 0; v < ob->nviews && !ret; v++) {
		const struct view *vw = &ob->views[v];
		memcpy(tmp, ratio + vw->off, (size_t)vw->n * sizeof(double));
		double med = fit_median_of(tmp, vw->n);
		for (int s = vw->off; s < vw->off + vw->n; s++)
			is_spec[s] =
				ratio[s] > (1 + ob->o->mask_threshold) * med;
	}
	free(white);
	free(ratio);
	free(tmp);
	return ret;
}

/*
 * The selections.  The masks are computed on every fitted pixel; the
 * coarse set is every 4th row and column plus every specular pixel: a
 * grid alone can miss a small glint, and the glint is what pins roughness
 * down (without it the coarse passes drift to any lobe).  The diffuse set
 * is the coarse set's non-specular pixels.
 */
int fit_make_selections(struct objective *ob, struct selections *sl)
{
	const struct fit_data *d = ob->d;
	size_t sz = (size_t)(d->n > 0 ? d->n : 1) * sizeof(int);
	unsigned char *is_spec = NULL;
	int ret = 0;

	memset(sl, 0, sizeof(*sl));
	sl->all = malloc(sz);
	sl->coarse = malloc(sz);
	sl->spec = malloc(sz);
	sl->diff = malloc(sz);
	is_spec = calloc((size_t)d->n + 1, 1);
	if (!sl->all || !sl->coarse || !sl->spec || !sl->diff || !is_spec) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	sl->nall = d->n;
	for (int i = 0; i < d->n; i++)
		sl->all[i] = i;
	ret = specular_mask(ob, sl->all, is_spec);
	if (ret < 0)
		goto out;
	for (int s = 0; s < d->n; s++) {
		const struct view *vw = &ob->views[fit_view_of(ob, s)];
		int on_grid = fit_data_coarse_pick(
			vw->r->gb.cfa, d->xy[2 * s] + vw->frame_x,
			d->xy[2 * s + 1] + vw->frame_y, vw->stride);
		if (is_spec[s])
			sl->spec[sl->nspec++] = s;
		if (on_grid || is_spec[s])
			sl->coarse[sl->ncoarse++] = s;
	}
	if (!ob->o->coarse_to_fine || sl->ncoarse < 64 ||
	    sl->ncoarse > sl->nall / 2) {
		memcpy(sl->coarse, sl->all, (size_t)sl->nall * sizeof(int));
		sl->ncoarse = sl->nall;
	}
	for (int t = 0; t < sl->ncoarse; t++)
		if (!is_spec[sl->coarse[t]])
			sl->diff[sl->ndiff++] = sl->coarse[t];
out:
	free(is_spec);
	return ret;
}

/* Every pixel and every parameter, no variable projection. */
void fit_select_all(struct objective *ob, const struct selections *sl)
{
	ob->sel = sl->all;
	ob->nsel = sl->nall;
	ob->varpro = 0;
	ob->nfree = ob->m->nparams;
	for (int k = 0; k < ob->m->nparams; k++)
		ob->free_idx[k] = k;
}
