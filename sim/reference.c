/* SPDX-License-Identifier: MIT */
#include "reference.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void glint_reference_default_opts(struct glint_reference_opts *o)
{
	o->spp = 8;
	o->samples = 128;
	o->seed = 1;
	o->nthreads = 0;
	o->rel_noise = 0;
	o->max_rounds = 16;
	o->rounds = NULL;
}

/* xoshiro128+ (Blackman & Vigna): small, fast, independent streams. */
struct rng {
	uint32_t s[4];
};

static uint32_t rotl(uint32_t x, int k)
{
	return (x << k) | (x >> (32 - k));
}

static double rng_u01(struct rng *r)
{
	uint32_t res = r->s[0] + r->s[3], t = r->s[1] << 9;
	r->s[2] ^= r->s[0];
	r->s[3] ^= r->s[1];
	r->s[1] ^= r->s[2];
	r->s[0] ^= r->s[3];
	r->s[2] ^= t;
	r->s[3] = rotl(r->s[3], 11);
	return (res >> 8) * (1.0 / 16777216.0);
}

static void rng_seed(struct rng *r, uint64_t seed)
{
	/* splitmix64 to fill the state */
	for (int i = 0; i < 4; i++) {
		uint64_t z = (seed += 0x9e3779b97f4a7c15ull);
		z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
		z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
		r->s[i] = (uint32_t)((z ^ (z >> 31)) >> 16);
	}
}

struct ref_job {
	const struct glint_scene *sc;
	const struct glint_envmap *env;
	const struct glint_model *m; /* the transparent sphere's, or NULL */
	const double *p;
	struct glint_bxdf bx; /* an opaque sphere's */
	const struct glint_reference_opts *o;
	struct glint_image *out;
	int failed;  /* a thread ran out of memory */
	long rounds; /* of spp primary samples, over every pixel */
};

/* Nearest hit of a ray with the sphere, double precision; -1 if none. */
static double hit_sphere(struct vec3 o, struct vec3 d, struct vec3 c, double r)
{
	struct vec3 oc = v3_sub(o, c);
	double b = v3_dot(oc, d), cc = v3_dot(oc, oc) - r * r;
	double disc = b * b - cc;
	if (disc < 0)
		return -1;
	double t = -b - sqrt(disc);
	return t > 0 ? t : -1;
}

/* shade()'s samples in batches of this many (shade_batch()). */
enum { REF_BATCH = 16 };

static int imin(int a, int b)
{
	return a < b ? a : b;
}

/* One of shade()'s samples between drawing its direction and reading its
 * light. */
struct ref_pending {
	struct vec3 wi;
	struct glint_envmap_loc q;
	double pl, pb; /* light's and lobe's pdfs (pl: an env sample's; a
			* lobe sample's is read with its light) */
};

/* A batch of shade()'s samples of lobe j, k in [k0, k1) (every one of one
 * technique): their uniforms drawn in order, their directions, then their
 * light, so that their table reads overlap; the same sums in the same
 * order as one at a time. */
static void shade_batch(const struct ref_job *job, int j, int k0, int k1,
			struct vec3 t, struct vec3 b, struct vec3 n,
			struct vec3 wo, struct rng *rng, double rgb[3])
{
	const struct glint_bxdf_ops *ops = job->bx.ops;
	const void *self = job->bx.self;
	const double *alb = ops->albedo(self, j);
	int ns = job->o->samples, m = k1 - k0, env = k0 < ns, np = 0;
	double u1[REF_BATCH], u2[REF_BATCH], pl[REF_BATCH];
	double lobes[GLINT_MAX_PARAMS];
	struct vec3 ww[REF_BATCH];
	struct ref_pending pend[REF_BATCH];

	for (int e = 0; e < m; e++) {
		/* env-map samples on jittered strata; lobe samples free */
		u1[e] = env ? (k0 + e + rng_u01(rng)) / ns : rng_u01(rng);
		u2[e] = rng_u01(rng);
	}
	if (env)
		glint_envmap_sample_n(job->env, m, u1, u2, ww, pl);
	for (int e = 0; e < m; e++) {
		struct ref_pending *q = &pend[np];
		if (env) {
			q->wi = v3(v3_dot(ww[e], t), v3_dot(ww[e], b),
				   v3_dot(ww[e], n));
			if (!(pl[e] > 0) || !(q->wi.z > 0))
				continue;
			q->pl = pl[e];
			q->pb = ops->pdf_lobe(self, j, wo, q->wi);
		} else {
			double u[2] = { u1[e], u2[e] };
			q->pb = ops->sample_lobe(self, j, wo, u, &q->wi);
			if (!(q->pb > 0))
				continue;
			ww[e] = v3_add(v3_add(v3_scale(t, q->wi.x),
					      v3_scale(b, q->wi.y)),
				       v3_scale(n, q->wi.z));
		}
		glint_envmap_locate(job->env, ww[e], &q->q);
		np++;
	}
	for (int e = 0; e < np; e++) {
		const struct ref_pending *q = &pend[e];
		double l[3],
			p_l = env ? q->pl
				  : glint_envmap_located_pdf(job->env, &q->q);
		double bj;
		if (ops->eval_lobe) {
			bj = ops->eval_lobe(self, j, wo, q->wi);
		} else {
			ops->eval_lobes(self, wo, q->wi, lobes);
			bj = lobes[j];
		}
		if (bj <= 0)
			continue;
		/* Power heuristic, one sample of ns per technique. */
		double pk = env ? p_l : q->pb, po = env ? q->pb : p_l;
		double w = pk * pk / (pk * pk + po * po);
		glint_envmap_located_lookup(job->env, &q->q, l);
		for (int c = 0; c < 3; c++)
			rgb[c] += alb[c] * bj * l[c] * q->wi.z * w / (pk * ns);
	}
}

static void shade(const struct ref_job *job, struct vec3 pos, struct vec3 d,
		  struct rng *rng, double rgb[3])
{
	int ns = job->o->samples;
	struct vec3 n = v3_norm(v3_sub(pos, job->sc->sphere_centre)), t, b;

	v3_frame(n, &t, &b);
	struct vec3 wo = v3(-v3_dot(d, t), -v3_dot(d, b), -v3_dot(d, n));
	rgb[0] = rgb[1] = rgb[2] = 0;
	for (int j = 0; j < job->bx.ops->nlobes; j++) {
		for (int k = 0; k < ns; k += REF_BATCH) /* env-map samples */
			shade_batch(job, j, k, imin(k + REF_BATCH, ns), t, b, n,
				    wo, rng, rgb);
		for (int k = ns; k < 2 * ns; k += REF_BATCH) /* lobe samples */
			shade_batch(job, j, k, imin(k + REF_BATCH, 2 * ns), t,
				    b, n, wo, rng, rgb);
	}
}

/* Fresnel reflectance in its angle form (Rs = sin^2(i - t) / sin^2(i + t),
 * Rp = tan^2(i - t) / tan^2(i + t)), written independently of
 * fit/render/dielectric_paths.c's coefficient form.  n1 -> n2; sets *tt (angle
 * of refraction), returns 1 on total internal reflection. */
static double fresnel_angles(double ti, double n1, double n2, double *tt)
{
	double st = n1 / n2 * sin(ti);
	if (st >= 1) {
		*tt = M_PI / 2;
		return 1;
	}
	*tt = asin(st);
	if (ti < 1e-6) {
		double r = (n1 - n2) / (n1 + n2);
		return r * r;
	}
	double a = sin(ti - *tt) / sin(ti + *tt);
	double b = tan(ti - *tt) / tan(ti + *tt);
	return 0.5 * (a * a + b * b);
}

/* A transparent sphere, stochastically: the first interface is split (its
 * reflection, the sharpest and brightest part, is added with weight R and
 * the path goes on refracted with 1 - R); inside, each interface reflects
 * with probability R, else refracts (unbiased); absorption by
 * Beer-Lambert; the path ends in the env map when it leaves. */
static void shade_dielectric(const struct ref_job *job, struct vec3 pos,
			     struct vec3 d, struct rng *rng, double rgb[3])
{
	const double *T = job->p;
	double ior = job->p[3], diam = 2 * job->sc->sphere_radius;
	double thr[3] = { 1, 1, 1 }, acc[3] = { 0, 0, 0 };
	int in = 0;
	struct vec3 c = job->sc->sphere_centre;

	for (int depth = 0; depth < 200; depth++) {
		struct vec3 n = v3_norm(v3_sub(pos, c)); /* outward */
		if (in)
			n = v3_scale(n, -1); /* facing the ray */
		double cos_i = -v3_dot(d, n), tt;
		double n1 = in ? ior : 1, n2 = in ? 1 : ior;
		double R = fresnel_angles(acos(fmin(1, cos_i)), n1, n2, &tt);
		if (depth == 0) {
			struct vec3 rd =
				v3_sub(d, v3_scale(n, 2 * v3_dot(d, n)));
			double l[3];
			glint_envmap_lookup(job->env, rd, l);
			for (int k = 0; k < 3; k++)
				acc[k] = R * l[k];
			if (R >= 1) {
				memcpy(rgb, acc, sizeof(acc));
				return;
			}
			for (int k = 0; k < 3; k++)
				thr[k] = 1 - R;
			R = 0; /* the refracted part goes on */
		}
		if (rng_u01(rng) < R) {
			d = v3_sub(d, v3_scale(n, 2 * v3_dot(d, n)));
		} else {
			/* tangential part scales by n1 / n2, the normal part
			 * follows from unit length */
			struct vec3 dt = v3_add(d, v3_scale(n, cos_i));
			struct vec3 tv = v3_scale(dt, n1 / n2);
			double nn = sqrt(fmax(0, 1 - v3_dot(tv, tv)));
			d = v3_norm(v3_sub(tv, v3_scale(n, nn)));
			in = !in;
		}
		if (!in) {
			glint_envmap_lookup(job->env, d, rgb);
			for (int k = 0; k < 3; k++)
				rgb[k] = acc[k] + rgb[k] * thr[k];
			return;
		}
		/* Across the sphere to the far side: the chord. */
		struct vec3 oc = v3_sub(pos, c);
		double b = v3_dot(oc, d);
		double cc = v3_dot(oc, oc) -
			    job->sc->sphere_radius * job->sc->sphere_radius;
		double len = -b + sqrt(fmax(0, b * b - cc));
		for (int k = 0; k < 3; k++)
			thr[k] *= pow(fmax(T[k], 1e-300), len / diam);
		pos = v3_add(pos, v3_scale(d, len));
	}
	memcpy(rgb, acc, sizeof(acc));
}

/*
 * Sample s of spp's position in its pixel, stratified: a k x k grid of
 * jittered cells when spp = k^2, else spp strata in each axis with the
 * rows' order shuffled (Latin hypercube; perm holds that order).  A
 * near-mirror's sun covers part of a pixel: 64 independent positions put
 * a highlight pixel's value 15-25 % from its integral (copper under
 * Venice), the strata 1-4 %.
 */
static void pixel_position(int s, int spp, int k, const int *perm,
			   struct rng *rng, double *px, double *py)
{
	double jx = rng_u01(rng), jy = rng_u01(rng);

	if (k * k == spp) {
		*px = (s % k + jx) / k;
		*py = (s / k + jy) / k;
	} else {
		*px = (s + jx) / spp;
		*py = (perm[s] + jy) / spp;
	}
}

/* One round of spp primary samples of pixel (x, y), added to sum; the
 * sum of their mean-over-channels and its square into s1, s2. */
static void pixel_round(const struct ref_job *job, int x, int y, int *perm,
			struct rng *rng, double sum[3], double *s1, double *s2)
{
	const struct glint_pinhole *cam = &job->sc->cam;
	int spp = job->o->spp, k = (int)lround(sqrt(spp));
	double rgb[3];

	for (int s = 0; s < spp; s++) {
		int r = (int)(rng_u01(rng) * (s + 1));
		perm[s] = perm[r];
		perm[r] = s;
	}
	for (int s = 0; s < spp; s++) {
		struct vec3 o, d;
		double px, py;
		pixel_position(s, spp, k, perm, rng, &px, &py);
		double lu = rng_u01(rng), lv = rng_u01(rng);
		glint_pinhole_ray(cam, x + px, y + py, lu, lv, &o, &d);
		double th = hit_sphere(o, d, job->sc->sphere_centre,
				       job->sc->sphere_radius);
		if (th < 0)
			glint_envmap_lookup(job->env, d, rgb);
		else if (job->m)
			shade_dielectric(job, v3_add(o, v3_scale(d, th)), d,
					 rng, rgb);
		else
			shade(job, v3_add(o, v3_scale(d, th)), d, rng, rgb);
		double v = (rgb[0] + rgb[1] + rgb[2]) / 3;
		for (int c = 0; c < 3; c++)
			sum[c] += rgb[c];
		*s1 += v;
		*s2 += v * v;
	}
}

/*
 * Each pixel: one round of spp primary samples; with opts.rel_noise set,
 * a pixel whose round has a relative standard error above it (a
 * highlight's heavy tail) gets the rounds that bring it under, at most
 * opts.max_rounds, and its value is their mean alone, so that the
 * choice made on the first round does not lean the value.
 */
static void ref_rows(void *ctx, int y0, int y1, int thread)
{
	struct ref_job *job = ctx;
	const struct glint_pinhole *cam = &job->sc->cam;
	int spp = job->o->spp;
	int *perm = malloc((size_t)spp * sizeof(*perm));
	long rounds = 0;

	(void)thread;
	glint_thread_ftz();
	if (!perm) {
		job->failed = 1;
		return;
	}
	for (int y = y0; y < y1; y++)
		for (int x = 0; x < cam->width; x++) {
			struct rng rng;
			double sum[3] = { 0, 0, 0 }, s1 = 0, s2 = 0;
			int n = 1;
			rng_seed(&rng, ((uint64_t)job->o->seed << 40) ^
					       ((uint64_t)y * cam->width + x));
			pixel_round(job, x, y, perm, &rng, sum, &s1, &s2);
			double mean = s1 / spp;
			double var = spp > 1 ? fmax(0, s2 - s1 * mean) /
						       (spp - 1) / spp
					     : 0;
			double want = job->o->rel_noise * fabs(mean);
			if (job->o->rel_noise > 0 && var > want * want) {
				double need = ceil(var / (want * want));
				n = need < job->o->max_rounds
					    ? (int)need
					    : job->o->max_rounds;
				memset(sum, 0, sizeof(sum));
				for (int i = 0; i < n; i++)
					pixel_round(job, x, y, perm, &rng, sum,
						    &s1, &s2);
			}
			rounds += n;
			float *dst = glint_image_px(job->out, x, y);
			for (int c = 0; c < 3; c++)
				dst[c] = (float)(sum[c] / ((double)spp * n));
		}
	free(perm);
	__atomic_fetch_add(&job->rounds, rounds, __ATOMIC_RELAXED);
}

static int render(struct ref_job *job)
{
	const struct glint_scene *scene = job->sc;
	struct glint_image *out = job->out;

	if (out->width != scene->cam.width || out->height != scene->cam.height)
		return glint_error_set(EINVAL,
				       "reference render target %dx%d: "
				       "expected %dx%d",
				       out->width, out->height,
				       scene->cam.width, scene->cam.height);
	if (job->o->spp < 1)
		return glint_error_set(
			EINVAL, "reference renderer: %d samples per pixel",
			job->o->spp);
	if (job->o->rel_noise > 0 && job->o->max_rounds < 1)
		return glint_error_set(EINVAL,
				       "reference renderer: at most %d rounds "
				       "a pixel",
				       job->o->max_rounds);
	glint_parallel_for(out->height, 1, job->o->nthreads, ref_rows, job);
	if (job->failed)
		return glint_error_set(ENOMEM, "out of memory");
	if (job->o->rounds)
		*job->o->rounds = job->rounds;
	return 0;
}

int glint_reference_render_bxdf(const struct glint_scene *scene,
				const struct glint_envmap *env,
				const struct glint_bxdf *bxdf,
				const struct glint_reference_opts *opts,
				struct glint_image *out)
{
	struct ref_job job = {
		.sc = scene, .env = env, .bx = *bxdf, .o = opts, .out = out
	};

	if (!(bxdf->ops->flags & GLINT_BXDF_LOBES) || bxdf->ops->nlobes <= 0)
		return glint_error_set(EINVAL, "reference renderer: a BRDF "
					       "without lobe structure");
	return render(&job);
}

int glint_reference_render(const struct glint_scene *scene,
			   const struct glint_envmap *env,
			   const struct glint_model *model, const double *p,
			   const struct glint_reference_opts *opts,
			   struct glint_image *out)
{
	struct ref_job job = { .sc = scene,
			       .env = env,
			       .m = model,
			       .p = p,
			       .o = opts,
			       .out = out };

	if (glint_model_is_transparent(model))
		return render(&job);
	struct glint_bxdf bx = glint_model_bxdf(model, p);
	if (!(bx.ops->flags & GLINT_BXDF_LOBES) || bx.ops->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "reference renderer: model %s has no "
				       "lobe structure",
				       model->name);
	return glint_reference_render_bxdf(scene, env, &bx, opts, out);
}
