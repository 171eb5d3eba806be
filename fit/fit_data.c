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
	size_t i = (size_t)y * gb->width + x;
	for (int s = 0; s < gb->spp; s++)
		if (gb->hits[i * gb->spp + s].geom < 0)
			return 0;
	return 1;
}

/*
 * Pixels wholly on the sphere, every `stride`-th row and column.  A pixel
 * whose primary samples all hit can still be partly background between
 * them, which mixes the backdrop into the photo's value: only pixels whose
 * whole 3x3 neighbourhood is covered are used.
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
	if (!d->pix || !d->xy || !d->y || !d->sw)
		return glint_error_set(ENOMEM, "out of memory");
	for (int y = 0; y < gb->height; y++)
		for (int x = 0; x < gb->width; x++) {
			size_t i = (size_t)y * gb->width + x;
			int on = 1;
			for (int dy = -1; dy <= 1 && on; dy++)
				for (int dx = -1; dx <= 1 && on; dx++)
					on = covered(gb, x + dx, y + dy);
			if (!on)
				continue;
			(*interior)++;
			if (x % stride || y % stride)
				continue;
			const float *v = glint_image_px(photo, x, y);
			const float *w =
				weight ? glint_image_px(weight, x, y) : NULL;
			d->pix[n] = (int32_t)i;
			d->xy[2 * n] = x;
			d->xy[2 * n + 1] = y;
			for (int c = 0; c < 3; c++) {
				double wc = w ? w[c] : 1;
				int ok = isfinite(v[c]) && isfinite(wc) &&
					 wc > 0;
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
}

/* Check the photo carries a signal where the sphere should be. */
static int check_photo(const struct fit_data *d)
{
	double sum = 0, mx = 0;
	int usable = 0;

	for (int i = 0; i < 3 * d->n; i++) {
		if (d->sw[i] > 0) {
			usable++;
			sum += d->y[i];
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

int fit_data_prepare(const struct glint_gbuffer *gb,
		     const struct glint_image *photo,
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
	ret = check_photo(d);
	if (ret < 0)
		return ret;
	if (!weight && o->weighting == GLINT_WEIGHT_POISSON) {
		double mean = 0;
		int nv = 0;
		for (int i = 0; i < 3 * d->n; i++)
			if (d->sw[i] > 0) {
				mean += fmax(0, d->y[i]);
				nv++;
			}
		mean /= nv;
		for (int i = 0; i < 3 * d->n; i++)
			if (d->sw[i] > 0)
				d->sw[i] =
					1 / sqrt(fmax(0, d->y[i]) + 0.1 * mean);
	}
	return 0;
}
