/* SPDX-License-Identifier: MIT */
/*
 * The job's final render: a pilot pair of renders, then samples enough to keep
 * the render's own noise below a share of the photo's, within a budget of
 * the fit's time (job.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "fit/job.h"
#include "fit/job_internal.h"

#include "fit/ladder.h"
#include "fit/misfit.h"
#include "fit/select.h"
#include "export/export.h"
#include "fit/render/compare.h"
#include "core/clock.h"
#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/path.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * The final render, with its own Monte Carlo noise held below the photo's
 * where the photo has a noise model (a weight image of 1/variance), so
 * that the residual judged in misfit and compare.png is the photo's noise
 * and the model's misfit, not the render's.  Two renders on independent
 * sample sets give the noise of their mean, (a - b)^2 / 4 per value; in
 * the photo's variance units, averaged over the sphere's weighted values,
 * that is q.  At the scene's sample counts q is measured; when it is above
 * RENDER_NOISE_TARGET (the render's noise at most half the photo's, adding
 * at most a quarter to chi^2) one more pair is rendered with the samples
 * that should bring the two together to the target (q falls as 1 /
 * samples), at most RENDER_MAX_FACTOR times the scene's, and the two
 * means are combined by inverse variance.  The whole render keeps to a
 * time budget, RENDER_BUDGET_SHARE of the fit's time and at least
 * RENDER_MIN_BUDGET_S, or the job's render_budget_s (--render-seconds):
 * the second pair is made only when the time left
 * after the first affords it (a pair's time grows with its samples), and
 * a large image's pairs shade a grid of every k-th pixel when even an
 * eighth of the samples over every pixel would not fit.  A
 * render held above the target by the budget is noisier than the photo
 * allows for, not wrong: its measured noise goes with it into the misfit
 * analysis, which counts it in the residual's variance.  What limited the
 * render is said in params.json.  Without a noise model the scene's
 * counts are used as they are.
 */
#define RENDER_NOISE_TARGET 0.25

#define RENDER_MAX_FACTOR 4

#define RENDER_BUDGET_SHARE 0.5

#define RENDER_MIN_BUDGET_S 1.0

/* The first pair's pilot, on images of 512 rows or more: every 16th row,
 * or on a taller image about RENDER_PILOT_ROWS of them (their noise is
 * measured on tens of thousands of values either way), at an eighth of
 * the scene's samples (the least the first pair takes); the pair's noise
 * and time at the scene's samples are scaled from it (noise as 1 /
 * samples; time as samples, which overstates it by the rays' share). */
#define RENDER_PILOT_STEP 16

#define RENDER_PILOT_ROWS 32

#define RENDER_PILOT_MIN_ROWS 512

#define RENDER_MIN_FACTOR 0.125

/* Where even an eighth of the samples over every pixel would overrun the
 * budget (a 12 MP photo: the sphere's 3.6 MP at 4 primary samples each),
 * the first pair shades a grid of every k-th pixel of every k-th row and
 * interpolates between grid pixels on the sphere (fit/render/render.h),
 * k at most RENDER_MAX_STEP. */
#define RENDER_MAX_STEP 8

double glint_render_first_factor(double q_pilot, double pair_s, double budget_s,
				 const char **limited_by)
{
	double f = 1;

	*limited_by = NULL;
	/* aimed at half the target, so that the pair lands below it */
	if (q_pilot >= 0 && isfinite(q_pilot))
		f = fmin(1, q_pilot / (0.5 * RENDER_NOISE_TARGET));
	if (pair_s > 0 && f * pair_s > budget_s) {
		f = budget_s / pair_s;
		*limited_by = "time: the budget_seconds it may take";
	}
	return fmax(f, RENDER_MIN_FACTOR);
}

int glint_render_pixel_step(double factor, double pair_s, double budget_s)
{
	if (!(pair_s > 0) || factor * pair_s <= budget_s)
		return 1;
	if (!(budget_s > 0)) /* the pilot took it all */
		return RENDER_MAX_STEP;
	int k = (int)ceil(sqrt(factor * pair_s / budget_s) - 1e-9);
	return k < RENDER_MAX_STEP ? k : RENDER_MAX_STEP;
}

int glint_render_factor(double q1, double pair_s, double budget_s,
			const char **limited_by)
{
	*limited_by = NULL;
	if (!(q1 > RENDER_NOISE_TARGET))
		return 0;
	int want = (int)ceil(q1 / RENDER_NOISE_TARGET - 1 - 1e-9);
	int factor = want;
	if (factor > RENDER_MAX_FACTOR) {
		factor = RENDER_MAX_FACTOR;
		*limited_by = "samples: at most 4 times the scene's per pair";
	}
	/* The second pair at `factor` takes about factor * pair_s. */
	int afford = pair_s > 0 ? (int)floor(budget_s / pair_s) : factor;
	if (afford < factor) {
		factor = afford > 0 ? afford : 0;
		*limited_by = "time: the budget_seconds it may take";
	}
	return factor;
}

/* The pair's noise over the pixels it shaded (with a pixel step, the
 * grid's: an interpolated pixel's noise is its corners' mean's). */
static double render_noise(const struct glint_image *a,
			   const struct glint_image *b,
			   const struct glint_image *cov,
			   const struct glint_image *w, int step, long *nv)
{
	double sum = 0;
	long n = 0;
	size_t np = (size_t)a->width * a->height;
	for (size_t i = 0; i < np; i++) {
		if (cov->data[3 * i] < 1)
			continue; /* rim or backdrop */
		if (step > 1 &&
		    ((i % a->width) % step || (i / a->width) % step))
			continue;
		for (int c = 0; c < 3; c++) {
			double wi = w->data[3 * i + c];
			double d = a->data[3 * i + c] - b->data[3 * i + c];
			if (!(wi > 0) || !isfinite(wi) || !isfinite(d))
				continue;
			sum += d * d / 4 * wi;
			n++;
		}
	}
	*nv = n;
	return n ? sum / n : NAN;
}

/* The scene's count n times factor, at least 1 when n is not 0. */
static int scaled(int n, double factor)
{
	return n ? (int)fmax(1, floor(n * factor + 0.5)) : 0;
}

/* One render at `factor` times the scene's samples, on sample sets
 * `seed`, of every row_step-th row. */
static int shade(struct glint_renderer *r, const struct glint_fit_job *job,
		 const struct glint_model *model, const double *p,
		 double factor, uint32_t seed, int row_step, int pixel_step,
		 struct glint_image *out, struct glint_image *cov)
{
	struct glint_shade_opts so = {
		.light_samples = scaled(job->scene.light_samples, factor),
		.brdf_samples = scaled(job->scene.brdf_samples, factor),
		.background = 1,
		.nthreads = job->nthreads,
		.seed = seed,
		.row_step = row_step,
		.pixel_step = pixel_step,
	};
	return glint_renderer_shade(r, model, p, &so, out, cov);
}

/* Into img, the mean of a pair of renders at `factor` times the scene's
 * samples; b receives the second.  *q: the mean's noise. */
static int render_pair(struct glint_renderer *r,
		       const struct glint_fit_job *job,
		       const struct glint_model *model, const double *p,
		       double factor, uint32_t seed, int row_step,
		       int pixel_step, struct glint_image *img,
		       struct glint_image *b, struct glint_image *cov,
		       double *q, long *nv)
{
	int ret = shade(r, job, model, p, factor, seed, row_step, pixel_step,
			img, cov);
	if (ret == 0)
		ret = shade(r, job, model, p, factor, seed + 1, row_step,
			    pixel_step, b, NULL);
	if (ret < 0)
		return ret;
	*q = render_noise(img, b, cov, job->weight, pixel_step, nv);
	for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++)
		img->data[i] = 0.5f * (img->data[i] + b->data[i]);
	return 0;
}

static json_t *render_step(const struct glint_fit_job *job, double factor,
			   double q, double seconds)
{
	return json_pack("{s:i, s:i, s:o, s:f}", "light_samples",
			 2 * scaled(job->scene.light_samples, factor),
			 "brdf_samples",
			 2 * scaled(job->scene.brdf_samples, factor), "noise",
			 glint_json_real_or_null(q), "seconds", seconds);
}

int job_render_final(struct glint_renderer *r, const struct glint_fit_job *job,
		     const struct glint_model *model, const double *p,
		     double fit_s, struct glint_image *img,
		     struct glint_image *cov, json_t **info)
{
	const struct glint_image *w = job->weight;
	double t0 = glint_clock_monotonic(), q1, q2 = NAN;
	struct glint_image *b = NULL, *more = NULL;
	long nv = 0;
	int ret, factor = 0;

	*info = NULL;
	if (!w || glint_model_is_transparent(model) || w->width != img->width ||
	    w->height != img->height) {
		ret = shade(r, job, model, p, 1, 0, 1, 1, img, cov);
		if (ret < 0)
			return ret;
		*info = json_pack("{s:i, s:i, s:s}", "light_samples",
				  job->scene.light_samples, "brdf_samples",
				  job->scene.brdf_samples, "noise",
				  "not compared: the photo has no noise model");
		return *info ? 0 : glint_error_set(ENOMEM, "out of memory");
	}
	b = glint_image_new(img->width, img->height);
	if (!b) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	double budget_s = job->render_budget_s > 0
				  ? job->render_budget_s
				  : fmax(RENDER_BUDGET_SHARE * fit_s,
					 RENDER_MIN_BUDGET_S);
	/* A large image's first pair is sized by a pilot (RENDER_PILOT_STEP
	 * above): fewer samples where the render is already far below the
	 * photo's noise, and within the time budget, on a grid if need be. */
	double f1 = 1, qp = NAN, pilot_s = 0;
	int step = 1;
	const char *first_limit = NULL;
	int pilot_step = img->height / RENDER_PILOT_ROWS;
	if (pilot_step < RENDER_PILOT_STEP)
		pilot_step = RENDER_PILOT_STEP;
	if (img->height >= RENDER_PILOT_MIN_ROWS) {
		double tp = glint_clock_monotonic();
		ret = render_pair(r, job, model, p, RENDER_MIN_FACTOR, 0,
				  pilot_step, 1, img, b, cov, &qp, &nv);
		if (ret < 0)
			goto out;
		pilot_s = glint_clock_monotonic() - tp;
		double full_s = pilot_s * pilot_step / RENDER_MIN_FACTOR;
		double left_s = budget_s - (glint_clock_monotonic() - t0);
		qp *= RENDER_MIN_FACTOR; /* at the scene's samples */
		f1 = glint_render_first_factor(qp, full_s, left_s,
					       &first_limit);
		step = glint_render_pixel_step(f1, full_s, left_s);
	}
	double t1 = glint_clock_monotonic();
	ret = render_pair(r, job, model, p, f1, 0, 1, step, img, b, cov, &q1,
			  &nv);
	if (ret < 0)
		goto out;
	double q = q1, pair_s = glint_clock_monotonic() - t1;
	const char *limited_by;
	/* the second pair from the time the pilot and first pair left */
	factor = glint_render_factor(q1, pair_s,
				     budget_s - (glint_clock_monotonic() - t0),
				     &limited_by);
	if (!factor && first_limit)
		limited_by = first_limit;
	if (factor && !(more = glint_image_new(img->width, img->height))) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	double pair2_s = 0;
	if (factor) {
		double t2 = glint_clock_monotonic();
		ret = render_pair(r, job, model, p, f1 * factor, 2, 1, step,
				  more, b, cov, &q2, &nv);
		if (ret < 0)
			goto out;
		pair2_s = glint_clock_monotonic() - t2;
		/* Inverse-variance weights, one for the whole image: the
		 * pixels' variances all fall with the samples alike. */
		double w1 = 1 / q1, w2 = 1 / q2;
		if (!(w2 > 0) || !isfinite(w2))
			w1 = 0, w2 = 1; /* a noiseless second pair */
		for (size_t i = 0; i < (size_t)img->width * img->height * 3;
		     i++)
			img->data[i] = (float)((w1 * img->data[i] +
						w2 * more->data[i]) /
					       (w1 + w2));
		q = 1 / (w1 + w2);
	}
	int total_l =
		2 * scaled(job->scene.light_samples, f1) +
		(factor ? 2 * scaled(job->scene.light_samples, f1 * factor)
			: 0);
	int total_b =
		2 * scaled(job->scene.brdf_samples, f1) +
		(factor ? 2 * scaled(job->scene.brdf_samples, f1 * factor) : 0);
	json_t *steps = json_array();
	if (steps) {
		json_array_append_new(steps, render_step(job, f1, q1, pair_s));
		if (factor)
			json_array_append_new(
				steps,
				render_step(job, f1 * factor, q2, pair2_s));
	}
	*info = json_pack(
		"{s:i, s:i, s:o, s:f, s:b, s:I, s:f, s:f, s:s?, "
		"s:o*}",
		"light_samples", total_l, "brdf_samples", total_b, "noise",
		glint_json_real_or_null(q), "noise_target", RENDER_NOISE_TARGET,
		"below_target", q <= RENDER_NOISE_TARGET, "values",
		(json_int_t)nv, "seconds", glint_clock_monotonic() - t0,
		"budget_seconds", budget_s, "limited_by",
		q <= RENDER_NOISE_TARGET ? NULL : limited_by, "steps", steps);
	if (*info && img->height >= RENDER_PILOT_MIN_ROWS)
		json_object_set_new(
			*info, "pilot",
			json_pack("{s:i, s:f, s:o, s:f, s:f}", "row_step",
				  pilot_step, "factor", RENDER_MIN_FACTOR,
				  "noise", glint_json_real_or_null(qp),
				  "first_pair_factor", f1, "seconds", pilot_s));
	if (*info)
		json_object_set_new(*info, "pixel_step", json_integer(step));
	if (!*info) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	char grid[64] = "";
	if (step > 1)
		snprintf(grid, sizeof(grid),
			 " on a grid of every %d pixels, interpolated between",
			 step);
	glint_log_info("final render: %d + %d samples%s, its noise %.2f of the "
		       "photo's variance (target %.2f), %.1f s%s%s",
		       total_l, total_b, grid, q, RENDER_NOISE_TARGET,
		       glint_clock_monotonic() - t0,
		       q > RENDER_NOISE_TARGET && limited_by ? "; limited by "
							     : "",
		       q > RENDER_NOISE_TARGET && limited_by ? limited_by : "");
out:
	glint_image_free(b);
	glint_image_free(more);
	return ret;
}
