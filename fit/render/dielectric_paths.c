/* SPDX-License-Identifier: MIT */
#include "dielectric_paths.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void glint_dielectric_default_opts(struct glint_dielectric_opts *o)
{
	/* Measured (tests/unit/test_dielectric.c): against 1e-7 the image
	 * changes by under 1e-4 of its RMS. */
	o->min_weight = 1e-4;
	o->max_depth = 64;
}

/* Paths of one primary sample, appended to a growing per-thread list. */
struct plist {
	struct glint_dpath *p;
	int64_t n, cap;
	double dropped;
	int depth;
};

static int push(struct plist *l, double w, double len, const double rgb[3])
{
	if (l->n == l->cap) {
		int64_t cap = l->cap ? 2 * l->cap : 1024;
		void *q = realloc(l->p, (size_t)cap * sizeof(*l->p));
		if (!q)
			return -ENOMEM;
		l->p = q;
		l->cap = cap;
	}
	l->p[l->n++] = (struct glint_dpath){ (float)w,
					     (float)len,
					     { (float)rgb[0], (float)rgb[1],
					       (float)rgb[2] } };
	return 0;
}

struct trace_job {
	struct glint_tracer *tracer;
	const struct glint_gbuffer *gb;
	const int32_t *pix;
	const struct glint_envmap *env;
	struct vec3 centre;
	double radius, ior;
	const struct glint_dielectric_opts *o;
	struct plist *lists; /* one per chunk */
	int64_t *counts;     /* paths per pixel */
	int chunk;
	int error;
};

/* Follow a ray inside the sphere from point p (on the surface) along d,
 * with weight w and length so far len (metres). */
static int inside(struct trace_job *j, struct plist *l, struct vec3 p,
		  struct vec3 d, double w, double len, int depth)
{
	double diam = 2 * j->radius;
	while (depth < j->o->max_depth) {
		double t = 0;
		struct vec3 ng, q, n;
		/* Embree's origin is float: from a point on the surface the
		 * nearest hit can be that point again, so a hit that is not
		 * an exit (the outward normal against the ray) is skipped by
		 * retrying past it. */
		double tnear = 1e-5 * j->radius;
		int ok = 0;
		for (int tries = 0; tries < 3 && !ok; tries++) {
			int g = glint_tracer_intersect1(j->tracer, p, d, tnear,
							&t, &ng);
			if (g < 0)
				break;
			q = v3_add(p, v3_scale(d, t));
			n = v3_norm(v3_sub(q, j->centre));
			ok = v3_dot(d, n) > 0;
			tnear = t + 1e-5 * j->radius;
		}
		if (!ok) { /* grazing: the branch leaves no exit to follow */
			if (w > l->dropped)
				l->dropped = w;
			return 0;
		}
		len += t;
		depth++;
		if (depth > l->depth)
			l->depth = depth;
		/* Inside -> outside: eta = 1 / ior; the normal facing d is
		 * -n. */
		struct vec3 nf = v3_scale(n, -1);
		double ci = v3_dot(d, n), ct;
		double R = glint_fresnel_interface(ci, 1 / j->ior, &ct);
		if (R < 1) {
			struct vec3 out;
			if (glint_refract(d, nf, 1 / j->ior, &out)) {
				double rgb[3];
				glint_envmap_lookup(j->env, out, rgb);
				if (push(l, w * (1 - R), len / diam, rgb) < 0)
					return -ENOMEM;
			}
		}
		w *= R;
		if (w < j->o->min_weight) {
			if (w > l->dropped)
				l->dropped = w;
			return 0;
		}
		d = glint_reflect(d, nf);
		p = q;
	}
	if (w > l->dropped)
		l->dropped = w;
	return 0;
}

static int trace_sample(struct trace_job *j, struct plist *l,
			const struct glint_hit *h, double w)
{
	struct vec3 d = v3(h->d[0], h->d[1], h->d[2]);
	double rgb[3];
	if (h->geom < 0) {
		glint_envmap_lookup(j->env, d, rgb);
		return push(l, w, 0, rgb);
	}
	struct vec3 p = v3(h->p[0], h->p[1], h->p[2]);
	struct vec3 n = v3_norm(v3_sub(p, j->centre));
	/* Snap the hit onto the sphere in double. */
	p = v3_add(j->centre, v3_scale(n, j->radius));
	double ci = -v3_dot(d, n), ct;
	double R = glint_fresnel_interface(ci, j->ior, &ct);
	glint_envmap_lookup(j->env, glint_reflect(d, n), rgb);
	if (push(l, w * R, 0, rgb) < 0)
		return -ENOMEM;
	struct vec3 t;
	if (w * (1 - R) < j->o->min_weight || !glint_refract(d, n, j->ior, &t))
		return 0;
	return inside(j, l, p, t, w * (1 - R), 0, 1);
}

static void trace_rows(void *ctx, int lo, int hi, int thread)
{
	struct trace_job *j = ctx;
	struct plist *l = &j->lists[lo / j->chunk];
	int spp = j->gb->spp;

	(void)thread;
	glint_thread_ftz();
	for (int i = lo; i < hi && !j->error; i++) {
		int64_t before = l->n;
		const struct glint_hit *h =
			glint_gbuffer_pixel(j->gb, (size_t)j->pix[i]);
		if (!h) { /* not kept: the caller's mistake */
			j->error = EINVAL;
			return;
		}
		for (int s = 0; s < spp; s++)
			if (trace_sample(j, l, h + s, 1.0 / spp) < 0) {
				j->error = ENOMEM;
				return;
			}
		j->counts[i] = l->n - before;
	}
}

int glint_dielectric_trace(struct glint_tracer *tracer,
			   const struct glint_gbuffer *gb, const int32_t *pix,
			   int n, const struct glint_envmap *env,
			   struct vec3 centre, double radius, double ior,
			   const struct glint_dielectric_opts *o, int nthreads,
			   struct glint_dielectric_cache *out)
{
	struct glint_dielectric_opts def;
	int chunk = 64, nchunks = (n + chunk - 1) / chunk;
	int ret = 0;

	memset(out, 0, sizeof(*out));
	if (!o) {
		glint_dielectric_default_opts(&def);
		o = &def;
	}
	if (!(ior > 1 && ior < 10))
		return glint_error_set(
			EINVAL, "dielectric: ior %g: expected (1, 10)", ior);
	struct trace_job j = { tracer, gb, pix,	 env,  centre, radius,
			       ior,    o,  NULL, NULL, chunk,  0 };
	j.lists = calloc((size_t)(nchunks ? nchunks : 1), sizeof(*j.lists));
	j.counts = calloc((size_t)(n ? n : 1), sizeof(*j.counts));
	out->pix = malloc((size_t)(n ? n : 1) * sizeof(int32_t));
	out->first = malloc((size_t)(n + 1) * sizeof(int64_t));
	if (!j.lists || !j.counts || !out->pix || !out->first) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto done;
	}
	glint_parallel_for(n, chunk, nthreads, trace_rows, &j);
	if (j.error) {
		ret = j.error == EINVAL
			      ? glint_error_set(EINVAL,
						"dielectric: a pixel's primary "
						"hits are not held by the "
						"G-buffer")
			      : glint_error_set(ENOMEM, "out of memory");
		goto done;
	}
	/* Chunks are contiguous pixel ranges: concatenate in order. */
	int64_t total = 0;
	for (int c = 0; c < nchunks; c++)
		total += j.lists[c].n;
	out->paths = malloc((size_t)(total ? total : 1) * sizeof(*out->paths));
	if (!out->paths) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto done;
	}
	int64_t k = 0;
	for (int c = 0; c < nchunks; c++) {
		memcpy(out->paths + k, j.lists[c].p,
		       (size_t)j.lists[c].n * sizeof(*out->paths));
		k += j.lists[c].n;
		if (j.lists[c].dropped > out->dropped)
			out->dropped = j.lists[c].dropped;
		if (j.lists[c].depth > out->max_depth_seen)
			out->max_depth_seen = j.lists[c].depth;
	}
	out->first[0] = 0;
	for (int i = 0; i < n; i++)
		out->first[i + 1] = out->first[i] + j.counts[i];
	memcpy(out->pix, pix, (size_t)n * sizeof(int32_t));
	out->n = n;
	out->npaths = total;
	out->ior = ior;
done:
	for (int c = 0; j.lists && c < nchunks; c++)
		free(j.lists[c].p);
	free(j.lists);
	free(j.counts);
	if (ret < 0)
		glint_dielectric_cache_free(out);
	return ret;
}

void glint_dielectric_cache_free(struct glint_dielectric_cache *c)
{
	free(c->pix);
	free(c->first);
	free(c->paths);
	memset(c, 0, sizeof(*c));
}

void glint_dielectric_shade(const struct glint_dielectric_cache *c,
			    const double T[3], double *rgb)
{
	double lt[3];
	for (int ch = 0; ch < 3; ch++)
		lt[ch] = log(fmax(T[ch], 1e-300));
	for (int i = 0; i < c->n; i++) {
		double s[3] = { 0, 0, 0 };
		for (int64_t k = c->first[i]; k < c->first[i + 1]; k++) {
			const struct glint_dpath *p = &c->paths[k];
			for (int ch = 0; ch < 3; ch++)
				s[ch] += p->w * exp(lt[ch] * p->len) *
					 p->rgb[ch];
		}
		for (int ch = 0; ch < 3; ch++)
			rgb[3 * i + ch] = s[ch];
	}
}

void glint_dielectric_dshade(const struct glint_dielectric_cache *c,
			     const double T[3], double *drgb)
{
	for (int i = 0; i < c->n; i++) {
		double s[3] = { 0, 0, 0 };
		for (int64_t k = c->first[i]; k < c->first[i + 1]; k++) {
			const struct glint_dpath *p = &c->paths[k];
			if (p->len <= 0)
				continue;
			for (int ch = 0; ch < 3; ch++)
				s[ch] += p->w * p->len *
					 pow(fmax(T[ch], 1e-12), p->len - 1) *
					 p->rgb[ch];
		}
		for (int ch = 0; ch < 3; ch++)
			drgb[3 * i + ch] = s[ch];
	}
}

int glint_dielectric_render(struct glint_tracer *tracer,
			    const struct glint_gbuffer *gb,
			    const struct glint_envmap *env, struct vec3 centre,
			    double radius, const double *p, int nthreads,
			    struct glint_image *out, struct glint_image *cov)
{
	int n = gb->width * gb->height;
	int32_t *pix = calloc((size_t)n, sizeof(int32_t));
	double *rgb = calloc((size_t)n * 3, sizeof(double));
	struct glint_dielectric_cache c;
	int ret = 0;

	if (!pix || !rgb) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	for (int i = 0; i < n; i++)
		pix[i] = i;
	ret = glint_dielectric_trace(tracer, gb, pix, n, env, centre, radius,
				     p[3], NULL, nthreads, &c);
	if (ret < 0)
		goto out;
	glint_dielectric_shade(&c, p, rgb);
	glint_dielectric_cache_free(&c);
	for (int i = 0; i < n; i++) {
		int hits = gb->cover[i];
		for (int ch = 0; ch < 3; ch++) {
			out->data[3 * (size_t)i + ch] = (float)rgb[3 * i + ch];
			if (cov)
				cov->data[3 * (size_t)i + ch] =
					(float)hits / gb->spp;
		}
	}
out:
	free(pix);
	free(rgb);
	return ret;
}
