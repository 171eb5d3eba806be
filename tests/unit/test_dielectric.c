/* SPDX-License-Identifier: MIT */
/*
 * The transparent sphere's physics (fit/render/dielectric_paths.c): Fresnel
 * against independently derived forms (Brewster, total internal reflection,
 * energy conservation R + T = 1 from the transmission amplitudes), the
 * ray through the centre, a white furnace, the transmission convention
 * on the axis, and the measured effect of the branch cut-off.
 */
#include "test.h"

#include "core/error.h"
#include "fit/render/dielectric_paths.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void test_fresnel(void)
{
	const double n = 1.5;
	/* Normal incidence. */
	double r0 = (n - 1) / (n + 1);
	CHECK_NEAR(glint_fresnel_interface(1, n, NULL), r0 * r0, 1e-12,
		   "R at normal incidence");
	/* Brewster: p vanishes, R = Rs / 2 with Rs from the angle form. */
	double tb = atan(n), ct;
	double R = glint_fresnel_interface(cos(tb), n, &ct);
	double tt = acos(ct);
	double rs = sin(tb - tt) / sin(tb + tt);
	CHECK_NEAR(R, 0.5 * rs * rs, 1e-12, "R at Brewster's angle");
	CHECK_NEAR(tb + tt, M_PI / 2, 1e-12, "Brewster: reflected ⟂ refracted");
	/* Energy: R + T = 1 per polarisation with T from the amplitudes. */
	for (double ti = 0.01; ti < 1.55; ti += 0.1) {
		double ci = cos(ti), c2;
		glint_fresnel_interface(ci, n, &c2);
		double ts = 2 * ci / (ci + n * c2), tp = 2 * ci / (n * ci + c2);
		double rss = (ci - n * c2) / (ci + n * c2);
		double rpp = (n * ci - c2) / (n * ci + c2);
		double Ts = n * c2 / ci * ts * ts, Tp = n * c2 / ci * tp * tp;
		CHECK_NEAR(rss * rss + Ts, 1, 1e-12, "s: R + T");
		CHECK_NEAR(rpp * rpp + Tp, 1, 1e-12, "p: R + T");
		CHECK_NEAR(glint_fresnel_interface(ci, n, NULL),
			   0.5 * (rss * rss + rpp * rpp), 1e-12, "R average");
	}
	/* Total internal reflection beyond the critical angle (inside). */
	double crit = asin(1 / n);
	CHECK(glint_fresnel_interface(cos(crit + 0.01), 1 / n, NULL) == 1,
	      "TIR beyond the critical angle");
	CHECK(glint_fresnel_interface(cos(crit - 0.01), 1 / n, NULL) < 1,
	      "no TIR before it");
	struct vec3 t;
	CHECK(!glint_refract(v3(sin(crit + 0.01), 0, -cos(crit + 0.01)),
			     v3(0, 0, 1), 1 / n, &t),
	      "no refracted ray under TIR");
	/* Snell. */
	double ti = 0.7;
	CHECK(glint_refract(v3(sin(ti), 0, -cos(ti)), v3(0, 0, 1), n, &t),
	      "refracts");
	CHECK_NEAR(sin(ti), n * t.x, 1e-12, "Snell's law");
}

struct glint_rig {
	struct glint_pinhole cam;
	struct glint_tracer *tr;
	struct glint_gbuffer gb;
	struct glint_envmap *env;
};

/* A 0.1 m sphere 0.5 m in front of a w x w camera that it fills. */
static void make_rig(struct glint_rig *r, int w, int spp,
		     struct glint_image *map)
{
	double pitch = 1e-5, fpx = 0.9 * w / 2 / tan(asin(0.05 / 0.5));
	glint_pinhole_init(&r->cam, w, w, fpx * pitch, pitch, 0, 0, v3(0, 0, 0),
			   v3(0, 0, -1), v3(0, 1, 0));
	glint_tracer_new(&r->tr);
	glint_tracer_add_sphere(r->tr, v3(0, 0, -0.5), 0.05, GLINT_SPHERE_USER);
	glint_tracer_commit(r->tr);
	CHECK(glint_tracer_primary(r->tr, &r->cam, spp, 0, NULL, &r->gb) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_envmap_new(map, NULL, 1, "test map", &r->env) == 0, "%s",
	      glint_error_msg());
}

static void free_rig(struct glint_rig *r)
{
	glint_gbuffer_free(&r->gb);
	glint_tracer_free(r->tr);
	glint_envmap_free(r->env);
}

static struct glint_image *const_map(double l)
{
	struct glint_image *m = glint_image_new(64, 32);
	for (int i = 0; i < 64 * 32 * 3; i++)
		m->data[i] = (float)l;
	return m;
}

/* Pixels whose samples all hit. */
static int covered(const struct glint_gbuffer *gb, int i)
{
	for (int s = 0; s < gb->spp; s++)
		if (gb->hits[(size_t)i * gb->spp + s].geom < 0)
			return 0;
	return 1;
}

static void test_furnace(void)
{
	struct glint_rig r;
	struct glint_dielectric_cache c;
	make_rig(&r, 24, 4, const_map(1));
	int n = 24 * 24, worst_i = -1;
	int32_t pix[24 * 24];
	double rgb[3 * 24 * 24], T[3] = { 1, 1, 1 }, worst = 0, top = 0;
	for (int i = 0; i < n; i++)
		pix[i] = i;
	CHECK(glint_dielectric_trace(r.tr, &r.gb, pix, n, r.env, v3(0, 0, -0.5),
				     0.05, 1.5, NULL, 1, &c) == 0,
	      "%s", glint_error_msg());
	glint_dielectric_shade(&c, T, rgb);
	for (int i = 0; i < n; i++) {
		top = fmax(top, rgb[3 * i]);
		if (covered(&r.gb, i) && 1 - rgb[3 * i] > worst) {
			worst = 1 - rgb[3 * i];
			worst_i = i;
		}
	}
	fprintf(stderr,
		"  white furnace, clear sphere: max %.9f, largest "
		"loss %.2e (pixel %d), deepest path %d interfaces\n",
		top, worst, worst_i, c.max_depth_seen);
	CHECK(top <= 1 + 1e-6, "furnace: a pixel exceeds 1 (%.9f)", top);
	CHECK(worst < 1e-3, "furnace: energy lost %.2e (cut-off 1e-4)", worst);
	glint_dielectric_cache_free(&c);
	free_rig(&r);
}

/* On the axis every internal bounce runs along the diameter: with
 * R0 = ((n-1)/(n+1))^2 and constant radiance 1, light leaves through the
 * back after an even number of internal reflections and through the front
 * after an odd one, each traversal attenuated by T:
 *   I = R0 + (1 - R0)^2 T sum_k (R0 T)^k = R0 + (1 - R0)^2 T / (1 - R0 T)
 * (1 for T = 1: nothing is lost). */
/* One primary sample straight down the axis (0, 0, -1) onto the sphere's
 * front pole. */
static void axis_rig(struct glint_rig *r, struct glint_image *map)
{
	static struct glint_hit hit = {
		{ 0, 0, -0.45f }, { 0, 0, 1 }, { 0, 0, -1 }, 0
	};
	memset(r, 0, sizeof(*r));
	glint_tracer_new(&r->tr);
	glint_tracer_add_sphere(r->tr, v3(0, 0, -0.5), 0.05, GLINT_SPHERE_USER);
	glint_tracer_commit(r->tr);
	r->gb.width = r->gb.height = r->gb.spp = 1;
	r->gb.hits = malloc(sizeof(hit));
	memcpy(r->gb.hits, &hit, sizeof(hit));
	CHECK(glint_envmap_new(map, NULL, 1, "test map", &r->env) == 0, "%s",
	      glint_error_msg());
}

static void test_axis(void)
{
	struct glint_rig r;
	struct glint_dielectric_cache c;
	axis_rig(&r, const_map(1));
	int32_t pix[1] = { 0 };
	double T[3] = { 0.5, 0.25, 1 }, rgb[3];
	CHECK(glint_dielectric_trace(r.tr, &r.gb, pix, 1, r.env, v3(0, 0, -0.5),
				     0.05, 1.5, NULL, 1, &c) == 0,
	      "%s", glint_error_msg());
	/* The path through the centre leaves undeviated, one diameter in. */
	const struct glint_dpath *p = &c.paths[1];
	CHECK_NEAR(p->len, 1, 1e-5, "central path: one diameter inside");
	glint_dielectric_shade(&c, T, rgb);
	double r0 = 0.04;
	for (int ch = 0; ch < 3; ch++) {
		double want =
			r0 + (1 - r0) * (1 - r0) * T[ch] / (1 - r0 * T[ch]);
		/* up to the branches cut below 1e-4 */
		CHECK_NEAR(rgb[ch], want, 1e-4, "axis radiance vs closed form");
	}
	glint_dielectric_cache_free(&c);
	free_rig(&r);

	/* Undeviated: a map with a gradient seen through the centre shows
	 * the texel straight behind. */
	struct glint_image *m = glint_image_new(256, 128);
	for (int y = 0; y < 128; y++)
		for (int x = 0; x < 256; x++)
			for (int ch = 0; ch < 3; ch++)
				glint_image_px(m, x, y)[ch] =
					(float)(1 + x + 1000 * y);
	axis_rig(&r, m);
	CHECK(glint_dielectric_trace(r.tr, &r.gb, pix, 1, r.env, v3(0, 0, -0.5),
				     0.05, 1.5, NULL, 1, &c) == 0,
	      "%s", glint_error_msg());
	double behind[3];
	glint_envmap_lookup(r.env, v3(0, 0, -1), behind);
	CHECK_NEAR(c.paths[1].rgb[0], behind[0], 1e-3 * behind[0],
		   "the central ray leaves undeviated");
	glint_dielectric_cache_free(&c);
	free_rig(&r);
}

/* The cut-off's effect, measured: 1e-4 (the default) against 1e-7. */
static void test_cutoff(void)
{
	struct glint_rig r;
	struct glint_dielectric_cache a, b;
	struct glint_dielectric_opts o;
	struct glint_image *m = glint_image_new(128, 64);
	for (int y = 0; y < 64; y++)
		for (int x = 0; x < 128; x++)
			for (int ch = 0; ch < 3; ch++)
				glint_image_px(m, x, y)[ch] =
					(float)((x / 8 + y / 8) % 2 ? 5 : 0.2);
	make_rig(&r, 32, 4, m);
	int n = 32 * 32;
	int32_t pix[32 * 32];
	for (int i = 0; i < n; i++)
		pix[i] = i;
	double T[3] = { 1, 0.8, 0.5 }, ia[3 * 32 * 32], ib[3 * 32 * 32];
	glint_dielectric_default_opts(&o);
	CHECK(glint_dielectric_trace(r.tr, &r.gb, pix, n, r.env, v3(0, 0, -0.5),
				     0.05, 1.5, &o, 1, &a) == 0,
	      "%s", glint_error_msg());
	o.min_weight = 1e-7;
	CHECK(glint_dielectric_trace(r.tr, &r.gb, pix, n, r.env, v3(0, 0, -0.5),
				     0.05, 1.5, &o, 1, &b) == 0,
	      "%s", glint_error_msg());
	glint_dielectric_shade(&a, T, ia);
	glint_dielectric_shade(&b, T, ib);
	double se = 0, ss = 0;
	for (int i = 0; i < 3 * n; i++) {
		se += (ia[i] - ib[i]) * (ia[i] - ib[i]);
		ss += ib[i] * ib[i];
	}
	fprintf(stderr,
		"  cut-off 1e-4: %lld paths, %d interfaces; 1e-7: %lld paths, "
		"%d interfaces; image change %.2e of its RMS\n",
		(long long)a.npaths, a.max_depth_seen, (long long)b.npaths,
		b.max_depth_seen, sqrt(se / ss));
	CHECK(sqrt(se / ss) < 1e-4, "cut-off changes the image by %.2e",
	      sqrt(se / ss));
	glint_dielectric_cache_free(&a);
	glint_dielectric_cache_free(&b);
	free_rig(&r);
}

int main(void)
{
	RUN(test_fresnel);
	RUN(test_furnace);
	RUN(test_axis);
	RUN(test_cutoff);
	return test_result();
}
