/* SPDX-License-Identifier: MIT */
#include "fit_data.h"

#include "core/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int covered(const struct glint_gbuffer *gb, int x, int y)
{
	if (x < 0 || y < 0 || x >= gb->width || y >= gb->height)
		return 0;
	return gb->cover[(size_t)y * gb->width + x] == gb->spp;
}

int fit_data_interior(const struct glint_gbuffer *gb, int x, int y)
{
	for (int dy = -1; dy <= 1; dy++)
		for (int dx = -1; dx <= 1; dx++)
			if (!covered(gb, x + dx, y + dy))
				return 0;
	return 1;
}

/*
 * Is frame pixel (X, Y) on the fine grid of stride s?  Every s-th row and
 * column; on a demosaiced photo (cfa) at an even stride that would be one
 * colour's sites only, every one of them fitted in the other two colours
 * as the demosaic interpolated them, so there each s x s block gives the
 * pixel at its corner's offset (p & 1, p >> 1), p = (bx + 2 by) mod 4 of
 * the block (bx, by): the four sites of the mosaic take turns, every
 * fourth block along a row or two rows down.
 */
int fit_data_fine_pick(const signed char cfa[4], int X, int Y, int s)
{
	if (cfa[0] < 0 || s % 2)
		return X % s == 0 && Y % s == 0;
	int p = (X / s + 2 * (Y / s)) & 3;
	return X % s == (p & 1) && Y % s == (p >> 1);
}

/* Is fine pixel (X, Y) (fit_data_fine_pick()) on the coarse grid, every
 * 4th of the fine grid's rows and columns?  On a demosaiced photo the
 * 4 x 4 blocks of fine blocks take turns at their blocks (p & 1, p >> 1),
 * p = (BX + 2 BY) mod 4, which puts every kind of site on the coarse
 * grid too. */
int fit_data_coarse_pick(const signed char cfa[4], int X, int Y, int s)
{
	if (cfa[0] < 0)
		return X % (4 * s) == 0 && Y % (4 * s) == 0;
	int bx = X / s, by = Y / s, p = (bx / 4 + 2 * (by / 4)) & 3;
	return bx % 4 == (p & 1) && by % 4 == (p >> 1);
}

/*
 * Pixels wholly on the sphere, every `stride`-th row and column
 * (fit_data_fine_pick()).  On a demosaiced photo each pixel is fitted in
 * the colour its site measured, the other two having weight 0: the
 * demosaic's interpolation, which no blur of the render reproduces (a
 * highlight a few pixels wide comes out in the wrong colour), is left out
 * of the fit.  A pixel
 * whose primary samples all hit can still be partly background between
 * them, which mixes the backdrop into the photo's value: only pixels whose
 * whole 3x3 neighbourhood is covered are used (fit_data_interior()).
 */
static int collect_pixels(const struct glint_gbuffer *gb, int stride,
			  const struct glint_image *photo,
			  const struct glint_image *weight, struct fit_data *d,
			  int *interior)
{
	int n = 0, cap = (gb->width / stride + 1) * (gb->height / stride + 1);

	*interior = 0;
	d->pix = malloc((size_t)cap * sizeof(*d->pix));
	d->xy = malloc((size_t)cap * 2 * sizeof(int));
	d->y = malloc((size_t)cap * 3 * sizeof(double));
	d->sw = malloc((size_t)cap * 3 * sizeof(double));
	d->va = malloc((size_t)cap * 3 * sizeof(double));
	d->vb = malloc((size_t)cap * 3 * sizeof(double));
	if (!d->pix || !d->xy || !d->y || !d->sw || !d->va || !d->vb)
		return glint_error_set(ENOMEM, "out of memory");
	for (int y = 0; y < gb->height; y++)
		for (int x = 0; x < gb->width; x++) {
			size_t i = (size_t)y * gb->width + x;
			if (!fit_data_interior(gb, x, y))
				continue;
			(*interior)++;
			int X = x + gb->frame_x, Y = y + gb->frame_y;
			if (!fit_data_fine_pick(gb->cfa, X, Y, stride))
				continue;
			int site = gb->cfa[(X & 1) + 2 * (Y & 1)];
			const float *v = glint_image_px(photo, x, y);
			const float *w =
				weight ? glint_image_px(weight, x, y) : NULL;
			d->pix[n] = (int32_t)i;
			d->xy[2 * n] = x;
			d->xy[2 * n + 1] = y;
			for (int c = 0; c < 3; c++) {
				double wc = w ? w[c] : 1;
				int ok = isfinite(v[c]) && isfinite(wc) &&
					 wc > 0 && (site < 0 || c == site);
				d->y[3 * n + c] = ok ? v[c] : 0;
				d->sw[3 * n + c] = ok ? sqrt(wc) : 0;
			}
			n++;
		}
	d->n = n;
	return 0;
}

void free_data(struct fit_data *d)
{
	free(d->pix);
	free(d->xy);
	free(d->y);
	free(d->sw);
	free(d->va);
	free(d->vb);
}

/*
 * The noise model of a weight image: per channel, the variance 1 / w
 * regressed on the value as a + b v (shot plus read noise); each value
 * keeps its own variance, scaled along that line: va + vb v with
 * va = var a / (a + b y), vb = var b / (a + b y).  A channel whose line
 * is not a noise model (b <= 0 or a < 0) keeps its weights as given.
 */
static void weight_noise_model(struct fit_data *d)
{
	for (int c = 0; c < 3; c++) {
		double s1 = 0, sy = 0, sv = 0, syy = 0, syv = 0;
		for (int i = c; i < 3 * d->n; i += 3) {
			if (!(d->sw[i] > 0))
				continue;
			double v = 1 / (d->sw[i] * d->sw[i]), y = d->y[i];
			s1++;
			sy += y;
			sv += v;
			syy += y * y;
			syv += y * v;
		}
		double det = s1 * syy - sy * sy;
		double b = det > 0 ? (s1 * syv - sy * sv) / det : 0;
		double a = s1 > 0 ? (sv - b * sy) / s1 : 0;
		int model = b > 0 && a >= 0;
		for (int i = c; i < 3 * d->n; i += 3) {
			double v = d->sw[i] > 0 ? 1 / (d->sw[i] * d->sw[i]) : 0;
			double at = a + b * fmax(0, d->y[i]);
			if (model && at > 0) {
				d->va[i] = v * a / at;
				d->vb[i] = v * b / at;
			} else {
				d->va[i] = v;
				d->vb[i] = 0;
			}
		}
	}
}

void fit_data_reweight(struct fit_data *d, const double *pred)
{
	for (int i = 0; i < 3 * d->n; i++) {
		if (!(d->sw[i] > 0))
			continue;
		double v = fit_data_variance(d, i, pred[i]);
		if (v > 0)
			d->sw[i] = 1 / sqrt(v);
	}
}

/* Check the photo carries a signal where the sphere should be. */
static int check_photo(const struct fit_data *d)
{
	double mx = 0;
	int usable = 0;

	for (int i = 0; i < 3 * d->n; i++) {
		if (d->sw[i] > 0) {
			usable++;
			mx = fmax(mx, d->y[i]);
		}
	}
	if (!usable)
		return glint_error_set(EINVAL,
				       "the photo has no usable pixel on the "
				       "sphere (all saturated, invalid or "
				       "zero-weight): nothing to fit");
	if (!(mx > 0))
		return glint_error_set(EINVAL,
				       "the photo is black where the scene "
				       "puts the sphere (%d pixels, maximum "
				       "%g): nothing to fit",
				       d->n, mx);
	if (usable < d->n * 3 / 10)
		return glint_error_set(EINVAL,
				       "only %d of %d values on the sphere are "
				       "usable (the rest saturated or "
				       "invalid): expected at least 30 %%",
				       usable, 3 * d->n);
	return 0;
}

/* Every s-th row and column, keeping at least about max_pixels. */
static int stride_for(int interior, int max_pixels)
{
	int s = (int)floor(sqrt((double)interior / max_pixels));
	return s < 1 ? 1 : s;
}

int fit_data_prepare(struct glint_gbuffer *gb, const struct glint_image *photo,
		     const struct glint_image *weight,
		     const struct glint_fit_opts *o, struct fit_data *d,
		     int *interior)
{
	int ret;

	if (photo->width != gb->width || photo->height != gb->height)
		return glint_error_set(EINVAL,
				       "photo is %dx%d: expected the scene "
				       "camera's %dx%d",
				       photo->width, photo->height, gb->width,
				       gb->height);
	if (weight &&
	    (weight->width != gb->width || weight->height != gb->height))
		return glint_error_set(
			EINVAL, "weight image is %dx%d: expected %dx%d",
			weight->width, weight->height, gb->width, gb->height);
	/* The fine pixel set: every stride-th interior pixel. */
	int count;

	*interior = 0;
	memset(d, 0, sizeof(*d));
	ret = collect_pixels(gb, 1, photo, NULL, d, interior);
	free_data(d);
	if (ret < 0)
		return ret;
	if (*interior < 16)
		return glint_error_set(EINVAL,
				       "only %d pixels lie wholly on the "
				       "sphere: expected at least 16 (is the "
				       "sphere in view?)",
				       *interior);
	int stride = stride_for(*interior, o->max_pixels);
	memset(d, 0, sizeof(*d));
	ret = collect_pixels(gb, stride, photo, weight, d, &count);
	if (ret < 0)
		return ret;
	d->stride = stride;
	d->frame_x = gb->frame_x;
	d->frame_y = gb->frame_y;
	ret = glint_gbuffer_keep(gb, d->pix, d->n, o->nthreads);
	if (ret < 0)
		return ret;
	ret = check_photo(d);
	if (ret < 0)
		return ret;
	if (weight) {
		weight_noise_model(d);
		d->noise_model = 1;
	} else if (o->weighting == GLINT_WEIGHT_POISSON) {
		double mean = 0;
		int nv = 0;
		for (int i = 0; i < 3 * d->n; i++)
			if (d->sw[i] > 0) {
				mean += fmax(0, d->y[i]);
				nv++;
			}
		mean /= nv;
		for (int i = 0; i < 3 * d->n; i++) {
			d->va[i] = 0.1 * mean;
			d->vb[i] = 1;
		}
		fit_data_reweight(d, d->y);
		d->shape_only = 1;
	} else {
		for (int i = 0; i < 3 * d->n; i++) {
			d->va[i] = 1;
			d->vb[i] = 0;
		}
	}
	return 0;
}

int fit_data_join(const struct fit_data *parts, int nparts, struct fit_data *d)
{
	size_t n = 0;

	memset(d, 0, sizeof(*d));
	for (int k = 0; k < nparts; k++)
		n += (size_t)parts[k].n;
	d->pix = malloc(n * sizeof(*d->pix));
	d->xy = malloc(n * 2 * sizeof(int));
	d->y = malloc(n * 3 * sizeof(double));
	d->sw = malloc(n * 3 * sizeof(double));
	d->va = malloc(n * 3 * sizeof(double));
	d->vb = malloc(n * 3 * sizeof(double));
	if (!d->pix || !d->xy || !d->y || !d->sw || !d->va || !d->vb ||
	    n > INT32_MAX / 3) {
		free_data(d);
		return glint_error_set(ENOMEM, "out of memory");
	}
	d->noise_model = 1;
	d->shape_only = 1;
	for (int k = 0; k < nparts; k++) {
		const struct fit_data *q = &parts[k];
		size_t o = (size_t)d->n, m = (size_t)q->n;
		memcpy(d->pix + o, q->pix, m * sizeof(*d->pix));
		memcpy(d->xy + 2 * o, q->xy, m * 2 * sizeof(int));
		memcpy(d->y + 3 * o, q->y, m * 3 * sizeof(double));
		memcpy(d->sw + 3 * o, q->sw, m * 3 * sizeof(double));
		memcpy(d->va + 3 * o, q->va, m * 3 * sizeof(double));
		memcpy(d->vb + 3 * o, q->vb, m * 3 * sizeof(double));
		d->n += q->n;
		d->noise_model &= q->noise_model;
		d->shape_only &= q->shape_only;
	}
	d->stride = parts[0].stride;
	d->frame_x = parts[0].frame_x;
	d->frame_y = parts[0].frame_y;
	return 0;
}

/*
 * What the photo alone says about a fit's residual, over the same values
 * as the backdrop check (fit.c): the relative RMSE of a flat disc of the
 * photo's mean colour (a sphere's shading and reflections explain much of that
 * spread; a photo of something else leaves it), and the RMSE noise alone
 * would leave when the weights come from a real noise model (NAN else).
 */
void fit_data_baselines(const struct fit_data *d, double *flat_rel,
			double *noise_rmse)
{
	double sum[3] = { 0, 0, 0 }, se = 0, sv = 0, sy = 0;
	int cnt[3] = { 0, 0, 0 }, n = 0;

	for (int i = 0; i < d->n; i++)
		for (int c = 0; c < 3; c++)
			if (d->sw[3 * i + c] > 0) {
				sum[c] += d->y[3 * i + c];
				cnt[c]++;
			}
	for (int i = 0; i < d->n; i++)
		for (int c = 0; c < 3; c++) {
			double sw = d->sw[3 * i + c];
			if (!(sw > 0))
				continue;
			double e = d->y[3 * i + c] - sum[c] / cnt[c];
			se += e * e;
			sv += 1 / (sw * sw);
			sy += d->y[3 * i + c];
			n++;
		}
	*flat_rel = n && sy > 0 ? sqrt(se / n) / (sy / n) : INFINITY;
	*noise_rmse = n && d->noise_model ? sqrt(sv / n) : NAN;
}

int fit_data_prepare_views(const struct glint_fit_view *in, int nviews,
			   const struct glint_fit_opts *o, struct fit_data *d,
			   struct fit_data_part *parts)
{
	struct fit_data one[GLINT_FIT_MAX_VIEWS];
	int ret = 0, off = 0, v;

	memset(one, 0, sizeof(one));
	for (v = 0; v < nviews && ret == 0; v++) {
		struct fit_data_part *pt = &parts[v];
		memset(pt, 0, sizeof(*pt));
		ret = fit_data_prepare(&in[v].r->gb, in[v].photo, in[v].weight,
				       o, &one[v], &pt->interior);
		if (ret < 0 && nviews > 1)
			ret = glint_error_prefix(-ret, "photo %d of %d", v + 1,
						 nviews);
		pt->off = off;
		pt->n = one[v].n;
		pt->stride = one[v].stride;
		pt->frame_x = one[v].frame_x;
		pt->frame_y = one[v].frame_y;
		off += one[v].n;
	}
	if (ret == 0 && nviews == 1) {
		*d = one[0];
		return 0;
	}
	if (ret == 0)
		ret = fit_data_join(one, nviews, d);
	for (int k = 0; k < nviews; k++)
		free_data(&one[k]);
	return ret;
}

int fit_data_cache_new(const struct glint_fit_view *in, int nviews,
		       const struct fit_data *d,
		       const struct fit_data_part *parts,
		       const struct glint_model *m,
		       const struct glint_shade_cache_opts *co,
		       struct glint_shade_light *const *lights,
		       struct glint_shade_cache **out)
{
	struct glint_shade_cache *one[GLINT_FIT_MAX_VIEWS];
	struct glint_shade_cache_opts c = *co;
	int ret = 0, v;

	for (v = 0; v < nviews && ret == 0; v++) {
		c.light = lights ? lights[v] : NULL;
		/* The pixel footprint is an affine model of the normal and
		 * ray over the pixel: through a lens of finite aperture a
		 * pixel's hits also spread over the circle of confusion,
		 * which it does not model (copper through f/4 at 512 px:
		 * roughness 0.094 for 0.005 with it, 0.0041 without). */
		c.no_footprint = co->no_footprint ||
				 in[v].r->scene.cam.aperture_radius > 0;
		ret = glint_shade_cache_new(&in[v].r->gb, d->pix + parts[v].off,
					    parts[v].n, in[v].r->env, m, &c,
					    &one[v]);
	}
	if (ret < 0) {
		for (int k = 0; k < v - 1; k++)
			glint_shade_cache_free(one[k]);
		return ret;
	}
	if (nviews == 1) {
		*out = one[0];
		return 0;
	}
	return glint_shade_cache_join(one, nviews, out);
}
