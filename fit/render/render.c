/* SPDX-License-Identifier: MIT */
#include "render.h"
#include "dielectric_paths.h"

#include "sampling.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static struct vec3 hvec(const float f[3])
{
	return v3(f[0], f[1], f[2]);
}

static struct vec3 to_local(struct vec3 v, struct vec3 t, struct vec3 b,
			    struct vec3 n)
{
	return v3(v3_dot(v, t), v3_dot(v, b), v3_dot(v, n));
}

static struct vec3 to_world(struct vec3 v, struct vec3 t, struct vec3 b,
			    struct vec3 n)
{
	return v3_add(v3_add(v3_scale(t, v.x), v3_scale(b, v.y)),
		      v3_scale(n, v.z));
}

/* A light path from the hit along world direction wi: visible? */
static int visible(struct glint_tracer *tracer, const struct glint_hit *h,
		   struct vec3 n, struct vec3 wi)
{
	if (!tracer)
		return 1;
	struct vec3 o = v3_add(hvec(h->p), v3_scale(n, 1e-6));
	return !glint_tracer_occluded(tracer, o, wi, 1e-6, INFINITY);
}

/* One of glint_shade_hit()'s samples between its direction and its
 * light. */
struct hit_pending {
	double f[3], w, pb; /* w: the env samples' weight (pb: a BRDF
			     * sample's pdf, its weight once pl is read) */
	struct glint_envmap_loc q;
};

/* The pending samples' light, added in order. */
static void hit_flush(const struct glint_envmap *env, int nl, int nb,
		      const struct hit_pending *pend, int np, int brdf,
		      double rgb[3])
{
	for (int e = 0; e < np; e++) {
		const struct hit_pending *q = &pend[e];
		double le[3], w = q->w;
		if (brdf) {
			double pl =
				nl ? glint_envmap_located_pdf(env, &q->q) : 0;
			w = w / (nl * pl + nb * q->pb);
		}
		glint_envmap_located_lookup(env, &q->q, le);
		for (int c = 0; c < 3; c++)
			rgb[c] += q->f[c] * le[c] * w;
	}
}

void glint_shade_hit(const struct glint_hit *h, uint32_t seed,
		     struct glint_tracer *tracer,
		     const struct glint_envmap *env,
		     const struct glint_model *model, const double *params,
		     int nl, int nb, double rgb[3])
{
	enum { BATCH = 16 }; /* samples whose table reads overlap */
	struct vec3 n = hvec(h->n), t, b;
	struct vec3 wo_w = v3_scale(hvec(h->d), -1);
	struct glint_bxdf bx = glint_model_bxdf(model, params);
	struct hit_pending pend[BATCH];
	double u1[BATCH], u2[BATCH], pls[BATCH];
	struct vec3 ws[BATCH];
	int np = 0;

	rgb[0] = rgb[1] = rgb[2] = 0;
	v3_frame(n, &t, &b);
	struct vec3 wo = to_local(wo_w, t, b, n);
	if (!(wo.z > 0))
		return;
	/* Env-map samples; balance heuristic weight nl pdf_l/(nl pdf_l +
	 * nb pdf_b) folded into the estimator's denominator.  In batches:
	 * their directions drawn side by side, then each one's BRDF and
	 * its texels prefetched, then their light. */
	for (int k0 = 0; k0 < nl; k0 += BATCH) {
		int m = nl - k0 < BATCH ? nl - k0 : BATCH;
		for (int e = 0; e < m; e++) {
			double u[2];
			glint_hammersley((uint32_t)(k0 + e), (uint32_t)nl, seed,
					 u);
			u1[e] = u[0];
			u2[e] = u[1];
		}
		glint_envmap_sample_n(env, m, u1, u2, ws, pls);
		np = 0;
		for (int e = 0; e < m; e++) {
			struct hit_pending *q = &pend[np];
			struct vec3 wi = to_local(ws[e], t, b, n);
			if (!(pls[e] > 0) || !(wi.z > 0))
				continue;
			glint_bxdf_eval(&bx, wo, wi, q->f);
			if (q->f[0] + q->f[1] + q->f[2] <= 0)
				continue;
			if (!visible(tracer, h, n, ws[e]))
				continue;
			double pb = nb ? glint_bxdf_pdf(&bx, wo, wi) : 0;
			q->w = wi.z / (nl * pls[e] + nb * pb);
			glint_envmap_locate(env, ws[e], &q->q);
			np++;
		}
		hit_flush(env, nl, nb, pend, np, 0, rgb);
	}
	np = 0;
	for (int k = 0; k < nb; k++) {
		double u[3];
		struct vec3 wi;
		struct hit_pending *q = &pend[np];
		glint_hammersley((uint32_t)k, (uint32_t)nb, seed ^ 0x68e31da4u,
				 u + 1);
		u[0] = glint_u01(glint_hash3(seed, (uint32_t)k, 0xb5297a4du));
		double pb = glint_bxdf_sample(&bx, wo, u, &wi);
		if (pb > 0 && wi.z > 0) {
			struct vec3 wi_w = to_world(wi, t, b, n);
			glint_bxdf_eval(&bx, wo, wi, q->f);
			if (q->f[0] + q->f[1] + q->f[2] > 0 &&
			    visible(tracer, h, n, wi_w)) {
				q->w = wi.z;
				q->pb = pb;
				glint_envmap_locate(env, wi_w, &q->q);
				np++;
			}
		}
		if (np == BATCH || (k == nb - 1 && np)) {
			hit_flush(env, nl, nb, pend, np, 1, rgb);
			np = 0;
		}
	}
}

struct shade_job {
	const struct glint_gbuffer *gb;
	struct glint_tracer *tracer;
	const struct glint_envmap *env;
	const struct glint_model *model;
	const double *params;
	const struct glint_shade_opts *opts;
	struct glint_image *out, *coverage;
	int step;      /* pixel_step, at least 1 */
	uint8_t *full; /* pixel_step > 1: the grid's pixels all on the sphere */
	int grid_w;    /* grid columns: (width - 1) / step + 1 */
	int filling;   /* the second pass */
	int failed;
};

/* Pixel (x, y) from its spp hits hs: the mean of its samples into out,
 * its hits' share into coverage.  Returns its hits. */
static int shade_pixel(struct shade_job *job, const struct glint_hit *hs, int x,
		       int y)
{
	const struct glint_gbuffer *gb = job->gb;
	int spp = gb->spp, hits = 0;
	size_t pix = (size_t)y * gb->width + x;
	double sum[3] = { 0, 0, 0 }, rgb[3];

	for (int s = 0; s < spp; s++) {
		const struct glint_hit *h = &hs[s];
		if (h->geom < 0) {
			if (!job->opts->background)
				continue;
			glint_envmap_lookup(job->env, hvec(h->d), rgb);
		} else {
			hits++;
			glint_shade_hit(
				h,
				glint_hash32(
					glint_gbuffer_frame_pixel(gb, pix) *
						(uint32_t)spp +
					(uint32_t)s +
					job->opts->seed * 0x9e3779b9u),
				job->tracer, job->env, job->model, job->params,
				job->opts->light_samples,
				job->opts->brdf_samples, rgb);
		}
		for (int c = 0; c < 3; c++)
			sum[c] += rgb[c];
	}
	float *o = glint_image_px(job->out, x, y);
	for (int c = 0; c < 3; c++)
		o[c] = (float)(sum[c] / spp);
	if (job->coverage) {
		float *cv = glint_image_px(job->coverage, x, y);
		cv[0] = cv[1] = cv[2] = (float)hits / spp;
	}
	return hits;
}

/* Pixel (x, y) between grid pixels that all lie on the sphere, as they
 * do: bilinear in the grid's four corners.  0 when it is not (a corner
 * off the image or off the sphere, or the pixel itself not wholly on it). */
static int interpolate_pixel(struct shade_job *job, const struct glint_hit *hs,
			     int x, int y)
{
	const struct glint_gbuffer *gb = job->gb;
	int k = job->step, gx = x / k, gy = y / k;

	if ((gx + 1) * k >= gb->width || (gy + 1) * k >= gb->height)
		return 0;
	for (int s = 0; s < gb->spp; s++)
		if (hs[s].geom < 0)
			return 0;
	const uint8_t *f = job->full + (size_t)gy * job->grid_w + gx;
	if (!f[0] || !f[1] || !f[job->grid_w] || !f[job->grid_w + 1])
		return 0;
	double u = (double)(x - gx * k) / k, v = (double)(y - gy * k) / k;
	const float *a = glint_image_px(job->out, gx * k, gy * k);
	const float *b = glint_image_px(job->out, gx * k + k, gy * k);
	const float *c = glint_image_px(job->out, gx * k, gy * k + k);
	const float *d = glint_image_px(job->out, gx * k + k, gy * k + k);
	float *o = glint_image_px(job->out, x, y);
	for (int ch = 0; ch < 3; ch++)
		o[ch] = (float)((1 - v) * ((1 - u) * a[ch] + u * b[ch]) +
				v * ((1 - u) * c[ch] + u * d[ch]));
	if (job->coverage) {
		float *cv = glint_image_px(job->coverage, x, y);
		cv[0] = cv[1] = cv[2] = 1;
	}
	return 1;
}

/* Row y of the first pass: every pixel (every row_step-th row for a
 * pilot), or with pixel_step k the grid's pixels only, each grid pixel's
 * "all on the sphere" kept for the second pass. */
static void shade_row(struct shade_job *job, int y, struct glint_hit *buf)
{
	const struct glint_gbuffer *gb = job->gb;
	int spp = gb->spp, k = job->step;

	if ((job->opts->row_step > 1 && y % job->opts->row_step) || y % k)
		return;
	const struct glint_hit *row = glint_gbuffer_row(gb, y, buf);
	for (int x = 0; x < gb->width; x += k) {
		int hits = shade_pixel(job, row + (size_t)x * spp, x, y);
		if (k > 1)
			job->full[(size_t)(y / k) * job->grid_w + x / k] =
				hits == spp;
	}
}

/* Row y of a pixel-step render's second pass: each pixel off the grid
 * interpolated where the grid around it lies on the sphere, shaded
 * where it does not (the rim, the backdrop). */
static void fill_row(struct shade_job *job, int y, struct glint_hit *buf)
{
	const struct glint_gbuffer *gb = job->gb;
	int spp = gb->spp, k = job->step;
	const struct glint_hit *row = glint_gbuffer_row(gb, y, buf);

	for (int x = 0; x < gb->width; x++) {
		const struct glint_hit *hs = row + (size_t)x * spp;
		if ((y % k == 0 && x % k == 0) ||
		    interpolate_pixel(job, hs, x, y))
			continue;
		shade_pixel(job, hs, x, y);
	}
}

/* A worker's rows of the pass job->filling says; the progress counts
 * each row once, in the last pass. */
static void shade_rows(void *ctx, int y0, int y1, int thread)
{
	struct shade_job *job = ctx;
	const struct glint_gbuffer *gb = job->gb;
	struct glint_hit *buf = NULL;

	(void)thread;
	glint_thread_ftz();
	if (!gb->hits &&
	    !(buf = malloc((size_t)gb->width * gb->spp * sizeof(*buf)))) {
		job->failed = 1;
		return;
	}
	for (int y = y0; y < y1; y++) {
		if (job->filling)
			fill_row(job, y, buf);
		else
			shade_row(job, y, buf);
		if (job->opts->progress && (job->filling || job->step == 1))
			glint_progress_add(job->opts->progress, 1);
	}
	free(buf);
}

int glint_render_shade(const struct glint_gbuffer *gb,
		       struct glint_tracer *tracer,
		       const struct glint_envmap *env,
		       const struct glint_model *model, const double *params,
		       const struct glint_shade_opts *opts,
		       struct glint_image *out, struct glint_image *coverage)
{
	struct shade_job job = {
		.gb = gb,
		.tracer = tracer,
		.env = env,
		.model = model,
		.params = params,
		.opts = opts,
		.out = out,
		.coverage = coverage,
	};

	if (out->width != gb->width || out->height != gb->height ||
	    (coverage &&
	     (coverage->width != gb->width || coverage->height != gb->height)))
		return glint_error_set(
			EINVAL, "render target %dx%d: expected %dx%d",
			out->width, out->height, gb->width, gb->height);
	if (opts->light_samples < 0 || opts->brdf_samples < 0 ||
	    opts->light_samples + opts->brdf_samples == 0)
		return glint_error_set(EINVAL,
				       "light samples %d, BRDF samples %d: "
				       "expected >= 0 and not both 0",
				       opts->light_samples, opts->brdf_samples);
	if (opts->pixel_step > 1 && opts->row_step > 1)
		return glint_error_set(EINVAL,
				       "a pilot (row step %d) at a pixel step "
				       "of %d: expected one or the other",
				       opts->row_step, opts->pixel_step);
	if (tracer && glint_tracer_is_convex(tracer))
		job.tracer = NULL;
	job.step = opts->pixel_step > 1 ? opts->pixel_step : 1;
	if (job.step > 1) {
		job.grid_w = (gb->width - 1) / job.step + 1;
		size_t grid_h = (size_t)(gb->height - 1) / job.step + 1;
		job.full = calloc((size_t)job.grid_w * grid_h, 1);
		if (!job.full)
			return glint_error_set(ENOMEM, "out of memory");
	}
	glint_parallel_for(gb->height, 2, opts->nthreads, shade_rows, &job);
	if (job.step > 1 && !job.failed) {
		job.filling = 1;
		glint_parallel_for(gb->height, 2, opts->nthreads, shade_rows,
				   &job);
	}
	free(job.full);
	if (job.failed)
		return glint_error_set(ENOMEM, "out of memory");
	return 0;
}

int glint_renderer_init(struct glint_renderer *r,
			const struct glint_scene *scene, int nthreads,
			struct glint_progress *progress)
{
	struct glint_envmap *env;
	int ret = glint_envmap_load(scene->env_path, scene->env_rotation,
				    scene->env_scale, scene->env_srgb, &env);
	if (ret < 0)
		return ret;
	return glint_renderer_init_env(r, scene, env, nthreads, progress);
}

int glint_renderer_init_env(struct glint_renderer *r,
			    const struct glint_scene *scene,
			    struct glint_envmap *env, int nthreads,
			    struct glint_progress *progress)
{
	int ret;

	memset(r, 0, sizeof(*r));
	r->scene = *scene;
	r->env = env;
	ret = glint_tracer_new(&r->tracer);
	if (!ret)
		ret = glint_tracer_add_sphere(r->tracer, scene->sphere_centre,
					      scene->sphere_radius,
					      GLINT_SPHERE_USER);
	if (!ret)
		ret = glint_tracer_commit(r->tracer);
	if (ret < 0)
		goto err;
	double t0 = glint_clock_monotonic();
	double dense_mb = (double)scene->cam.width * scene->cam.height *
			  scene->spp * sizeof(struct glint_hit) / 1048576;
	if (dense_mb > glint_gbuffer_dense_mb())
		ret = glint_tracer_primary_sparse(r->tracer, &scene->cam,
						  scene->spp, nthreads,
						  progress, &r->gb);
	else
		ret = glint_tracer_primary(r->tracer, &scene->cam, scene->spp,
					   nthreads, progress, &r->gb);
	r->trace_seconds = glint_clock_monotonic() - t0;
	if (ret < 0)
		goto err;
	return 0;
err:
	glint_renderer_release(r);
	return ret;
}

void glint_renderer_release(struct glint_renderer *r)
{
	glint_gbuffer_free(&r->gb);
	glint_tracer_free(r->tracer);
	glint_envmap_free(r->env);
	r->tracer = NULL;
	r->env = NULL;
}

int glint_renderer_shade(struct glint_renderer *r,
			 const struct glint_model *model, const double *params,
			 const struct glint_shade_opts *opts,
			 struct glint_image *out, struct glint_image *coverage)
{
	if (glint_model_is_transparent(model)) {
		/* Its paths are traced for every pixel at once. */
		int n = r->gb.width * r->gb.height;
		int32_t *all =
			r->gb.hits ? NULL : malloc((size_t)n * sizeof(*all));
		if (!r->gb.hits && !all)
			return glint_error_set(ENOMEM, "out of memory");
		for (int i = 0; all && i < n; i++)
			all[i] = i;
		int ret =
			all ? glint_gbuffer_keep(&r->gb, all, n, opts->nthreads)
			    : 0;
		free(all);
		if (ret < 0)
			return ret;
		return glint_dielectric_render(r->tracer, &r->gb, r->env,
					       r->scene.sphere_centre,
					       r->scene.sphere_radius, params,
					       opts->nthreads, out, coverage);
	}
	return glint_render_shade(&r->gb, r->tracer, r->env, model, params,
				  opts, out, coverage);
}
