/* SPDX-License-Identifier: MIT */
#include "shade_cache.h"
#include "shade_cache_internal.h"

#include "irradiance.h"
#include "sampling.h"

#include "core/error.h"
#include "core/parallel.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/*
 * Hit h's nl env samples: block s of a Sobol sequence shifted by seed,
 * for hit s of a pixel's hits sharing that seed: each hit's block a
 * stratified set of its own, the pixel's blocks together a larger one
 * (under many small lights a quarter less noise than sets of their own:
 * silver under grace.hdr, bench/residual).
 */
static void draw_env_samples(const struct glint_envmap *env,
			     const struct glint_env_hot *hot,
			     const struct glint_model *m,
			     const struct cache_hit *h, int nl, uint32_t salt,
			     int s, uint32_t seed, struct env_sample *es)
{
	enum { BATCH = 16 }; /* drawn side by side (glint_env_dist_sample_n) */
	double u1[BATCH], u2[BATCH], pdfs[BATCH];
	double dx[BATCH], dy[BATCH], dz[BATCH];
	struct vec3 ds[BATCH];
	struct glint_env_query q[BATCH];

	for (int k = 0; k < nl; k++) {
		int e = k % BATCH;
		if (!e) {
			int cnt = nl - k < BATCH ? nl - k : BATCH;
			for (int a = 0; a < cnt; a++) {
				double u[2];
				glint_sobol2((uint32_t)(s * nl + k + a),
					     seed ^ salt, u);
				u1[a] = u[0];
				u2[a] = u[1];
			}
			glint_env_dist_sample_n(env, &hot->rest, cnt, u1, u2,
						ds, pdfs);
			/* and their places in the rest's table (the queries'
			 * conversions vectorised) */
			for (int a = 0; a < cnt; a++)
				dx[a] = ds[a].x, dy[a] = ds[a].y,
				dz[a] = ds[a].z;
			glint_env_query_start_n(hot, cnt, dx, dy, dz, q);
		}
		double l[3], pdf = pdfs[e];
		struct vec3 d = ds[e];
		struct env_sample *es_k = &es[k];
		struct vec3 wi = v3(v3_dot(d, fv(h->t)), v3_dot(d, fv(h->b)),
				    v3_dot(d, fv(h->n)));
		memset(es_k, 0, sizeof(*es_k));
		if (!(pdf > 0) || !(wi.z > 0))
			continue; /* contributes nothing: b = 0 below */
		/* the rest's radiance and smooth pdf from one read of the
		 * table (glint_env_query(): the same values as
		 * glint_env_rest_lookup() and glint_env_dist_pdf_smooth()) */
		double ps;
		glint_env_query_finish(hot, &q[e], l, &ps);
		es_k->wi[0] = (float)wi.x;
		es_k->wi[1] = (float)wi.y;
		es_k->wi[2] = (float)wi.z;
		for (int ch = 0; ch < 3; ch++)
			es_k->l[ch] = (float)l[ch];
		es_k->pdf = (float)pdf;
		es_k->pdf_smooth = (float)ps;
		/* A sample whose smooth pdf vanishes must keep its weight
		 * finite: fall back to the sampling pdf. */
		if (!(es_k->pdf_smooth > 0))
			es_k->pdf_smooth = es_k->pdf;
		if (m->lobes->geometry)
			m->lobes->geometry(fv(h->wo), wi, es_k->g);
	}
}

struct setup_job {
	struct glint_shade_cache *c;
	int static_samples;
	const double *p0;
	int failed;
};

static void setup_pixels(void *ctx, int i0, int i1, int thread)
{
	struct setup_job *job = ctx;
	struct glint_shade_cache *c = job->c;
	const struct glint_model *m = c->model;
	int ns = job->static_samples;
	struct env_sample *tmp = malloc((size_t)ns * sizeof(*tmp));
	double(*u)[2] = malloc((size_t)ns * sizeof(*u));

	(void)thread;
	glint_thread_ftz();
	if (!tmp || !u) {
		job->failed = 1;
		goto out;
	}
	for (int k = 0; k < ns; k++) {
		u[k][0] = (k + 0.5) / ns;
		u[k][1] = glint_radical2((uint32_t)k);
	}
	for (int i = i0; i < i1; i++) {
		for (int s = 0; s < c->spp; s++) {
			const struct cache_hit *h =
				&c->hits[(size_t)i * c->spp + s];
			draw_env_samples(
				c->env, c->hot, m, h, c->nl, 0x3c6ef372u, s,
				c->hits[(size_t)i * c->spp].seed,
				c->envs + ((size_t)i * c->spp + s) * c->nl);
			int drawn = 0;
			for (int j = 0; j < m->bxdf->nlobes; j++) {
				double a[3] = { 0, 0, 0 }, e[3];
				if (m->lobes->varies[j])
					continue;
				if (c->lambert[j]) {
					/* Exact: hot texels + irradiance. */
					shade_hot_quadrature(c, h, job->p0, j,
							     1, a, NULL);
					glint_irradiance_lookup(&c->light->irr,
								fv(h->n), e);
					for (int ch = 0; ch < 3; ch++)
						a[ch] += e[ch] / M_PI;
				} else {
					if (!drawn)
						draw_env_samples(c->env, c->hot,
								 m, h, ns,
								 0x1b873593u, 0,
								 h->seed, tmp);
					drawn = 1;
					shade_lobe_at_hit(c, h, tmp, ns, ns, u,
							  job->p0, j, 1, NULL,
							  -1, 0, a, NULL);
				}
				double *dst =
					c->static_lobes +
					((size_t)i * m->bxdf->nlobes + j) * 3;
				for (int ch = 0; ch < 3; ch++)
					dst[ch] += a[ch] / c->spp;
			}
		}
	}
out:
	free(tmp);
	free(u);
}

/* Hot texels: within 1 % of the brightest, if at most 256 of them (a
 * sun, or a few lamps: six lamps of 0.6 to 2 degrees at 1024 px are 155;
 * each lamp's points are culled by its own cone); 2 x 2 points each
 * (spread: half their spacing in latitude). */
int glint_shade_light_new(const struct glint_envmap *env,
			  const struct glint_shade_cache_opts *opts,
			  struct glint_shade_light **out)
{
	struct glint_shade_light *l = calloc(1, sizeof(*l));
	int ret;

	*out = NULL;
	if (!l)
		return glint_error_set(ENOMEM, "out of memory");
	ret = glint_env_hot_new(env, 0.01, opts->no_hot ? 0 : 256, 2, &l->hot);
	l->spread = M_PI / env->img->height / 2 / 2;
	if (ret == 0)
		ret = glint_irradiance_build(env, l->hot->is_hot, 128,
					     opts->nthreads, &l->irr);
	if (ret < 0) {
		glint_shade_light_free(l);
		return ret;
	}
	*out = l;
	return 0;
}

void glint_shade_light_free(struct glint_shade_light *l)
{
	if (!l)
		return;
	glint_env_hot_free(l->hot);
	glint_irradiance_free(&l->irr);
	free(l);
}

int glint_shade_cache_new(const struct glint_gbuffer *gb, const int32_t *pix,
			  int n, const struct glint_envmap *env,
			  const struct glint_model *model,
			  const struct glint_shade_cache_opts *opts,
			  struct glint_shade_cache **out)
{
	struct glint_shade_cache *c;
	double p0[GLINT_MAX_PARAMS];

	*out = NULL;
	if (model->bxdf->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "model %s is not linear in its albedos: "
				       "the shade cache cannot fit it",
				       model->name);
	if (n <= 0)
		return glint_error_set(EINVAL, "no pixels to fit");
	c = calloc(1, sizeof(*c));
	if (!c)
		return glint_error_set(ENOMEM, "out of memory");
	c->model = model;
	c->env = env;
	c->n = n;
	c->spp = gb->spp;
	c->nl = opts->light_samples;
	c->nb = opts->lobe_samples;
	c->nthreads = opts->nthreads;
	/* The footprint's corrections integrate a pixel's square; with the
	 * camera's blur the hits are spread over its filter already, and
	 * the square's corrections bias a narrow lobe (a glossy highlight
	 * fitted 6 times too sharp under a 1.1 px blur). */
	c->no_footprint = opts->no_footprint || glint_gbuffer_filter(gb);
	c->pix = malloc((size_t)n * sizeof(*c->pix));
	c->hits = calloc((size_t)n * gb->spp, sizeof(*c->hits));
	c->feet = calloc((size_t)n, sizeof(*c->feet));
	c->envs = calloc((size_t)n * gb->spp * (c->nl ? c->nl : 1),
			 sizeof(*c->envs));
	c->lobe_sobol = malloc((size_t)(c->nb ? c->nb : 1) * gb->spp *
			       sizeof(*c->lobe_sobol));
	c->static_lobes =
		calloc((size_t)n * model->bxdf->nlobes * 3, sizeof(double));
	if (!c->pix || !c->hits || !c->feet || !c->envs || !c->lobe_sobol ||
	    !c->static_lobes) {
		glint_shade_cache_free(c);
		return glint_error_set(ENOMEM,
				       "out of memory for the shade cache of "
				       "%d pixels",
				       n);
	}
	memcpy(c->pix, pix, (size_t)n * sizeof(*pix));
	int ret = 0;
	c->light = opts->light;
	if (!c->light) {
		ret = glint_shade_light_new(env, opts, &c->own_light);
		c->light = c->own_light;
	}
	if (ret < 0) {
		glint_shade_cache_free(c);
		return ret;
	}
	c->hot = c->light->hot;
	/* Constant lobes equal to 1/pi (Lambert) integrate exactly through
	 * the irradiance of the rest of the map. */
	for (int k = 0; k < model->nparams; k++)
		p0[k] = model->params[k].def;
	for (int j = 0; j < model->bxdf->nlobes; j++) {
		double b[GLINT_MAX_PARAMS];
		model->bxdf->eval_lobes(p0, v3(0, 0.6, 0.8), v3(0.3, 0, 0.9539),
					b);
		c->lambert[j] = !model->lobes->varies[j] &&
				fabs(b[j] - 1 / M_PI) < 1e-12;
	}
	for (int k = 0; k < c->nb * gb->spp; k++)
		glint_sobol2_bits((uint32_t)k, c->lobe_sobol[k]);
	for (int i = 0; i < n; i++) {
		for (int s = 0; s < gb->spp; s++) {
			const struct glint_hit *g =
				glint_gbuffer_pixel(gb, (size_t)pix[i]);
			struct cache_hit *h = &c->hits[(size_t)i * gb->spp + s];
			if (g)
				g += s;
			if (!g || g->geom < 0) {
				glint_shade_cache_free(c);
				return glint_error_set(
					EINVAL,
					"pixel %d of the fit is not wholly "
					"on the sample",
					pix[i]);
			}
			struct vec3 nn = fv(g->n), t, b;
			struct vec3 wo = v3_scale(fv(g->d), -1);
			v3_frame(nn, &t, &b);
			for (int k = 0; k < 3; k++) {
				h->t[k] = (float)(k == 0   ? t.x
						  : k == 1 ? t.y
							   : t.z);
				h->b[k] = (float)(k == 0   ? b.x
						  : k == 1 ? b.y
							   : b.z);
				h->n[k] = g->n[k];
			}
			h->wo[0] = (float)v3_dot(wo, t);
			h->wo[1] = (float)v3_dot(wo, b);
			h->wo[2] = (float)v3_dot(wo, nn);
			h->seed = glint_hash32(
				(glint_gbuffer_frame_pixel(gb, (size_t)pix[i]) *
					 (uint32_t)gb->spp +
				 (uint32_t)s) ^
				0x85ebca6bu ^ glint_hash32(opts->seed));
		}
		shade_foot_fit(gb, pix[i],
			       glint_gbuffer_pixel(gb, (size_t)pix[i]),
			       &c->feet[i]);
	}
	struct setup_job job = { c, opts->static_samples, p0, 0 };
	glint_parallel_for(n, 64, opts->nthreads, setup_pixels, &job);
	if (job.failed) {
		glint_shade_cache_free(c);
		return glint_error_set(ENOMEM, "out of memory");
	}
	*out = c;
	return 0;
}

int glint_shade_cache_join(struct glint_shade_cache **parts, int nparts,
			   struct glint_shade_cache **out)
{
	struct glint_shade_cache *c = NULL;
	int n = 0, ret = 0;

	*out = NULL;
	for (int k = 0; k < nparts; k++)
		n += parts[k]->n;
	if (nparts < 1 || nparts > USHRT_MAX)
		ret = glint_error_set(EINVAL,
				      "%d parts: a joint cache takes 1 "
				      "to %d",
				      nparts, USHRT_MAX);
	else if (!(c = calloc(1, sizeof(*c))) ||
		 !(c->part_of = malloc((size_t)n * sizeof(*c->part_of))) ||
		 !(c->part_off = malloc((size_t)nparts * sizeof(int))) ||
		 !(c->parts = malloc((size_t)nparts * sizeof(*c->parts))))
		ret = glint_error_set(ENOMEM, "out of memory");
	if (ret < 0) {
		for (int k = 0; k < nparts; k++)
			glint_shade_cache_free(parts[k]);
		glint_shade_cache_free(c); /* its own arrays: no parts yet */
		return ret;
	}
	c->model = parts[0]->model;
	c->nthreads = parts[0]->nthreads;
	c->n = n;
	c->nparts = nparts;
	for (int k = 0, i = 0; k < nparts; k++) {
		c->parts[k] = parts[k];
		c->part_off[k] = i;
		for (int u = 0; u < parts[k]->n; u++)
			c->part_of[i++] = (unsigned short)k;
	}
	*out = c;
	return 0;
}

void glint_shade_cache_fix_footprint(struct glint_shade_cache *c,
				     const double *p)
{
	for (int k = 0; k < c->nparts; k++)
		glint_shade_cache_fix_footprint(c->parts[k], p);
	c->foot_fixed = p != NULL;
	if (p)
		memcpy(c->foot_p, p,
		       (size_t)c->model->nparams * sizeof(*c->foot_p));
}

void glint_shade_cache_free(struct glint_shade_cache *c)
{
	if (!c)
		return;
	for (int k = 0; k < c->nparts; k++)
		glint_shade_cache_free(c->parts[k]);
	free(c->parts);
	free(c->part_of);
	free(c->part_off);
	free(c->pix);
	free(c->hits);
	free(c->feet);
	free(c->envs);
	free(c->lobe_sobol);
	free(c->static_lobes);
	glint_shade_light_free(c->own_light);
	free(c);
}

struct lobes_job {
	struct glint_shade_cache *c;
	const double *p;
	const int *sel; /* NULL: all pixels */
	double *lobes;
	double *dlobes;	   /* NULL, or the lobes' derivatives by factor_param */
	int constant_only; /* the varying lobes 0, not shaded */
};

static void lobes_pixels(void *ctx, int i0, int i1, int thread)
{
	struct lobes_job *job = ctx;
	const struct glint_model *m = job->c->model;
	int nj = m->bxdf->nlobes;

	(void)thread;
	glint_thread_ftz();
	for (int k = i0; k < i1; k++) {
		int i = job->sel ? job->sel[k] : k;
		const struct glint_shade_cache *c = job->c;
		if (c->parts) {
			int part = c->part_of[i];
			i -= c->part_off[part];
			c = c->parts[part];
		}
		double *dst = job->lobes + (size_t)k * nj * 3;
		double *dd =
			job->dlobes ? job->dlobes + (size_t)k * nj * 3 : NULL;
		memcpy(dst, c->static_lobes + (size_t)i * nj * 3,
		       (size_t)nj * 3 * sizeof(double));
		if (dd) /* the constant lobes depend on no parameter */
			memset(dd, 0, (size_t)nj * 3 * sizeof(double));
		for (int j = 0; j < nj; j++) {
			if (!m->lobes->varies[j])
				continue;
			if (job->constant_only) {
				dst[j * 3] = dst[j * 3 + 1] = dst[j * 3 + 2] =
					0;
				continue;
			}
			double hot[3], dhot[3];
			const double *pf = c->foot_fixed ? c->foot_p : job->p;
			int foot = shade_hot_footprint(c, i, job->p, pf, j, hot,
						       dd ? dhot : NULL);
			for (int ch = 0; ch < 3 && foot; ch++) {
				dst[j * 3 + ch] += hot[ch];
				if (dd)
					dd[j * 3 + ch] += dhot[ch];
			}
			struct spread sp = { &c->feet[i], 0, { 0, 0 }, 0, 0 };
			sp.w = fmin(1, fmax(0, shade_foot_level(c, i, pf, j) +
						       SPREAD_FROM));
			if (sp.w > 0) {
				uint32_t sd = c->hits[(size_t)i * c->spp].seed;
				sp.shift[0] = glint_u01(
					glint_hash32(sd ^ 0x7f4a7c15u));
				sp.shift[1] = glint_u01(
					glint_hash32(sd ^ 0x94d049bbu));
				sp.perm = glint_hash32(sd ^ 0x5bd1e995u);
			}
			for (int s = 0; s < c->spp; s++) {
				size_t hi = (size_t)i * c->spp + s;
				double a[3], da[3];
				sp.s = s;
				shade_lobe_at_hit(
					c, &c->hits[hi], c->envs + hi * c->nl,
					c->nl, c->nb, NULL, job->p, j, !foot,
					sp.w > 0 ? &sp : NULL, s,
					c->hits[(size_t)i * c->spp].seed, a,
					dd ? da : NULL);
				for (int ch = 0; ch < 3; ch++) {
					dst[j * 3 + ch] += a[ch] / c->spp;
					if (dd)
						dd[j * 3 + ch] +=
							da[ch] / c->spp;
				}
			}
		}
	}
}

void glint_shade_cache_lobes(struct glint_shade_cache *c, const double *p,
			     double *lobes)
{
	struct lobes_job job = { c, p, NULL, lobes, NULL, 0 };

	glint_parallel_for(c->n, 32, c->nthreads, lobes_pixels, &job);
}

void glint_shade_cache_lobes_sel(struct glint_shade_cache *c, const double *p,
				 const int *sel, int nsel, double *lobes)
{
	struct lobes_job job = { c, p, sel, lobes, NULL, 0 };

	glint_parallel_for(nsel, 32, c->nthreads, lobes_pixels, &job);
}

void glint_shade_cache_lobes_d(struct glint_shade_cache *c, const double *p,
			       const int *sel, int nsel, double *lobes,
			       double *dlobes)
{
	struct lobes_job job = {
		c, p, sel, lobes, c->model->lobes->factor_dlog ? dlobes : NULL,
		0
	};

	glint_parallel_for(nsel, 32, c->nthreads, lobes_pixels, &job);
}

void glint_shade_cache_constant_lobes_sel(struct glint_shade_cache *c,
					  const int *sel, int nsel,
					  double *lobes)
{
	struct lobes_job job = { c, NULL, sel, lobes, NULL, 1 };

	glint_parallel_for(nsel, 256, c->nthreads, lobes_pixels, &job);
}
