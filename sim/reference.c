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
	o->irradiance_w = 128;
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

struct irradiance {
	int w, h;
	double *e; /* w * h * 3 */
};

/* E(n) on a lat-long grid of normals (world frame, map convention). */
static int irradiance_build(const struct glint_envmap *env, int w,
			    struct irradiance *ir)
{
	const struct glint_image *img = env->img;
	int f = img->width / 256 > 1 ? img->width / 256 : 1;
	int dw = img->width / f, dh = img->height / f;
	double *lt = malloc((size_t)dw * dh * 3 * sizeof(double));
	struct vec3 *dir = malloc((size_t)dw * dh * sizeof(struct vec3));

	ir->w = w;
	ir->h = w / 2;
	ir->e = calloc((size_t)ir->w * ir->h * 3, sizeof(double));
	if (!lt || !dir || !ir->e) {
		free(lt);
		free(dir);
		free(ir->e);
		return glint_error_set(ENOMEM, "out of memory");
	}
	/* Box-downsampled texels: radiance x solid angle, world direction. */
	for (int j = 0; j < dh; j++) {
		double t0 = M_PI * j / dh, t1 = M_PI * (j + 1) / dh;
		double omega = (2 * M_PI / dw) * (cos(t0) - cos(t1));
		for (int i = 0; i < dw; i++) {
			double s[3] = { 0, 0, 0 };
			for (int y = 0; y < f; y++)
				for (int x = 0; x < f; x++) {
					const float *p = glint_image_px(
						img, i * f + x, j * f + y);
					for (int c = 0; c < 3; c++)
						s[c] += p[c];
				}
			for (int c = 0; c < 3; c++)
				lt[((size_t)j * dw + i) * 3 + c] =
					env->scale * s[c] / (f * f) * omega;
			dir[(size_t)j * dw + i] =
				m3_mul(&env->rot,
				       glint_envmap_uv_to_dir((i + 0.5) / dw,
							      (j + 0.5) / dh));
		}
	}
	for (int y = 0; y < ir->h; y++)
		for (int x = 0; x < ir->w; x++) {
			struct vec3 n = glint_envmap_uv_to_dir(
				(x + 0.5) / ir->w, (y + 0.5) / ir->h);
			double *e = ir->e + ((size_t)y * ir->w + x) * 3;
			for (int k = 0; k < dw * dh; k++) {
				double c = v3_dot(n, dir[k]);
				if (c <= 0)
					continue;
				for (int ch = 0; ch < 3; ch++)
					e[ch] += c * lt[3 * (size_t)k + ch];
			}
		}
	free(lt);
	free(dir);
	return 0;
}

static void irradiance_lookup(const struct irradiance *ir, struct vec3 n,
			      double e[3])
{
	double u, v;
	glint_envmap_dir_to_uv(n, &u, &v);
	double x = u * ir->w - 0.5, y = v * ir->h - 0.5;
	double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
	int x0 = ((int)fx % ir->w + ir->w) % ir->w, x1 = (x0 + 1) % ir->w;
	int y0 = (int)fy < 0 ? 0 : (int)fy, y1 = (int)fy + 1;
	y0 = y0 >= ir->h ? ir->h - 1 : y0;
	y1 = y1 >= ir->h ? ir->h - 1 : y1 < 0 ? 0 : y1;
	for (int c = 0; c < 3; c++) {
		const double *a = ir->e + ((size_t)y0 * ir->w + x0) * 3;
		const double *b = ir->e + ((size_t)y0 * ir->w + x1) * 3;
		const double *d = ir->e + ((size_t)y1 * ir->w + x0) * 3;
		const double *g = ir->e + ((size_t)y1 * ir->w + x1) * 3;
		e[c] = (1 - ty) * ((1 - tx) * a[c] + tx * b[c]) +
		       ty * ((1 - tx) * d[c] + tx * g[c]);
	}
}

struct ref_job {
	const struct glint_scene *sc;
	const struct glint_envmap *env;
	const struct glint_model_ops *m;
	const double *p;
	const struct glint_reference_opts *o;
	struct irradiance ir;
	int diffuse_lobe; /* index of the constant 1/pi lobe, or -1 */
	struct glint_image *out;
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

static void shade(const struct ref_job *job, struct vec3 pos, struct vec3 d,
		  struct rng *rng, double rgb[3])
{
	const struct glint_model_ops *m = job->m;
	int ns = job->o->samples;
	struct vec3 n = v3_norm(v3_sub(pos, job->sc->sphere_centre)), t, b;
	double lobes[GLINT_MAX_PARAMS], l[3];

	v3_frame(n, &t, &b);
	struct vec3 wo = v3(-v3_dot(d, t), -v3_dot(d, b), -v3_dot(d, n));
	rgb[0] = rgb[1] = rgb[2] = 0;
	if (job->diffuse_lobe >= 0) {
		double e[3];
		irradiance_lookup(&job->ir, n, e);
		for (int c = 0; c < 3; c++)
			rgb[c] += job->p[m->lobe_param[job->diffuse_lobe] + c] *
				  e[c] / M_PI;
	}
	for (int j = 0; j < m->nlobes; j++) {
		if (j == job->diffuse_lobe)
			continue;
		const double *alb = job->p + m->lobe_param[j];
		for (int k = 0; k < 2 * ns; k++) {
			struct vec3 wi, ww;
			double pl, pb;
			if (k < ns) { /* env-map sample */
				double u1 = rng_u01(rng), u2 = rng_u01(rng);
				pl = glint_envmap_sample(job->env, u1, u2, &ww);
				wi = v3(v3_dot(ww, t), v3_dot(ww, b),
					v3_dot(ww, n));
				if (!(pl > 0) || !(wi.z > 0))
					continue;
				pb = m->pdf_lobe(job->p, j, wo, wi);
			} else { /* lobe sample */
				double u[2] = { rng_u01(rng), rng_u01(rng) };
				pb = m->sample_lobe(job->p, j, wo, u, &wi);
				if (!(pb > 0))
					continue;
				ww = v3_add(v3_add(v3_scale(t, wi.x),
						   v3_scale(b, wi.y)),
					    v3_scale(n, wi.z));
				pl = glint_envmap_pdf(job->env, ww);
			}
			m->eval_lobes(job->p, wo, wi, lobes);
			if (lobes[j] <= 0)
				continue;
			/* Power heuristic, one sample of ns per technique. */
			double pk = k < ns ? pl : pb, po = k < ns ? pb : pl;
			double w = pk * pk / (pk * pk + po * po);
			glint_envmap_lookup(job->env, ww, l);
			for (int c = 0; c < 3; c++)
				rgb[c] += alb[c] * lobes[j] * l[c] * wi.z * w /
					  (pk * ns);
		}
	}
}

static void ref_rows(void *ctx, int y0, int y1, int thread)
{
	struct ref_job *job = ctx;
	const struct glint_camera *cam = &job->sc->cam;
	int spp = job->o->spp;

	(void)thread;
	glint_thread_ftz();
	for (int y = y0; y < y1; y++)
		for (int x = 0; x < cam->width; x++) {
			struct rng rng;
			double sum[3] = { 0, 0, 0 }, rgb[3];
			rng_seed(&rng, ((uint64_t)job->o->seed << 40) ^
					       ((uint64_t)y * cam->width + x));
			for (int s = 0; s < spp; s++) {
				struct vec3 o, d;
				double px = x + rng_u01(&rng);
				double py = y + rng_u01(&rng);
				double lu = rng_u01(&rng), lv = rng_u01(&rng);
				glint_camera_ray(cam, px, py, lu, lv, &o, &d);
				double th =
					hit_sphere(o, d, job->sc->sphere_centre,
						   job->sc->sphere_radius);
				if (th < 0)
					glint_envmap_lookup(job->env, d, rgb);
				else
					shade(job, v3_add(o, v3_scale(d, th)),
					      d, &rng, rgb);
				for (int c = 0; c < 3; c++)
					sum[c] += rgb[c];
			}
			float *dst = glint_image_px(job->out, x, y);
			for (int c = 0; c < 3; c++)
				dst[c] = (float)(sum[c] / spp);
		}
}

int glint_reference_render(const struct glint_scene *scene,
			   const struct glint_envmap *env,
			   const struct glint_model_ops *model, const double *p,
			   const struct glint_reference_opts *opts,
			   struct glint_image *out)
{
	struct ref_job job = { scene, env, model, p, opts, { 0 }, -1, out };
	int ret;

	if (model->nlobes <= 0)
		return glint_error_set(EINVAL,
				       "reference renderer: model %s has no "
				       "lobe structure",
				       model->name);
	if (out->width != scene->cam.width || out->height != scene->cam.height)
		return glint_error_set(EINVAL,
				       "reference render target %dx%d: "
				       "expected %dx%d",
				       out->width, out->height,
				       scene->cam.width, scene->cam.height);
	/* The constant lobe that equals 1/pi is integrated by quadrature. */
	for (int j = 0; j < model->nlobes; j++) {
		double b[GLINT_MAX_PARAMS];
		model->eval_lobes(p, v3(0, 0.6, 0.8), v3(0.3, 0, 0.9539), b);
		if (!model->lobe_varies[j] && fabs(b[j] - 1 / M_PI) < 1e-12)
			job.diffuse_lobe = j;
	}
	if (job.diffuse_lobe >= 0) {
		ret = irradiance_build(env, opts->irradiance_w, &job.ir);
		if (ret < 0)
			return ret;
	}
	glint_parallel_for(out->height, 1, opts->nthreads, ref_rows, &job);
	free(job.ir.e);
	return 0;
}
