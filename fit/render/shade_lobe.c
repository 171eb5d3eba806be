/* SPDX-License-Identifier: MIT */
/*
 * One lobe's estimate at a hit of the shade cache: the hot texels'
 * quadrature, env and lobe samples weighed against each other, and where
 * the lobe is narrow against a pixel, its samples spread over the pixel's
 * footprint or the hot part integrated over it (shade_cache_internal.h).
 */
#include "shade_cache_internal.h"

#include "sampling.h"

#include <math.h>
#include <string.h>

/* Lobe j at one point (frame t, b, n; view wo, local) over the hot
 * points pts[k0 .. k1), each radiance x solid angle, added to out (and
 * its derivative by the model's factor parameter to dout, unless NULL);
 * only the points whose cosine to r is at least cos_ext count.  The
 * points go in blocks: their lobe values in one call a block
 * (glint_lobe_values(), a loop that vectorises), then summed in order. */
static void hot_points(const struct glint_model *m, const double *p, int j,
		       const float *pts, int k0, int k1, double cos_ext,
		       struct vec3 r, struct vec3 t, struct vec3 b,
		       struct vec3 n, struct vec3 wo, double out[3],
		       double *dout)
{
	enum { BLOCK = 64 };
	double x[BLOCK], y[BLOCK], z[BLOCK], bj[BLOCK], dl[BLOCK];
	int idx[BLOCK];

	for (int k = k0; k < k1;) {
		int nk = 0;
		for (; k < k1 && nk < BLOCK; k++) {
			const float *pt = pts + 6 * (size_t)k;
			struct vec3 l = v3(pt[0], pt[1], pt[2]);
			if (cos_ext > -1 && v3_dot(l, r) < cos_ext)
				continue;
			x[nk] = v3_dot(l, t);
			y[nk] = v3_dot(l, b);
			z[nk] = v3_dot(l, n);
			idx[nk++] = k;
		}
		glint_lobe_values(m, p, j, wo, nk, x, y, z, bj,
				  dout ? dl : NULL);
		for (int i = 0; i < nk; i++) {
			if (!(z[i] > 0) || bj[i] <= 0)
				continue;
			const float *rad = pts + 6 * (size_t)idx[i] + 3;
			for (int ch = 0; ch < 3; ch++)
				out[ch] += bj[i] * z[i] * rad[ch];
			if (dout)
				for (int ch = 0; ch < 3; ch++)
					dout[ch] +=
						bj[i] * dl[i] * z[i] * rad[ch];
		}
	}
}

/* Lobe j over the hot texels, on their fixed points: the map's
 * radiance on the hot texels' area (by_area: with the irradiance of the
 * other texels) or the hot texels' part of the radiance wherever it
 * reaches (with lobe and env samples of the rest: envmap.h). */
void shade_hot_quadrature(const struct glint_shade_cache *c,
			  const struct cache_hit *h, const double *p, int j,
			  int by_area, double out[3], double *dout)
{
	const struct glint_env_hot *hot = c->hot;
	const struct glint_model *m = c->model;
	struct vec3 wo = fv(h->wo);
	/* A lobe at least HOT_COARSE_TEXELS texels wide takes the hot part
	 * on one point a texel (fewer points), widened by the
	 * spread those points leave out (the cluster's coarse_s): the same
	 * flux and second moment, the error of fourth order in texel /
	 * width (unit test hot_coarse) */
	int coarse = !by_area && hot->ncoarse &&
		     glint_lobe_width(m, p, j) >=
			     HOT_COARSE_TEXELS * M_PI / hot->env->img->height;
	int npts = by_area ? hot->npts : coarse ? hot->ncoarse : hot->npart;
	const float *pts = by_area  ? hot->pts
			   : coarse ? hot->coarse
				    : hot->part;
	struct vec3 r = v3(0, 0, 0);

	if (!npts)
		return;
	double ext = glint_lobe_extent(m, p, j);
	if (ext > 0) {
		r = local_to_world(h, v3(-wo.x, -wo.y, wo.z));
		if (angle_fast(r, hot->axis) - hot->radius > ext)
			return;
	}
	for (int g = 0; g < hot->nclusters; g++) {
		const struct glint_env_hot_cluster *cl = &hot->clusters[g];
		double pw[GLINT_MAX_PARAMS];
		if (ext > 0 && angle_fast(r, cl->axis) - cl->radius > ext)
			continue; /* the lobe is below 1e-12 of it */
		if (coarse) {
			memcpy(pw, p, sizeof(double) * (size_t)m->nparams);
			glint_lobe_widen(m, pw, j, cl->coarse_s);
		}
		hot_points(m, coarse ? pw : p, j, pts,
			   by_area  ? cl->pts0
			   : coarse ? cl->coarse0
				    : cl->part0,
			   by_area  ? cl->pts1
			   : coarse ? cl->coarse1
				    : cl->part1,
			   -2, r, fv(h->t), fv(h->b), fv(h->n), wo, out, dout);
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

/* A lobe sample's light, read from its query q, weighted by the balance
 * heuristic against nl env samples (lobe value x cosine bjz, pdf pb) and
 * by w, added to out (its derivative by the factor parameter, dlog
 * times it, to dout unless NULL). */
static void lobe_sample_light(const struct glint_shade_cache *c, int nl, int nb,
			      const struct glint_env_query *q, double bjz,
			      double pb, double w, double dlog, double out[3],
			      double *dout)
{
	double l[3], ps = 0;

	/* the rest's radiance, continuous across the hot texels' edges
	 * (their part is shade_hot_quadrature()'s) */
	glint_env_query_finish(c->hot, q, l, &ps);
	if (!nl)
		ps = 0;
	double wt = w * (bjz / (nl * ps + nb * pb));
	for (int ch = 0; ch < 3; ch++)
		out[ch] += wt * l[ch];
	if (dout)
		for (int ch = 0; ch < 3; ch++)
			dout[ch] += wt * dlog * l[ch];
}

/* Lobe samples waiting to be taken together: sample k's uniforms (u0,
 * u1), its hit and its weight; a spread sample's hit kept in own[]. */
enum { LOBE_BLOCK = 8 };
struct lobe_block {
	int n;
	double u0[LOBE_BLOCK], u1[LOBE_BLOCK], w[LOBE_BLOCK];
	const struct cache_hit *hit[LOBE_BLOCK];
	struct cache_hit own[LOBE_BLOCK];
};

/* The block's samples, each weighted by the balance heuristic against nl
 * env samples and by its w, added to out: their directions in one call,
 * their map coordinates in another (loops that vectorise), their table
 * reads overlapping; summed in the order they joined. */
static void lobe_block_run(const struct glint_shade_cache *c,
			   struct lobe_block *lb, const double *p, int j,
			   int nl, int nb, double out[3], double *dout)
{
	double x[LOBE_BLOCK], y[LOBE_BLOCK], z[LOBE_BLOCK], pb[LOBE_BLOCK];
	double bj[LOBE_BLOCK], dl[LOBE_BLOCK];
	double dx[LOBE_BLOCK], dy[LOBE_BLOCK], dz[LOBE_BLOCK];
	/* initialised: the sanitizer build's GCC cannot see that n >= 1 */
	struct vec3 wo[LOBE_BLOCK] = { { 0, 0, 0 } };
	struct glint_env_query q[LOBE_BLOCK];
	int n = lb->n;

	for (int k = 0; k < n; k++)
		wo[k] = fv(lb->hit[k]->wo);
	glint_lobe_sample_values(c->model, p, j, n, wo, lb->u0, lb->u1, x, y, z,
				 pb, bj, dout ? dl : NULL);
	for (int k = 0; k < n; k++) {
		struct vec3 d =
			local_to_world(lb->hit[k], v3(x[k], y[k], z[k]));
		dx[k] = d.x, dy[k] = d.y, dz[k] = d.z;
	}
	glint_env_query_start_n(c->hot, n, dx, dy, dz, q);
	for (int k = 0; k < n; k++)
		if (pb[k] > 0 && bj[k] > 0)
			lobe_sample_light(c, nl, nb, &q[k], bj[k] * z[k], pb[k],
					  lb->w[k], dout ? dl[k] : 0, out,
					  dout);
	lb->n = 0;
}

/* Sample uu at hit h (NULL: the one just made in lb->own[lb->n]) with
 * weight w joins the block, which runs once full. */
static void lobe_block_add(const struct glint_shade_cache *c,
			   struct lobe_block *lb, const struct cache_hit *h,
			   const double uu[2], double w, const double *p, int j,
			   int nl, int nb, double out[3], double *dout)
{
	int k = lb->n++;

	lb->u0[k] = uu[0];
	lb->u1[k] = uu[1];
	lb->w[k] = w;
	lb->hit[k] = h ? h : &lb->own[k];
	if (lb->n == LOBE_BLOCK)
		lobe_block_run(c, lb, p, j, nl, nb, out, dout);
}

/*
 * Estimate lobe j's integral at one hit: nl env samples, nb lobe samples,
 * balance-heuristic weights with the smooth light pdf.  The lobe samples'
 * uniforms: for hit hs >= 0 of its pixel, block hs of a Sobol sequence
 * shifted by the pixel's seed pseed (as draw_env_samples()); for hs < 0
 * (constant lobes at set-up), the pairs u[k] shifted by the hit's seed.
 * env samples come from `es`, or are drawn afresh when es is NULL.
 */
void shade_lobe_at_hit(const struct glint_shade_cache *c,
		       const struct cache_hit *h, const struct env_sample *es,
		       int nl, int nb, const double (*u)[2], const double *p,
		       int j, int with_hot, const struct spread *sp, int hs,
		       uint32_t pseed, double out[3], double *dout)
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
	if (dout)
		dout[0] = dout[1] = dout[2] = 0;
	if (with_hot)
		shade_hot_quadrature(c, h, p, j, 0, out, dout);
	for (int k = 0; k < nl; k++) {
		const struct env_sample *e = &es[k];
		struct vec3 wi = fv(e->wi);
		double pb = 0, dlog = 0;
		double *dl = dout ? &dlog : NULL;
		double bj = geom ? m->lobes->from_geometry(p, j, e->g,
							   nb ? &pb : NULL, dl)
				 : glint_lobe_value_pdf(m, p, j, wo, wi,
							nb ? &pb : NULL, dl);
		if (bj <= 0)
			continue;
		double w = bj * wi.z * e->pdf_smooth /
			   (e->pdf * (nl * e->pdf_smooth + nb * pb));
		for (int ch = 0; ch < 3; ch++)
			out[ch] += w * e->l[ch];
		if (dout)
			for (int ch = 0; ch < 3; ch++)
				dout[ch] += w * dlog * e->l[ch];
	}
	double w_hit = sp ? 1 - sp->w : 1;
	int spread = sp && sp->w > 0;
	struct lobe_block lb;
	lb.n = 0;
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
		/* the hit's own sample, then (spread) one at point q of a
		 * (0, 2)-set over the pixel, shifted; the points shuffled
		 * among the samples (by index, x would follow the lobe
		 * sample's own first uniform: one slice of the pixel x lobe
		 * domain) */
		if (w_hit > 0)
			lobe_block_add(c, &lb, h, uu, w_hit, p, j, nl, nb, out,
				       dout);
		if (!spread)
			continue;
		uint32_t q = glint_permute((uint32_t)(k * c->spp + sp->s),
					   (uint32_t)(nb * c->spp), sp->perm);
		double x = (q + 0.5) / (nb * c->spp) + sp->shift[0];
		double y = glint_radical2(q) + sp->shift[1];
		double at[2] = { x - (x >= 1) - 0.5, y - (y >= 1) - 0.5 };
		if (hit_at(sp->f, at, &lb.own[lb.n]))
			lobe_block_add(c, &lb, NULL, uu, sp->w, p, j, nl, nb,
				       out, dout);
	}
	if (lb.n)
		lobe_block_run(c, &lb, p, j, nl, nb, out, dout);
}

/*
 * Fit pixel pix's footprint to its spp hits g (least squares over their
 * positions in the pixel; glint_gbuffer_pixel_sample() places them as the
 * tracer did).  Fewer than 3 hits, or hits in a line: no footprint (turn 0).
 */
void shade_foot_fit(const struct glint_gbuffer *gb, int32_t pix,
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
		glint_gbuffer_pixel_sample(gb, (int)(fp % (uint32_t)fw),
					   (int)(fp / (uint32_t)fw), s, pos,
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
 * only hot points within ext of a point's mirror direction count, of
 * the clusters near[0 .. ncl) (those within reach of the footprint's
 * mirror directions; near NULL: all of them). */
static void hot_grid(const struct glint_shade_cache *c,
		     const struct cache_foot *f, const double *p, int j, int k,
		     double ext, const int *near, int ncl, double out[3],
		     double *dout)
{
	const struct glint_env_hot *hot = c->hot;
	const struct glint_model *m = c->model;
	double cos_ext = cos(fmin(ext, M_PI));

	out[0] = out[1] = out[2] = 0;
	if (dout)
		dout[0] = dout[1] = dout[2] = 0;
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
			for (int g = 0; g < ncl; g++) {
				const struct glint_env_hot_cluster *cl =
					&hot->clusters[near ? near[g] : g];
				hot_points(m, p, j, hot->part, cl->part0,
					   cl->part1, cos_ext, r, t, b, n, wo,
					   out, dout);
			}
		}
	for (int ch = 0; ch < 3; ch++) {
		out[ch] /= (double)k * k;
		if (dout)
			dout[ch] /= (double)k * k;
	}
}

/* Lobe j's hot part, the mean over pixel i's hits. */
static void hot_hits(const struct glint_shade_cache *c, int i, const double *p,
		     int j, double out[3], double *dout)
{
	out[0] = out[1] = out[2] = 0;
	if (dout)
		dout[0] = dout[1] = dout[2] = 0;
	for (int s = 0; s < c->spp; s++) {
		double a[3] = { 0, 0, 0 }, da[3] = { 0, 0, 0 };
		shade_hot_quadrature(c, &c->hits[(size_t)i * c->spp + s], p, j,
				     0, a, dout ? da : NULL);
		for (int ch = 0; ch < 3; ch++) {
			out[ch] += a[ch] / c->spp;
			if (dout)
				dout[ch] += da[ch] / c->spp;
		}
	}
}

/* How many times (log2) pixel i's mirror direction turns across it by
 * lobe j's width at p; -1 without a footprint. */
double shade_foot_level(const struct glint_shade_cache *c, int i,
			const double *p, int j)
{
	const struct glint_model *m = c->model;
	double sd = glint_lobe_width(m, p, j);

	if (c->no_footprint || !(sd > 0) || !(c->feet[i].turn > 0))
		return -1;
	return log2(c->feet[i].turn / sd);
}

/*
 * Lobe j's hot part over pixel i where the lobe is narrow against the
 * pixel's turn of mirror direction: a near-mirror's sun covers part of a
 * pixel, which the hits' few points alias.  The lobe is widened by the
 * spread of the hot texels' quadrature points (so that they integrate
 * the texels' area, not points of light) and integrated on a grid whose
 * cells turn by at most its width, blending two levels so that the
 * result stays continuous in the parameters.  Returns 0 (out untouched)
 * when the lobe is wide enough for the hits' own points
 * (shade_hot_quadrature()).
 */
int shade_hot_footprint(const struct glint_shade_cache *c, int i,
			const double *p, const double *pf, int j, double out[3],
			double *dout)
{
	const struct cache_foot *f = &c->feet[i];
	const struct glint_model *m = c->model;
	double pw[GLINT_MAX_PARAMS], pwf[GLINT_MAX_PARAMS];

	if (c->no_footprint || !m->lobes->microfacet || !(f->turn > 0) ||
	    !c->hot->npart)
		return 0;
	memcpy(pw, p, (size_t)m->nparams * sizeof(*p));
	glint_lobe_widen(m, pw, j, c->light->spread);
	if (pf != p) { /* the blend fixed elsewhere */
		memcpy(pwf, pf, (size_t)m->nparams * sizeof(*pf));
		glint_lobe_widen(m, pwf, j, c->light->spread);
	}
	double sd = glint_lobe_width(m, pf != p ? pwf : pw, j);
	double lv = sd > 0 ? log2(f->turn / sd) : 0;
	if (!(lv > 0))
		return 0;
	/* Where a lobe has no bound (GGX's tails), 40 widths hold its
	 * core; its tails there are the hits'. */
	double ext = glint_lobe_extent(m, pw, j);
	if (!(ext > 0))
		ext = 40 * sd;
	out[0] = out[1] = out[2] = 0;
	if (dout)
		dout[0] = dout[1] = dout[2] = 0;
	const struct glint_env_hot *hot = c->hot;
	if (angle_fast(fv(f->r), hot->axis) - hot->radius > ext + f->turn)
		return 1;
	/* The clusters within reach of any of the footprint's mirror
	 * directions (each within f->turn of the centre's). */
	int near_buf[64], *near = near_buf, ncl = 0;
	for (int g = 0; g < hot->nclusters && near; g++) {
		const struct glint_env_hot_cluster *cl = &hot->clusters[g];
		if (angle_fast(fv(f->r), cl->axis) - cl->radius > ext + f->turn)
			continue;
		if (ncl == 64) /* many within reach: visit them all */
			near = NULL;
		else
			near[ncl++] = g;
	}
	if (!near)
		ncl = hot->nclusters;
	lv = fmin(lv, 3);
	int lo = (int)lv;
	double w = lv - lo, a[3], b[3] = { 0, 0, 0 };
	double da[3] = { 0, 0, 0 }, db[3] = { 0, 0, 0 };
	if (lo)
		hot_grid(c, f, pw, j, 2 << lo, ext, near, ncl, a,
			 dout ? da : NULL);
	else
		hot_hits(c, i, p, j, a, dout ? da : NULL);
	if (w > 0)
		hot_grid(c, f, pw, j, 4 << lo, ext, near, ncl, b,
			 dout ? db : NULL);
	for (int ch = 0; ch < 3; ch++) {
		out[ch] = (1 - w) * a[ch] + w * b[ch];
		if (dout)
			dout[ch] = (1 - w) * da[ch] + w * db[ch];
	}
	return 1;
}
