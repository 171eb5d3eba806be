/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_FIT_DATA_H
#define GLINT_FIT_FIT_DATA_H

/* The pixels a fit uses, shared by the opaque (fit.c) and transparent
 * (fit_dielectric.c) fitters.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: read only once built, shared by the
 * fit's threads.  Who frees: free_data().
 */

#include "fit.h"
#include "render/shade_cache.h"

/* The pixels of a fit ("universe") with their photo values and weights. */
struct fit_data {
	int n;
	int32_t *pix; /* image pixel index */
	int *xy;      /* x, y pairs */
	double *y;    /* photo, 3 per pixel */
	double *sw;   /* sqrt of the weights, 3 per pixel */
	/* The noise model behind the weights, 3 per pixel: the variance of
	 * a value whose noise-free signal is v is va + vb v.  Weights made
	 * from the photo's own noisy values correlate with its noise (a
	 * pixel that came out dark gets more weight) and bias the fit low;
	 * fit_data_reweight() evaluates the model at the fit's prediction
	 * instead. */
	double *va, *vb;
	int noise_model; /* va, vb model a weight image (a real noise model) */
	/* va, vb known up to a scale (the default signal-proportional
	 * variance, `--weights` not given): re-evaluated at the prediction
	 * too, the scale estimated from the residuals */
	int shape_only;
	int stride;	      /* every stride-th row and column was taken */
	int frame_x, frame_y; /* xy's origin in the frame (pinhole.h) */
};

void free_data(struct fit_data *d);

/* Which frame pixels (X, Y) the fine set of stride s takes, and which of
 * those the coarse set does, given the photo's colour filter array (cfa,
 * pinhole.h): every s-th (4 s-th) row and column, the mosaic's sites
 * taking turns on a demosaiced photo. */
int fit_data_fine_pick(const signed char cfa[4], int X, int Y, int s);
int fit_data_coarse_pick(const signed char cfa[4], int X, int Y, int s);

/* Is pixel (x, y) wholly on the sphere as a fit takes it: every hit of
 * its whole 3 x 3 neighbourhood on it (a pixel whose own hits all hit
 * can still be part backdrop between them)? */
int fit_data_interior(const struct glint_gbuffer *gb, int x, int y);

/*
 * Check photo and weight against the camera, collect the pixels wholly on
 * the sphere (every stride-th, about o->max_pixels of them) with their
 * values and sqrt weights (o->weighting when weight is NULL), and check
 * the photo shows something there.  A sparse G-buffer is made to hold
 * the chosen pixels.  *interior gets the count before
 * subsampling.
 */
int fit_data_prepare(struct glint_gbuffer *gb, const struct glint_image *photo,
		     const struct glint_image *weight,
		     const struct glint_fit_opts *o, struct fit_data *d,
		     int *interior);

/* The pixels of several photos one after the other (a joint fit):
 * copies; stride and frame are parts[0]'s, noise_model is set when every
 * part has one, shape_only when every part is so (photos with and
 * without weights together: no reweighting, the scales differ). */
int fit_data_join(const struct fit_data *parts, int nparts, struct fit_data *d);

/* Where one photo's pixels lie in a joint fit_data (off, n) and how they
 * were taken from it (fit_data_prepare()). */
struct fit_data_part {
	int off, n;
	int interior, stride, frame_x, frame_y;
};

/* Each photo's pixels (fit_data_prepare()), joined one after the other
 * into d (one photo: its own), with where each lies in parts[]; an error
 * names the photo ("photo 2 of 3"). */
int fit_data_prepare_views(const struct glint_fit_view *in, int nviews,
			   const struct glint_fit_opts *o, struct fit_data *d,
			   struct fit_data_part *parts);

/* A shade cache of model m over every pixel of d: one per photo in its
 * own scene, joined.  lights[v] (the array or an entry may be NULL) is
 * what photo v's caches share (co->light is ignored). */
int fit_data_cache_new(const struct glint_fit_view *in, int nviews,
		       const struct fit_data *d,
		       const struct fit_data_part *parts,
		       const struct glint_model *m,
		       const struct glint_shade_cache_opts *co,
		       struct glint_shade_light *const *lights,
		       struct glint_shade_cache **out);

/* The noise model's variance of value i (of 3 per pixel) whose
 * noise-free signal is v. */
static inline double fit_data_variance(const struct fit_data *d, int i,
				       double v)
{
	return d->va[i] + d->vb[i] * (v > 0 ? v : 0);
}

/* Weights from the noise model at the predicted values pred (3 per
 * pixel), for values that have a weight (pred = y: unchanged). */
void fit_data_reweight(struct fit_data *d, const double *pred);

/* Baselines for judging a fit's residual, over every value with a weight:
 * the relative RMSE of a flat disc of the photo's mean colour, and the
 * RMSE that noise alone leaves (NAN without a real noise model). */
void fit_data_baselines(const struct fit_data *d, double *flat_rel,
			double *noise_rmse);

#endif
