/* SPDX-License-Identifier: MIT */
#include "shade_cache.h"

#include "irradiance.h"
#include "sampling.h"

#include "core/error.h"
#include "core/parallel.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One fixed env-map sample of a hit, in the hit's local frame. */
struct env_sample {
	float wi[3];
	float l[3];
	float pdf;	  /* the sampling pdf */
	float pdf_smooth; /* continuous stand-in for the MIS weights */
	float g[4];	  /* model->lobes->geometry() at wo, wi */
};

/* One primary hit: its frame, its view direction, its sample shift. */
struct cache_hit {
	float t[3], b[3], n[3];
	float wo[3]; /* local */
	uint32_t seed;
};

/*
 * A pixel's footprint: its normal and ray direction as affine functions
 * of the position (u, v) in the pixel (centre 0, edges +-1/2), fitted to
 * its primary hits by least squares, and how fast its mirror direction
 * turns across it.  The hot texels of a lobe narrower than that are
 * integrated over the pixel on a grid (hot_footprint()), and its lobe
 * samples spread over the pixel (struct spread): a sun or a softbox's
 * edge seen in a near-mirror covers part of a pixel, which a few point
 * samples alias.
 */
struct cache_foot {
	float n[3], nu[3], nv[3];
	float d[3], du[3], dv[3];
	float r[3]; /* mirror direction at the centre */
	float turn; /* radians per pixel (largest of u and v); 0: no fit */
};

struct glint_shade_cache {
	const struct glint_model *model;
	const struct glint_envmap *env;
	/* The split of the map, and the irradiance of the non-hot texels
	 * for constant 1/pi lobes. */
	const struct glint_shade_light *light;
	const struct glint_env_hot *hot;     /* light->hot */
	struct glint_shade_light *own_light; /* when not shared */
	int lambert[GLINT_MAX_PARAMS];	     /* lobe j is the constant 1/pi */
	int n, spp, nl, nb, nthreads, no_footprint;
	int32_t *pix;
	struct cache_hit *hits;	   /* n * spp */
	struct cache_foot *feet;   /* n */
	struct env_sample *envs;   /* n * spp * nl */
	uint32_t (*lobe_sobol)[2]; /* spp nb Sobol points, unshifted */
	double *static_lobes;	   /* n * nlobes * 3, constant lobes only */
	/* A joint cache (glint_shade_cache_join()): its pixels are the
	 * parts' in order; part_of[i] is pixel i's part, part_off[k] part
	 * k's first pixel.  None of the fields above is set. */
	struct glint_shade_cache **parts;
	int nparts;
	unsigned short *part_of;
	int *part_off;
};

static struct vec3 fv(const float f[3])
{
	return v3(f[0], f[1], f[2]);
}

static struct vec3 local_to_world(const struct cache_hit *h, struct vec3 v)
{
	return v3_add(v3_add(v3_scale(fv(h->t), v.x), v3_scale(fv(h->b), v.y)),
		      v3_scale(fv(h->n), v.z));
}

/* Lobe j over the hot texels, on their fixed points: the map's
 * radiance on the hot texels' area (by_area: with the irradiance of the
 * other texels) or the hot texels' part of the radiance wherever it
 * reaches (with lobe and env samples of the rest: envmap.h). */
static void hot_quadrature(const struct glint_shade_cache *c,
			   const struct cache_hit *h, const double *p, int j,
			   int by_area, double out[3])
{
	const struct glint_env_hot *hot = c->hot;
	const struct glint_model *m = c->model;
	struct vec3 wo = fv(h->wo);
	int npts = by_area ? hot->npts : hot->npart;
	const float *pts = by_area ? hot->pts : hot->part;

	if (!npts)
		return;
	double ext = glint_lobe_extent(m, p, j);
	if (ext > 0) {
		struct vec3 r = local_to_world(h, v3(-wo.x, -wo.y, wo.z));
		double a = acos(fmin(1, fmax(-1, v3_dot(r, hot->axis))));
		if (a - hot->radius > ext)
			return;
	}
	for (int k = 0; k < npts; k++) {
		const float *pt = pts + 6 * (size_t)k;
		struct vec3 d = v3(pt[0], pt[1], pt[2]);
		struct vec3 wi = v3(v3_dot(d, fv(h->t)), v3_dot(d, fv(h->b)),
				    v3_dot(d, fv(h->n)));
		if (!(wi.z > 0))
			continue;
		double bj = glint_lobe_value_pdf(m, p, j, wo, wi, NULL);
		if (bj <= 0)
			continue;
		for (int ch = 0; ch < 3; ch++)
			out[ch] += bj * wi.z * pt[3 + ch];
	}
}

/* Pixel i's normal and ray direction at (u, v) in it, and the mirror
 * direction there. */
static void foot_at(const struct cache_foot *f, double u, double v,
		    struct vec3 *n, struct vec3 *d, struct vec3 *r)
{
	*n = v3_norm(v3_add(fv(f->n), v3_add(v3_scale(fv(f->nu), u),
					     v3_scale(fv(f->nv), v))));
	*d = v3_norm(v3_add(fv(f->d), v3_add(v3_scale(fv(f->du), u),
					     v3_scale(fv(f->dv), v))));
	*r = v3_sub(*d, v3_scale(*n, 2 * v3_dot(*d, *n)));
}

/*
 * A near-mirror's lobe samples spread over the pixel (lobes_pixels()):
 * lobe sample k of hit s is taken at the footprint's point q = k spp + s
 * of a stratified set of spp nb points, weight w (the rest, 1 - w, at the
 * hit itself).
 */
struct spread {
	const struct cache_foot *f;
	double w, shift[2];
	uint32_t perm;
	int s;
};

/* The hit seen at point at (centred) of footprint f: its frame and view
 * direction; 0 where the view grazes away. */
static int hit_at(const struct cache_foot *f, const double at[2],
		  struct cache_hit *h)
{
	struct vec3 n, d, r, t, b;

	foot_at(f, at[0], at[1], &n, &d, &r);
	v3_frame(n, &t, &b);
	struct vec3 wo = v3(-v3_dot(d, t), -v3_dot(d, b), -v3_dot(d, n));
	if (!(wo.z > 0))
		return 0;
	h->t[0] = (float)t.x, h->t[1] = (float)t.y, h->t[2] = (float)t.z;
	h->b[0] = (float)b.x, h->b[1] = (float)b.y, h->b[2] = (float)b.z;
	h->n[0] = (float)n.x, h->n[1] = (float)n.y, h->n[2] = (float)n.z;
	h->wo[0] = (float)wo.x, h->wo[1] = (float)wo.y, h->wo[2] = (float)wo.z;
	return 1;
}

/* One lobe sample (uniforms uu) at hit h, weighted by the balance
 * heuristic against nl env samples and by w, added to out. */
static void lobe_sample(const struct glint_shade_cache *c,
			const struct cache_hit *h, const double *p, int j,
			int nl, int nb, const double uu[2], double w,
			double out[3])
{
	const struct glint_model *m = c->model;
	struct vec3 wi;
	double bj;

	double pb = glint_lobe_sample_value(m, p, j, fv(h->wo), uu, &wi, &bj);
	if (!(pb > 0) || bj <= 0)
		return;
	struct vec3 ww = local_to_world(h, wi);
	double l[3], ps = 0;
	/* The rest's radiance, continuous across the hot texels' edges
	 * (their part is hot_quadrature()'s). */
	glint_env_query(c->hot, ww, l, &ps);
	if (!nl)
		ps = 0;
	w *= bj * wi.z / (nl * ps + nb * pb);
	for (int ch = 0; ch < 3; ch++)
		out[ch] += w * l[ch];
}

/*
 * Estimate lobe j's integral at one hit: nl env samples, nb lobe samples,
 * balance-heuristic weights with the smooth light pdf.  The lobe samples'
 * uniforms: for hit hs >= 0 of its pixel, block hs of a Sobol sequence
 * shifted by the pixel's seed pseed (as draw_env_samples()); for hs < 0
 * (constant lobes at set-up), the pairs u[k] shifted by the hit's seed.
 * env samples come from `es`, or are drawn afresh when es is NULL.
 */
static void lobe_at_hit(const struct glint_shade_cache *c,
			const struct cache_hit *h, const struct env_sample *es,
			int nl, int nb, const double (*u)[2], const double *p,
			int j, int with_hot, const struct spread *sp, int hs,
			uint32_t pseed, double out[3])
{
	const struct glint_model *m = c->model;
	struct vec3 wo = fv(h->wo);
	double sx = 0, sy = 0;
	uint32_t shift[2] = { 0, 0 };

	if (hs >= 0) {
		glint_sobol2_shift(pseed, shift);
	} else {
		sx = glint_u01(glint_hash32(h->seed ^ 0x2545f491u));
		sy = glint_u01(glint_hash32(h->seed ^ 0x9e3779b9u));
	}

	int geom = m->lobes->from_geometry && m->lobes->varies[j];

	out[0] = out[1] = out[2] = 0;
	if (with_hot)
		hot_quadrature(c, h, p, j, 0, out);
	for (int k = 0; k < nl; k++) {
		const struct env_sample *e = &es[k];
		struct vec3 wi = fv(e->wi);
		double pb = 0;
		double bj = geom ? m->lobes->from_geometry(p, j, e->g,
							   nb ? &pb : NULL)
				 : glint_lobe_value_pdf(m, p, j, wo, wi,
							nb ? &pb : NULL);
		if (bj <= 0)
			continue;
		double w = bj * wi.z * e->pdf_smooth /
			   (e->pdf * (nl * e->pdf_smooth + nb * pb));
		for (int ch = 0; ch < 3; ch++)
			out[ch] += w * e->l[ch];
	}
	double w_hit = sp ? 1 - sp->w : 1;
	for (int k = 0; k < nb; k++) {
		double uu[2];
		if (hs >= 0) {
			const uint32_t *q = c->lobe_sobol[hs * nb + k];
			uu[0] = (q[0] ^ shift[0]) * (1.0 / 4294967296.0);
			uu[1] = (q[1] ^ shift[1]) * (1.0 / 4294967296.0);
		} else {
			uu[0] = u[k][0] + sx;
			uu[1] = u[k][1] + sy;
			uu[0] -= uu[0] >= 1;
			uu[1] -= uu[1] >= 1;
		}
		if (w_hit > 0)
			lobe_sample(c, h, p, j, nl, nb, uu, w_hit, out);
		if (sp && sp->w > 0) {
			/* Point q of a (0, 2)-set over the pixel, shifted;
			 * the points shuffled among the samples (by index,
			 * x would follow the lobe sample's own first
			 * uniform: one slice of the pixel x lobe domain). */
			uint32_t q = glint_permute(
				(uint32_t)(k * c->spp + sp->s),
				(uint32_t)(nb * c->spp), sp->perm);
			double x = (q + 0.5) / (nb * c->spp) + sp->shift[0];
			double y = glint_radical2(q) + sp->shift[1];
			double at[2] = { x - (x >= 1) - 0.5,
					 y - (y >= 1) - 0.5 };
			struct cache_hit hq;
			if (hit_at(sp->f, at, &hq))
				lobe_sample(c, &hq, p, j, nl, nb, uu, sp->w,
					    out);
		}
	}
}

static double angle(struct vec3 a, struct vec3 b)
{
	return acos(fmin(1, fmax(-1, v3_dot(a, b) / (v3_len(a) * v3_len(b)))));
}

/*
 * Fit pixel pix's footprint to its spp hits g (least squares over their
 * positions in the pixel; glint_pixel_sample() places them as the tracer
 * did).  Fewer than 3 hits, or hits in a line: no footprint (turn 0).
 */
static void foot_fit(const struct glint_gbuffer *gb, int32_t pix,
		     const struct glint_hit *g, struct cache_foot *f)
{
	uint32_t fp = glint_gbuffer_frame_pixel(gb, (size_t)pix);
	int fw = gb->frame_width ? gb->frame_width : gb->width;
	double m[3][3] = { { 0 } }, rhs[6][3] = { { 0 } }, inv[3][3];

	memset(f, 0, sizeof(*f));
	if (gb->spp < 3)
		return;
	for (int s = 0; s < gb->spp; s++) {
		double pos[2], lens[2];
		glint_pixel_sample((int)(fp % (uint32_t)fw),
				   (int)(fp / (uint32_t)fw), s, gb->spp, pos,
				   lens);
		double b[3] = { 1, pos[0] - 0.5, pos[1] - 0.5 };
		for (int a = 0; a < 3; a++) {
			for (int e = 0; e < 3; e++)
				m[a][e] += b[a] * b[e];
			for (int k = 0; k < 3; k++) {
				rhs[k][a] += b[a] * g[s].n[k];
				rhs[3 + k][a] += b[a] * g[s].d[k];
			}
		}
	}
	double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
		     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
		     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
	if (!(fabs(det) > 1e-9 * gb->spp * gb->spp * gb->spp))
		return;
	for (int a = 0; a < 3; a++)
		for (int e = 0; e < 3; e++) {
			int a1 = (e + 1) % 3, a2 = (e + 2) % 3;
			int e1 = (a + 1) % 3, e2 = (a + 2) % 3;
			inv[a][e] = (m[a1][e1] * m[a2][e2] -
				     m[a1][e2] * m[a2][e1]) /
				    det;
		}
	float *dst[6][3] = {
		{ &f->n[0], &f->nu[0], &f->nv[0] },
		{ &f->n[1], &f->nu[1], &f->nv[1] },
		{ &f->n[2], &f->nu[2], &f->nv[2] },
		{ &f->d[0], &f->du[0], &f->dv[0] },
		{ &f->d[1], &f->du[1], &f->dv[1] },
		{ &f->d[2], &f->du[2], &f->dv[2] },
	};
	for (int k = 0; k < 6; k++)
		for (int a = 0; a < 3; a++) {
			double x = 0;
			for (int e = 0; e < 3; e++)
				x += inv[a][e] * rhs[k][e];
			*dst[k][a] = (float)x;
		}
	struct vec3 n, d, r, r0, r1;
	foot_at(f, 0, 0, &n, &d, &r);
	f->r[0] = (float)r.x;
	f->r[1] = (float)r.y;
	f->r[2] = (float)r.z;
	foot_at(f, -0.5, 0, &n, &d, &r0);
	foot_at(f, 0.5, 0, &n, &d, &r1);
	double tu = angle(r0, r1);
	foot_at(f, 0, -0.5, &n, &d, &r0);
	foot_at(f, 0, 0.5, &n, &d, &r1);
	f->turn = (float)fmax(tu, angle(r0, r1));
}

/* Lobe j's hot part, the mean over pixel i's footprint on a k x k grid;
 * only hot points within ext of a point's mirror direction count. */
static void hot_grid(const struct glint_shade_cache *c,
		     const struct cache_foot *f, const double *p, int j, int k,
		     double ext, double out[3])
{
	const struct glint_env_hot *hot = c->hot;
	const struct glint_model *m = c->model;
	double cos_ext = cos(fmin(ext, M_PI));

	out[0] = out[1] = out[2] = 0;
	for (int a = 0; a < k; a++)
		for (int e = 0; e < k; e++) {
			struct vec3 n, d, r, t, b;
			foot_at(f, (a + 0.5) / k - 0.5, (e + 0.5) / k - 0.5, &n,
				&d, &r);
			v3_frame(n, &t, &b);
			struct vec3 wo =
				v3(-v3_dot(d, t), -v3_dot(d, b), -v3_dot(d, n));
			if (!(wo.z > 0))
				continue;
			r = v3_norm(r);
			for (int q = 0; q < hot->npart; q++) {
				const float *pt = hot->part + 6 * (size_t)q;
				struct vec3 l = v3(pt[0], pt[1], pt[2]);
				if (v3_dot(l, r) < cos_ext)
					continue;
				struct vec3 wi = v3(v3_dot(l, t), v3_dot(l, b),
						    v3_dot(l, n));
				if (!(wi.z > 0))
					continue;
				double bj = glint_lobe_value_pdf(m, p, j, wo,
								 wi, NULL);
				if (bj <= 0)
					continue;
				for (int ch = 0; ch < 3; ch++)
					out[ch] += bj * wi.z * pt[3 + ch];
			}
		}
	for (int ch = 0; ch < 3; ch++)
		out[ch] /= (double)k * k;
}

/* Lobe j's hot part, the mean over pixel i's hits. */
static void hot_hits(const struct glint_shade_cache *c, int i, const double *p,
		     int j, double out[3])
{
	out[0] = out[1] = out[2] = 0;
	for (int s = 0; s < c->spp; s++) {
		double a[3] = { 0, 0, 0 };
		hot_quadrature(c, &c->hits[(size_t)i * c->spp + s], p, j, 0, a);
		for (int ch = 0; ch < 3; ch++)
			out[ch] += a[ch] / c->spp;
	}
}

/* How many times (log2) pixel i's mirror direction turns across it by
 * lobe j's width at p; -1 without a footprint. */
static double foot_level(const struct glint_shade_cache *c, int i,
			 const double *p, int j)
{
	const struct glint_model *m = c->model;
	double sd = glint_lobe_width(m, p, j);

	if (c->no_footprint || !(sd > 0) || !(c->feet[i].turn > 0))
		return -1;
	return log2(c->feet[i].turn / sd);
}

/*
 * The lobe samples are spread over the footprint (lobe_at_hit()'s
 * spread) as the lobe narrows from 2^SPREAD_FROM of the pixel's turn of
 * mirror direction to 2^(SPREAD_FROM - 1), blended between so that the
 * objective stays continuous.  Where the lobe is under about two turns
 * the highlight's profile bends within a pixel, and the hits' 2 x 2
 * points misjudge its area: aluminium bronze under studio.exr's
 * softboxes (roughness 0.023; a turn 0.7 of the lobe's width at the
 * sphere's centre, more toward the rim), at the truth
 * and 64 + 64 samples, differed from the reference photo by 2.8 times
 * the photo's own noise (squared, red), by 1.7 times spread from 2
 * turns (bench/residual; 16 hits a pixel: 1.0).  Until 2026-11-27 the
 * spreading began at one turn (SPREAD_FROM 0).
 */
#define SPREAD_FROM 1

/*
 * Lobe j's hot part over pixel i where the lobe is narrow against the
 * pixel's turn of mirror direction: a near-mirror's sun covers part of a
 * pixel, which the hits' few points alias.  The lobe is widened by the
 * spread of the hot texels' quadrature points (so that they integrate
 * the texels' area, not points of light) and integrated on a grid whose
 * cells turn by at most its width, blending two levels so that the
 * result stays continuous in the parameters.  Returns 0 (out untouched)
 * when the lobe is wide enough for the hits' own points
 * (hot_quadrature()).
 */
static int hot_footprint(const struct glint_shade_cache *c, int i,
			 const double *p, int j, double out[3])
{
	const struct cache_foot *f = &c->feet[i];
	const struct glint_model *m = c->model;
	double pw[GLINT_MAX_PARAMS];

	if (c->no_footprint || !m->lobes->microfacet || !(f->turn > 0) ||
	    !c->hot->npart)
		return 0;
	memcpy(pw, p, (size_t)m->nparams * sizeof(*p));
	glint_lobe_widen(m, pw, j, c->light->spread);
	double sd = glint_lobe_width(m, pw, j);
	double lv = sd > 0 ? log2(f->turn / sd) : 0;
	if (!(lv > 0))
		return 0;
	/* Where a lobe has no bound (GGX's tails), 40 widths hold its
	 * core; its tails there are the hits'. */
	double ext = glint_lobe_extent(m, pw, j);
	if (!(ext > 0))
		ext = 40 * sd;
	out[0] = out[1] = out[2] = 0;
	if (angle(fv(f->r), c->hot->axis) - c->hot->radius > ext + f->turn)
		return 1;
	lv = fmin(lv, 3);
	int lo = (int)lv;
	double w = lv - lo, a[3], b[3] = { 0, 0, 0 };
	if (lo)
		hot_grid(c, f, pw, j, 2 << lo, ext, a);
	else
		hot_hits(c, i, p, j, a);
	if (w > 0)
		hot_grid(c, f, pw, j, 4 << lo, ext, b);
	for (int ch = 0; ch < 3; ch++)
		out[ch] = (1 - w) * a[ch] + w * b[ch];
	return 1;
}

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
	for (int k = 0; k < nl; k++) {
		double u[2], l[3];
		struct vec3 d;
		glint_sobol2((uint32_t)(s * nl + k), seed ^ salt, u);
		double pdf =
			glint_env_dist_sample(env, &hot->rest, u[0], u[1], &d);
		struct env_sample *e = &es[k];
		struct vec3 wi = v3(v3_dot(d, fv(h->t)), v3_dot(d, fv(h->b)),
				    v3_dot(d, fv(h->n)));
		memset(e, 0, sizeof(*e));
		if (!(pdf > 0) || !(wi.z > 0))
			continue; /* contributes nothing: b = 0 below */
		glint_env_rest_lookup(env, hot, d, l);
		e->wi[0] = (float)wi.x;
		e->wi[1] = (float)wi.y;
		e->wi[2] = (float)wi.z;
		for (int ch = 0; ch < 3; ch++)
			e->l[ch] = (float)l[ch];
		e->pdf = (float)pdf;
		e->pdf_smooth =
			(float)glint_env_dist_pdf_smooth(env, &hot->rest, d);
		/* A sample whose smooth pdf vanishes must keep its weight
		 * finite: fall back to the sampling pdf. */
		if (!(e->pdf_smooth > 0))
			e->pdf_smooth = e->pdf;
		if (m->lobes->geometry)
			m->lobes->geometry(fv(h->wo), wi, e->g);
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
					hot_quadrature(c, h, job->p0, j, 1, a);
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
					lobe_at_hit(c, h, tmp, ns, ns, u,
						    job->p0, j, 1, NULL, -1, 0,
						    a);
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

/* Hot texels: within 1 % of the brightest, if at most 64 of them;
 * 2 x 2 points each (spread: half their spacing in latitude). */
int glint_shade_light_new(const struct glint_envmap *env,
			  const struct glint_shade_cache_opts *opts,
			  struct glint_shade_light **out)
{
	struct glint_shade_light *l = calloc(1, sizeof(*l));
	int ret;

	*out = NULL;
	if (!l)
		return glint_error_set(ENOMEM, "out of memory");
	ret = glint_env_hot_new(env, 0.01, opts->no_hot ? 0 : 64, 2, &l->hot);
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
	c->no_footprint = opts->no_footprint;
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
		foot_fit(gb, pix[i], glint_gbuffer_pixel(gb, (size_t)pix[i]),
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
		memcpy(dst, c->static_lobes + (size_t)i * nj * 3,
		       (size_t)nj * 3 * sizeof(double));
		for (int j = 0; j < nj; j++) {
			if (!m->lobes->varies[j])
				continue;
			double hot[3];
			int foot = hot_footprint(c, i, job->p, j, hot);
			if (foot)
				for (int ch = 0; ch < 3; ch++)
					dst[j * 3 + ch] += hot[ch];
			struct spread sp = { &c->feet[i], 0, { 0, 0 }, 0, 0 };
			sp.w = fmin(1, fmax(0, foot_level(c, i, job->p, j) +
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
				double a[3];
				sp.s = s;
				lobe_at_hit(
					c, &c->hits[hi], c->envs + hi * c->nl,
					c->nl, c->nb, NULL, job->p, j, !foot,
					sp.w > 0 ? &sp : NULL, s,
					c->hits[(size_t)i * c->spp].seed, a);
				for (int ch = 0; ch < 3; ch++)
					dst[j * 3 + ch] += a[ch] / c->spp;
			}
		}
	}
}

void glint_shade_cache_lobes(struct glint_shade_cache *c, const double *p,
			     double *lobes)
{
	struct lobes_job job = { c, p, NULL, lobes };

	glint_parallel_for(c->n, 32, c->nthreads, lobes_pixels, &job);
}

void glint_shade_cache_lobes_sel(struct glint_shade_cache *c, const double *p,
				 const int *sel, int nsel, double *lobes)
{
	struct lobes_job job = { c, p, sel, lobes };

	glint_parallel_for(nsel, 32, c->nthreads, lobes_pixels, &job);
}
