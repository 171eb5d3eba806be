/* SPDX-License-Identifier: MIT */
/* Tracer and shading: furnace tests, silhouettes, camera geometry. */
#include <string.h>

#include "quadrature.h"
#include "test.h"

#include "core/error.h"
#include "fit/job.h"
#include "fit/render/render.h"
#include "fit/render/sampling.h"
#include "fit/render/shade_cache.h"

static struct glint_envmap *constant_env(double l)
{
	struct glint_image *img = glint_image_new(16, 8);
	struct glint_envmap *env = NULL;
	for (int i = 0; i < 16 * 8 * 3; i++)
		img->data[i] = (float)l;
	glint_envmap_new(img, NULL, 1, "constant", &env);
	return env;
}

/* Camera at the origin looking down -Z; fpx pixels of focal length. */
static void make_camera(struct glint_pinhole *cam, int w, int h, double fpx,
			double fnum, double focus)
{
	double pitch = 1e-5;
	glint_pinhole_init(cam, w, h, fpx * pitch, pitch, fnum, focus,
			   v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
}

struct setup {
	struct glint_pinhole cam;
	struct glint_tracer *t;
	struct glint_gbuffer gb;
};

static void setup_sphere(struct setup *s, struct vec3 c, double r, int spp)
{
	glint_tracer_new(&s->t);
	glint_tracer_add_sphere(s->t, c, r, GLINT_SPHERE_USER);
	glint_tracer_commit(s->t);
	CHECK(glint_tracer_primary(s->t, &s->cam, spp, 0, NULL, &s->gb) == 0,
	      "%s", glint_error_msg());
}

static void teardown(struct setup *s)
{
	glint_gbuffer_free(&s->gb);
	glint_tracer_free(s->t);
}

/* Lambertian sphere under constant radiance L renders kd L. */
static void test_furnace_lambert(void)
{
	struct setup s;
	struct glint_envmap *env = constant_env(0.7);
	double kd[3] = { 0.2, 0.5, 0.8 };
	make_camera(&s.cam, 48, 48, 60, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, 4);
	struct glint_image *img = glint_image_new(48, 48);
	struct glint_image *cov = glint_image_new(48, 48);

	/* Cosine sampling alone is exact for this integrand. */
	struct glint_shade_opts o = { .light_samples = 0, .brdf_samples = 8 };
	glint_render_shade(&s.gb, s.t, env, &glint_model_lambert, kd, &o, img,
			   cov);
	int covered = 0, bad = 0;
	for (int i = 0; i < 48 * 48; i++) {
		if (cov->data[3 * i] < 1)
			continue;
		covered++;
		for (int c = 0; c < 3; c++)
			bad += fabs(img->data[3 * i + c] - kd[c] * 0.7) > 1e-5;
	}
	CHECK(covered > 300 && bad == 0,
	      "BRDF sampling: %d of %d covered pixels off kd L", bad, covered);

	/* Multiple importance sampling: unbiased, small noise. */
	o = (struct glint_shade_opts){ .light_samples = 32,
				       .brdf_samples = 32 };
	glint_render_shade(&s.gb, s.t, env, &glint_model_lambert, kd, &o, img,
			   cov);
	double sum[3] = { 0 }, worst = 0;
	for (int i = 0; i < 48 * 48; i++) {
		if (cov->data[3 * i] < 1)
			continue;
		for (int c = 0; c < 3; c++) {
			sum[c] += img->data[3 * i + c];
			worst = fmax(
				worst,
				fabs(img->data[3 * i + c] / (kd[c] * 0.7) - 1));
		}
	}
	for (int c = 0; c < 3; c++)
		CHECK_NEAR(sum[c] / covered, kd[c] * 0.7, 2e-3 * kd[c],
			   "MIS mean over covered pixels");
	CHECK(worst < 0.03, "MIS worst pixel off by %.3g", worst);
	glint_image_free(img);
	glint_image_free(cov);
	glint_envmap_free(env);
	teardown(&s);
}

/* Torrance-Sparrow in a white furnace: the renderer's Monte Carlo
 * estimate matches an independent quadrature of the BRDF, and no pixel
 * exceeds 1. */
static void test_furnace_ts(void)
{
	struct setup s;
	struct glint_envmap *env = constant_env(1.0);
	double p[8] = { 0, 0, 0, 1, 1, 1, 0.2, 2.34 };
	make_camera(&s.cam, 40, 40, 50, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, 1);
	double worst = 0;
	int checked = 0;
	for (int y = 4; y < 40; y += 5)
		for (int x = 4; x < 40; x += 5) {
			const struct glint_hit *h = &s.gb.hits[y * 40 + x];
			if (h->geom < 0)
				continue;
			struct vec3 n = v3(h->n[0], h->n[1], h->n[2]), t, b;
			struct vec3 wo = v3(-h->d[0], -h->d[1], -h->d[2]);
			v3_frame(n, &t, &b);
			struct vec3 wl =
				v3(v3_dot(wo, t), v3_dot(wo, b), v3_dot(wo, n));
			double mc[3], q[3];
			glint_shade_hit(h, 1234u + x * 7 + y, NULL, env,
					&glint_model_torrance_sparrow, p, 512,
					512, mc);
			albedo_quadrature(&glint_model_torrance_sparrow, p, wl,
					  q);
			worst = fmax(worst, fabs(mc[0] - q[0]) / q[0]);
			CHECK(fabs(mc[0] - q[0]) <= 0.02 * q[0] + 1e-4,
			      "pixel (%d,%d) cos_o %.3f: MC %g, quadrature %g",
			      x, y, wl.z, mc[0], q[0]);
			checked++;
		}
	fprintf(stderr, "  %d pixels, worst relative difference %.4f\n",
		checked, worst);

	struct glint_image *img = glint_image_new(40, 40);
	double q[8] = { 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.1, 5 };
	struct glint_shade_opts o = { .light_samples = 32, .brdf_samples = 32 };
	glint_render_shade(&s.gb, s.t, env, &glint_model_torrance_sparrow, q,
			   &o, img, NULL);
	double mx = 0;
	/* Not an fmax() reduction: GCC 12.2 for arm64 stops with an internal
	 * error vectorising one (docs/arm64.md). */
	for (int i = 0; i < 40 * 40 * 3; i++)
		if (img->data[i] > mx)
			mx = img->data[i];
	/* Misses see the furnace itself (1.0); the sphere must not glow. */
	CHECK(mx <= 1.0 + 1e-6, "furnace pixel %g > 1", mx);
	glint_image_free(img);
	glint_envmap_free(env);
	teardown(&s);
}

static int inside_ellipse(const struct glint_ellipse *e, double x, double y)
{
	double dx = x - e->cx, dy = y - e->cy;
	double c = cos(e->angle), s = sin(e->angle);
	double u = c * dx + s * dy, v = -s * dx + c * dy;
	return (u * u) / (e->a * e->a) + (v * v) / (e->b * e->b) <= 1;
}

/* Coverage = fraction of a pixel's samples on the sphere. */
static void coverage(struct setup *s, double *cov)
{
	int n = s->cam.width * s->cam.height;
	for (int i = 0; i < n; i++) {
		int hits = 0;
		for (int k = 0; k < s->gb.spp; k++)
			hits += s->gb.hits[(size_t)i * s->gb.spp + k].geom >= 0;
		cov[i] = (double)hits / s->gb.spp;
	}
}

static void test_silhouette(void)
{
	struct setup s;
	struct vec3 c = v3(0.45, -0.3, -2.2), back;
	double r = 0.25;
	struct glint_ellipse e;
	int w = 200, h = 150;
	make_camera(&s.cam, w, h, 260, 0, 0);
	CHECK(glint_pinhole_sphere_ellipse(&s.cam, c, r, &e) == 0, "%s",
	      glint_error_msg());
	CHECK(e.a > e.b * 1.01,
	      "off-axis silhouette should be elongated: "
	      "a %g b %g",
	      e.a, e.b);
	/* The circle (centre, tangential radius) gives back the centre. */
	glint_pinhole_sphere_from_circle(&s.cam, e.cx, e.cy, e.b, r, &back);
	CHECK(v3_len(v3_sub(back, c)) < 1e-9, "circle -> 3-D off by %g m",
	      v3_len(v3_sub(back, c)));

	setup_sphere(&s, c, r, 256);
	double *cov = calloc((size_t)w * h, sizeof(double));
	coverage(&s, cov);
	double area = 0, mx = 0, my = 0;
	int wrong_in = 0, wrong_out = 0;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			double v = cov[y * w + x];
			area += v;
			mx += v * (x + 0.5);
			my += v * (y + 0.5);
			int corners = inside_ellipse(&e, x, y) +
				      inside_ellipse(&e, x + 1, y) +
				      inside_ellipse(&e, x, y + 1) +
				      inside_ellipse(&e, x + 1, y + 1);
			if (corners == 4 && v != 1)
				wrong_in++;
			/* Outside with a margin: a pixel whose centre lies
			 * more than a pixel beyond the ellipse. */
			struct glint_ellipse big = e;
			big.a += 1.5;
			big.b += 1.5;
			if (!inside_ellipse(&big, x + 0.5, y + 0.5) && v != 0)
				wrong_out++;
		}
	double exact = M_PI * e.a * e.b;
	/* The centroid of the silhouette is the ellipse's centre. */
	CHECK(fabs(area - exact) < 1e-3 * exact,
	      "silhouette area %.3f px^2, ellipse %.3f", area, exact);
	CHECK(fabs(mx / area - e.cx) < 0.02 && fabs(my / area - e.cy) < 0.02,
	      "centroid (%.4f, %.4f), ellipse centre (%.4f, %.4f)", mx / area,
	      my / area, e.cx, e.cy);
	CHECK(wrong_in == 0 && wrong_out == 0,
	      "%d inner pixels not covered, %d outer pixels covered", wrong_in,
	      wrong_out);
	free(cov);
	teardown(&s);
}

static int partial_pixels(struct setup *s)
{
	int n = s->cam.width * s->cam.height, k = 0;
	double *cov = calloc((size_t)n, sizeof(double));
	coverage(s, cov);
	for (int i = 0; i < n; i++)
		k += cov[i] > 0.02 && cov[i] < 0.98;
	free(cov);
	return k;
}

/* Thin lens: in focus the silhouette is sharp; defocus blurs it. */
static void test_thin_lens(void)
{
	struct setup a, b;
	struct vec3 c = v3(0, 0, -2);
	/* Focal length 150 px * 10 um = 1.5 mm at N = 0.025: a lens of
	 * radius 3 cm.  The silhouette lies at sqrt(2^2 - 0.25^2) = 1.984 m;
	 * focused at 1 m its blur circle is about 150 * 0.06 * (1 - 1/1.984)
	 * = 4.5 px wide. */
	make_camera(&a.cam, 80, 80, 150, 0.025, 1.984);
	make_camera(&b.cam, 80, 80, 150, 0.025, 1.0);
	CHECK_NEAR(a.cam.aperture_radius, 0.03, 1e-12, "aperture radius");
	setup_sphere(&a, c, 0.25, 64);
	setup_sphere(&b, c, 0.25, 64);
	int sharp = partial_pixels(&a), blurred = partial_pixels(&b);
	CHECK(blurred > 3 * sharp, "partial pixels: in focus %d, defocused %d",
	      sharp, blurred);
	teardown(&a);
	teardown(&b);
}

/* Icosphere mesh (convex, flat faces) through the shadow-ray path. */
static void test_mesh_furnace(void)
{
	struct setup s;
	struct glint_envmap *env = constant_env(0.5);
	double t = (1 + sqrt(5)) / 2, kd[3] = { 0.6, 0.6, 0.6 };
	float v[12 * 3] = { -1,	       (float)t, 0,	    1,	       (float)t,
			    0,	       -1,	 (float)-t, 0,	       1,
			    (float)-t, 0,	 0,	    -1,	       (float)t,
			    0,	       1,	 (float)t,  0,	       -1,
			    (float)-t, 0,	 1,	    (float)-t, (float)t,
			    0,	       -1,	 (float)t,  0,	       1,
			    (float)-t, 0,	 -1,	    (float)-t, 0,
			    1 };
	uint32_t f[20 * 3] = { 0,  11, 5,  0, 5, 1,  0, 1,  7, 0,  7,  10,
			       0,  10, 11, 1, 5, 9,  5, 11, 4, 11, 10, 2,
			       10, 7,  6,  7, 1, 8,  3, 9,  4, 3,  4,  2,
			       3,  2,  6,  3, 6, 8,  3, 8,  9, 4,  9,  5,
			       2,  4,  11, 6, 2, 10, 8, 6,  7, 9,  8,  1 };
	for (int i = 0; i < 12; i++)
		v[3 * i + 2] -= 8; /* move it to z = -8 */
	make_camera(&s.cam, 32, 32, 40, 0, 0);
	glint_tracer_new(&s.t);
	CHECK(glint_tracer_add_mesh(s.t, v, 12, f, 20) == 0, "%s",
	      glint_error_msg());
	glint_tracer_commit(s.t);
	CHECK(!glint_tracer_is_convex(s.t), "a mesh is not the convex case");
	glint_tracer_primary(s.t, &s.cam, 1, 0, NULL, &s.gb);
	struct glint_image *img = glint_image_new(32, 32);
	struct glint_shade_opts o = { .light_samples = 0, .brdf_samples = 16 };
	glint_render_shade(&s.gb, s.t, env, &glint_model_lambert, kd, &o, img,
			   NULL);
	int hits = 0, bad = 0;
	for (int i = 0; i < 32 * 32; i++) {
		if (s.gb.hits[i].geom < 0)
			continue;
		hits++;
		bad += fabs(img->data[3 * i] - 0.3) > 1e-4;
	}
	CHECK(hits > 50 && bad == 0, "%d of %d mesh pixels off kd L", bad,
	      hits);
	/* A ray from inside towards a face is occluded. */
	CHECK(glint_tracer_occluded(s.t, v3(0, 0, -8), v3(0, 0, 1), 0, 100),
	      "occlusion from the centre");
	CHECK(!glint_tracer_occluded(s.t, v3(0, 0, 0), v3(0, 0, 1), 0, 100),
	      "ray away from the mesh occluded");
	uint32_t badtri[3] = { 0, 1, 99 };
	CHECK(glint_tracer_add_mesh(s.t, v, 12, badtri, 1) < 0,
	      "out-of-range index accepted");
	CHECK_MSG(glint_error_msg(), "uses vertex 99");
	glint_image_free(img);
	glint_envmap_free(env);
	teardown(&s);
}

/* Same inputs, any thread count: the same image, bit for bit. */
static void test_deterministic(void)
{
	struct setup s;
	struct glint_envmap *env = constant_env(1.0);
	glint_image_px(env->img, 3, 2)[0] = 50; /* something to sample */
	glint_envmap_free(env);
	struct glint_image *m = glint_image_new(16, 8);
	for (int i = 0; i < 16 * 8 * 3; i++)
		m->data[i] = (float)(1 + (i % 7));
	glint_envmap_new(m, NULL, 1, "m", &env);
	double p[8] = { 0.3, 0.2, 0.1, 0.4, 0.4, 0.4, 0.1, 1.6 };
	make_camera(&s.cam, 24, 24, 30, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, 4);
	struct glint_image *a = glint_image_new(24, 24),
			   *b = glint_image_new(24, 24);
	struct glint_shade_opts o = { .light_samples = 8,
				      .brdf_samples = 8,
				      .background = 1,
				      .nthreads = 1 };
	glint_render_shade(&s.gb, s.t, env, &glint_model_torrance_sparrow, p,
			   &o, a, NULL);
	o.nthreads = 3;
	glint_render_shade(&s.gb, s.t, env, &glint_model_torrance_sparrow, p,
			   &o, b, NULL);
	CHECK(!memcmp(a->data, b->data, 24 * 24 * 12),
	      "images differ between 1 and 3 threads");
	/* Another seed: other sample sets, the same expectation. */
	o.seed = 1;
	glint_render_shade(&s.gb, s.t, env, &glint_model_torrance_sparrow, p,
			   &o, b, NULL);
	double sa = 0, sb = 0;
	int differ = 0;
	for (int i = 0; i < 24 * 24 * 3; i++) {
		sa += a->data[i];
		sb += b->data[i];
		differ += a->data[i] != b->data[i];
	}
	CHECK(differ > 100, "seed 1 changed only %d values", differ);
	CHECK(fabs(sa - sb) < 0.05 * sa, "seed 1: sum %g against %g", sb, sa);
	glint_image_free(a);
	glint_image_free(b);
	glint_envmap_free(env);
	teardown(&s);
}

/* A render at a pixel step: the grid's pixels and every pixel it does not
 * interpolate (the rim, the backdrop) are the full render's own bits; the
 * interpolated ones, all wholly on the sphere, stay within the full
 * render's noise of it; the coverage is the full render's. */
static void test_pixel_step(void)
{
	enum { W = 61, H = 47 };
	struct setup s;
	struct glint_image *m = glint_image_new(32, 16);
	struct glint_envmap *env = NULL;
	for (int y = 0; y < 16; y++)
		for (int x = 0; x < 32; x++)
			for (int c = 0; c < 3; c++)
				glint_image_px(m, x, y)[c] =
					(float)(1 + 0.5 * sin(0.2 * x + c) +
						0.3 * cos(0.3 * y));
	glint_envmap_new(m, NULL, 1, "smooth", &env);
	double p[8] = { 0.3, 0.2, 0.1, 0.2, 0.2, 0.2, 0.3, 1.5 };
	make_camera(&s.cam, W, H, 60, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, 4);
	struct glint_image *a = glint_image_new(W, H),
			   *b = glint_image_new(W, H);
	struct glint_image *ca = glint_image_new(W, H),
			   *cb = glint_image_new(W, H);
	struct glint_image *a2 = glint_image_new(W, H);
	struct glint_shade_opts o = { .light_samples = 16,
				      .brdf_samples = 16,
				      .background = 1,
				      .nthreads = 2 };
	CHECK(glint_render_shade(&s.gb, NULL, env,
				 &glint_model_torrance_sparrow, p, &o, a,
				 ca) == 0,
	      "%s", glint_error_msg());
	o.seed = 1; /* the full render's own noise: another sample set */
	glint_render_shade(&s.gb, NULL, env, &glint_model_torrance_sparrow, p,
			   &o, a2, NULL);
	o.seed = 0;
	o.pixel_step = 3;
	CHECK(glint_render_shade(&s.gb, NULL, env,
				 &glint_model_torrance_sparrow, p, &o, b,
				 cb) == 0,
	      "%s", glint_error_msg());
	int same = 0, interp = 0, rim_differs = 0, grid_differs = 0;
	double d_interp = 0, d_noise = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			const float *pa = glint_image_px(a, x, y),
				    *pb = glint_image_px(b, x, y),
				    *p2 = glint_image_px(a2, x, y);
			float cov = glint_image_px(ca, x, y)[0];
			int eq = !memcmp(pa, pb, 3 * sizeof(float));
			CHECK(glint_image_px(cb, x, y)[0] == cov,
			      "coverage differs at (%d, %d)", x, y);
			if (x % 3 == 0 && y % 3 == 0)
				grid_differs += !eq;
			else if (cov < 1)
				rim_differs += !eq;
			if (eq) {
				same++;
				continue;
			}
			interp++;
			for (int c = 0; c < 3; c++) {
				d_interp += fabs(pb[c] - pa[c]);
				d_noise += fabs(p2[c] - pa[c]);
			}
		}
	CHECK(grid_differs == 0 && rim_differs == 0,
	      "%d grid and %d rim or backdrop pixels differ from the full "
	      "render",
	      grid_differs, rim_differs);
	CHECK(interp > 600 && same > 600, "%d pixels interpolated, %d shaded",
	      interp, same);
	/* An interpolated pixel is the mean of four at the same noise, with
	 * the smooth map's curvature between them: nearer the full render
	 * than another full render's noise. */
	CHECK(d_interp < d_noise,
	      "interpolated pixels differ by %g, "
	      "another sample set by %g",
	      d_interp / (3 * interp), d_noise / (3 * interp));
	/* a pilot at a pixel step is refused */
	o.row_step = 4;
	CHECK(glint_render_shade(&s.gb, NULL, env,
				 &glint_model_torrance_sparrow, p, &o, b,
				 NULL) == -EINVAL,
	      "a row step with a pixel step was taken");
	glint_error_clear();
	glint_image_free(a);
	glint_image_free(a2);
	glint_image_free(b);
	glint_image_free(ca);
	glint_image_free(cb);
	glint_envmap_free(env);
	teardown(&s);
}

/* The fast per-pixel sample pattern equals glint_pixel_sample()'s, and
 * samples stay inside their pixel. */
static void test_sample_pattern(void)
{
	struct setup s;
	int bad = 0, outside = 0;
	make_camera(&s.cam, 20, 10, 30, 0.02, 2.5);
	setup_sphere(&s, v3(0, 0, -3), 1, 5);
	for (int y = 0; y < 10; y++)
		for (int x = 0; x < 20; x++)
			for (int k = 0; k < 5; k++) {
				double pix[2], lens[2];
				struct vec3 o, d;
				glint_pixel_sample(x, y, k, 5, pix, lens);
				outside += pix[0] < 0 || pix[0] >= 1 ||
					   pix[1] < 0 || pix[1] >= 1;
				glint_pinhole_ray(&s.cam, x + pix[0],
						  y + pix[1], lens[0], lens[1],
						  &o, &d);
				const float *g =
					s.gb.hits[(y * 20 + x) * 5 + k].d;
				bad += fabs(g[0] - d.x) > 1e-6 ||
				       fabs(g[1] - d.y) > 1e-6 ||
				       fabs(g[2] - d.z) > 1e-6;
			}
	CHECK(bad == 0 && outside == 0,
	      "%d G-buffer rays differ from the reference pattern, %d "
	      "samples outside their pixel",
	      bad, outside);
	teardown(&s);
}

/* The final render's second pair (fit/job.c): the samples that bring its
 * noise to the target, capped at 4 times the scene's and by the time
 * budget, and what capped them named. */
static void test_render_factor(void)
{
	const char *why;

	/* Below the target: no second pair. */
	CHECK(glint_render_factor(0.2, 1, 20, &why) == 0 && !why, "%s",
	      "below target");
	/* q1 = 1.01 of the photo's variance: 1/q1 + f/q1 = 4 at f = 3.04,
	 * so 4 times the samples, which 20 s affords at 2 s a pair. */
	int f = glint_render_factor(1.01, 2, 20, &why);
	CHECK(f == 4 && !why, "factor %d (%s)", f, why ? why : "-");
	/* q1 = 0.5: one more pair at the scene's samples halves it. */
	f = glint_render_factor(0.5, 2, 20, &why);
	CHECK(f == 1 && !why, "factor %d", f);
	/* Far above: capped at 4, and said. */
	f = glint_render_factor(10, 2, 20, &why);
	CHECK(f == 4 && why && strstr(why, "samples"), "factor %d", f);
	/* A 1 MP photo: 57 s a pair against a 20 s budget: no second pair,
	 * and the time is what stopped it. */
	f = glint_render_factor(1.8, 57, 20, &why);
	CHECK(f == 0 && why && strstr(why, "time"), "factor %d", f);
	/* Part of it affordable. */
	f = glint_render_factor(1.8, 7, 20, &why);
	CHECK(f == 2 && why && strstr(why, "time"), "factor %d", f);

	/* The first pair from its pilot.  Noisy enough: the scene's
	 * samples. */
	double g = glint_render_first_factor(0.5, 10, 20, &why);
	CHECK(g == 1 && !why, "first factor %g", g);
	/* Far below the noise target (0.25; aimed at half of it): a quarter
	 * of the samples brings q from 0.03125 to 0.125. */
	g = glint_render_first_factor(0.03125, 10, 20, &why);
	CHECK(fabs(g - 0.25) < 1e-12 && !why, "first factor %g", g);
	/* Never below an eighth. */
	g = glint_render_first_factor(0.001, 10, 20, &why);
	CHECK(g == 0.125 && !why, "first factor %g", g);
	/* A 12 MP window: 400 s a pair against 50 s: an eighth, said to be
	 * the time's doing; 800 s: still an eighth (over the budget). */
	g = glint_render_first_factor(0.5, 400, 50, &why);
	CHECK(g == 0.125 && why && strstr(why, "time"), "first factor %g", g);
	g = glint_render_first_factor(0.5, 800, 50, &why);
	CHECK(g == 0.125 && why, "first factor %g", g);
	/* Between: 100 s against 50 s. */
	g = glint_render_first_factor(0.5, 100, 50, &why);
	CHECK(fabs(g - 0.5) < 1e-12 && why, "first factor %g", g);
	/* The pixel step: 1 while an eighth of the samples fits; a
	 * 12 MP render 160 s at an eighth against 4 s: 1/k^2 of it,
	 * k = ceil(sqrt(40)) = 7; far beyond, at most 8. */
	CHECK(glint_render_pixel_step(0.125, 80, 20) == 1, "%s", "fits");
	CHECK(glint_render_pixel_step(0.125, 1280, 4) == 7, "step %d",
	      glint_render_pixel_step(0.125, 1280, 4));
	CHECK(glint_render_pixel_step(1, 40, 10) == 2, "step %d",
	      glint_render_pixel_step(1, 40, 10));
	CHECK(glint_render_pixel_step(0.125, 1e6, 1) == 8, "%s", "cap");
	CHECK(glint_render_pixel_step(0.125, 10, -0.5) == 8, "%s",
	      "no budget left");
	/* No pilot noise (no values): the budget alone. */
	g = glint_render_first_factor(NAN, 10, 20, &why);
	CHECK(g == 1 && !why, "first factor %g", g);
}

/* A 2048 x 1024 map: sky 0.05 and, towards (0.3, 0.4, 1), a sun of
 * 0.008 rad radius, 20 000 times brighter (box 0), or a softbox 0.3 rad
 * square, 400 times brighter (box 1: too large for hot texels). */
static struct glint_envmap *sun_env(int box)
{
	struct glint_image *img = glint_image_new(2048, 1024);
	struct glint_envmap *env = NULL;
	struct vec3 sun = v3_norm(v3(0.3, 0.4, 1));

	for (int y = 0; y < 1024; y++)
		for (int x = 0; x < 2048; x++) {
			struct vec3 d = glint_latlong_uv_to_dir(
				(x + 0.5) / 2048, (y + 0.5) / 1024);
			struct vec3 e =
				v3_sub(d, v3_scale(sun, v3_dot(d, sun)));
			float l = v3_dot(d, sun) > cos(0.008) ? 1000 : 0.05f;
			if (box)
				l = v3_dot(d, sun) > 0 && fabs(e.x) < 0.15 &&
						    fabs(e.y) < 0.15
					    ? 20
					    : 0.05f;
			float *px = glint_image_px(img, x, y);
			px[0] = px[1] = px[2] = l;
		}
	glint_envmap_new(img, NULL, 1, "sun", &env);
	return env;
}

/* The specular lobe of pixels pix[0..n) of a 48 x 48 frame of a sphere
 * 20 px in radius, at roughness m (ior 1.5), with spp hits per pixel and
 * ns light and ns lobe samples per hit. */
static void near_mirror_lobe_ns(const struct glint_envmap *env, int spp, int ns,
				int no_footprint, const int32_t *pix, int n,
				const double *ms, int nm, double *out)
{
	struct setup s;
	struct glint_shade_cache *c = NULL;
	struct glint_shade_cache_opts o = { .static_samples = 4,
					    .light_samples = ns,
					    .lobe_samples = ns,
					    .no_footprint = no_footprint,
					    .nthreads = 2 };
	double *lobes = calloc((size_t)n * 2 * 3, sizeof(double));

	make_camera(&s.cam, 48, 48, 60, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, spp);
	CHECK(glint_shade_cache_new(&s.gb, pix, n, env,
				    &glint_model_torrance_sparrow, &o, &c) == 0,
	      "%s", glint_error_msg());
	for (int k = 0; c && k < nm; k++) {
		double p[8] = { 0.1, 0.1, 0.1, 1, 1, 1, ms[k], 1.5 };
		glint_shade_cache_lobes(c, p, lobes);
		for (int i = 0; i < n; i++)
			out[k * n + i] = lobes[(i * 2 + 1) * 3];
	}
	glint_shade_cache_free(c);
	free(lobes);
	teardown(&s);
}

static void near_mirror_lobe(const struct glint_envmap *env, int spp,
			     int no_footprint, const int32_t *pix, int n,
			     const double *ms, int nm, double *out)
{
	near_mirror_lobe_ns(env, spp, 8, no_footprint, pix, n, ms, nm, out);
}

/* The 48 x 48 frame's sphere interior, 2 px in from its outline: pixel
 * indices into pix, their count returned. */
static int sphere_interior(int32_t *pix)
{
	int n = 0;
	for (int y = 0; y < 48; y++)
		for (int x = 0; x < 48; x++) {
			double dx = x + 0.5 - 24, dy = y + 0.5 - 24;
			if (dx * dx + dy * dy < 17 * 17)
				pix[n++] = y * 48 + x;
		}
	return n;
}

/*
 * A near-mirror's sun covers part of a pixel: the fitter's 4 hits alias
 * it, the footprint integral (shade_cache.c) must match 256 hits a pixel
 * (the sun's texels 0.003 rad, the lobe 0.006, a pixel's mirror direction
 * turning by 0.1: the sun's reflection is a fraction of a pixel, blurred
 * over a few): the highlight's pixels within 10 % of their total, and
 * the integral continuous in roughness across its grid levels.
 */
/*
 * The lobes' derivatives by ior (glint_shade_cache_lobes_d()) against a
 * central difference of the lobes on the same samples, for each model
 * with a factor parameter, under a sun (hot texels) or a softbox (env
 * and lobe samples), from a near-mirror (the footprint's grid and spread
 * samples) to a rough lobe.
 */
static void test_factor_derivative(void)
{
	static const struct glint_model *const models[] = {
		&glint_model_torrance_sparrow,
		&glint_model_ggx,
		&glint_model_two_lobe,
	};
	static const double rough[] = { 0.004, 0.05, 0.3 };
	int32_t pix[48 * 48];
	int n = sphere_interior(pix);

	for (int box = 0; box < 2; box++) {
		struct glint_envmap *env = sun_env(box);
		struct setup s;
		make_camera(&s.cam, 48, 48, 60, 0, 0);
		setup_sphere(&s, v3(0, 0, -3), 1, 4);
		for (int k = 0; k < 3; k++) {
			/* Torrance-Sparrow under both; GGX under the sun,
			 * two lobes under the softbox */
			if ((k == 1 && box) || (k == 2 && !box))
				continue;
			const struct glint_model *m = models[k];
			int nj = m->bxdf->nlobes, ior = m->lobes->factor_param;
			struct glint_shade_cache_opts o = { .static_samples = 4,
							    .light_samples = 8,
							    .lobe_samples = 8,
							    .nthreads = 2 };
			struct glint_shade_cache *c = NULL;
			size_t nl = (size_t)n * nj * 3;
			double *l0 = calloc(nl, sizeof(double));
			double *d = calloc(nl, sizeof(double));
			double *lp = calloc(nl, sizeof(double));
			double *lm = calloc(nl, sizeof(double));
			CHECK(m->lobes->factor_dlog && l0 && d && lp && lm,
			      "%s: a factor parameter", m->name);
			CHECK(glint_shade_cache_new(&s.gb, pix, n, env, m, &o,
						    &c) == 0,
			      "%s", glint_error_msg());
			for (int r = 0; c && r < 3; r++) {
				double p[GLINT_MAX_PARAMS], q[GLINT_MAX_PARAMS];
				for (int a = 0; a < m->nparams; a++)
					p[a] = m->params[a].def;
				p[m->lobes->roughness_param] = rough[r];
				if (nj > 2) /* two-lobe: the second wider */
					p[11] = 2 * rough[r];
				p[ior] = 1.6;
				int *sel = malloc((size_t)n * sizeof(int));
				for (int i = 0; i < n; i++)
					sel[i] = i;
				glint_shade_cache_lobes_d(c, p, sel, n, l0, d);
				memcpy(q, p, sizeof(q));
				double h = 1e-4;
				q[ior] = p[ior] + h;
				glint_shade_cache_lobes_sel(c, q, sel, n, lp);
				q[ior] = p[ior] - h;
				glint_shade_cache_lobes_sel(c, q, sel, n, lm);
				double scale = 0, err = 0, same = 0;
				for (size_t i = 0; i < nl; i++) {
					double fd = (lp[i] - lm[i]) / (2 * h);
					scale = fmax(scale, fabs(fd));
					err = fmax(err, fabs(d[i] - fd));
				}
				/* the value itself as without derivatives */
				glint_shade_cache_lobes_sel(c, p, sel, n, lp);
				for (size_t i = 0; i < nl; i++)
					same = fmax(same, fabs(lp[i] - l0[i]));
				printf("  %s, %s, roughness %.3f: d/d ior "
				       "within %.2g of %.3g\n",
				       m->name, box ? "softbox" : "sun",
				       rough[r], err, scale);
				CHECK(scale > 0 && err < 1e-6 * scale,
				      "%s roughness %g: derivative off by %g "
				      "of %g",
				      m->name, rough[r], err, scale);
				CHECK(same == 0, "%s: the value moved by %g",
				      m->name, same);
				free(sel);
			}
			glint_shade_cache_free(c);
			free(l0);
			free(d);
			free(lp);
			free(lm);
		}
		teardown(&s);
		glint_envmap_free(env);
	}
}

static void test_footprint(void)
{
	struct glint_envmap *env = sun_env(0);
	int32_t pix[48 * 48];
	int n = sphere_interior(pix);
	double m = 0.004;
	double *ref = calloc((size_t)n, sizeof(double));
	double *foot = calloc((size_t)n, sizeof(double));
	double *hits = calloc((size_t)n, sizeof(double));
	near_mirror_lobe(env, 256, 1, pix, n, &m, 1, ref);
	near_mirror_lobe(env, 4, 0, pix, n, &m, 1, foot);
	near_mirror_lobe(env, 4, 1, pix, n, &m, 1, hits);
	double tot = 0, efoot = 0, ehits = 0, peak = 0;
	int lit = 0;
	for (int i = 0; i < n; i++) {
		tot += ref[i];
		peak = fmax(peak, ref[i]);
		efoot += fabs(foot[i] - ref[i]);
		ehits += fabs(hits[i] - ref[i]);
	}
	for (int i = 0; i < n; i++)
		lit += ref[i] > 0.01 * peak;
	printf("  near-mirror under a sun: %d pixels lit, total %.4g; "
	       "error over the footprint %.3f, on 4 hits %.3f\n",
	       lit, tot, efoot / tot, ehits / tot);
	CHECK(lit >= 1 && peak > 0.1, "the sun lights %d pixels", lit);
	CHECK(efoot < 0.1 * tot, "footprint: error %.3f of the total",
	      efoot / tot);
	CHECK(ehits > 2 * efoot, "4 hits alone: error %.3f (footprint %.3f)",
	      ehits / tot, efoot / tot);

	/* Continuous in roughness: from 0.002 to 0.03 in steps of 2 %, no
	 * step changes the highlight's total by more than 3 times its
	 * neighbours' steps (a jump at a grid level would). */
	enum { NM = 140 };
	double ms[NM], *v = calloc((size_t)NM * n, sizeof(double)), sum[NM];
	for (int k = 0; k < NM; k++)
		ms[k] = 0.002 * pow(1.02, k);
	near_mirror_lobe(env, 4, 0, pix, n, ms, NM, v);
	for (int k = 0; k < NM; k++) {
		sum[k] = 0;
		for (int i = 0; i < n; i++)
			sum[k] += v[k * n + i];
	}
	int jumps = 0;
	for (int k = 2; k + 2 < NM; k++) {
		double d = fabs(sum[k + 1] - sum[k]);
		double nb = fmax(fabs(sum[k] - sum[k - 1]),
				 fabs(sum[k + 2] - sum[k + 1]));
		if (d > 3 * nb + 1e-9 * fabs(sum[k])) {
			jumps++;
			printf("  jump at roughness %.5f: %.4g -> %.4g\n",
			       ms[k], sum[k], sum[k + 1]);
		}
	}
	CHECK(jumps == 0, "%d jumps in the highlight's total", jumps);
	free(v);
	free(ref);
	free(foot);
	free(hits);
	glint_envmap_free(env);
}

/* Pixel values fp (n of them) against the reference rp: the sum of
 * absolute errors over the sum of the reference. */
static double l1_error(const double *fp, const double *rp, int n)
{
	double tot = 0, e = 0;
	for (int i = 0; i < n; i++) {
		tot += rp[i];
		e += fabs(fp[i] - rp[i]);
	}
	return e / tot;
}

/*
 * The rest of the map (here a softbox too large for hot texels) seen in
 * a near-mirror: its edges cross pixels, which 4 hits alias; the lobe
 * samples spread over the footprint must come closer to 256 hits a pixel.
 */
static void test_footprint_rest(void)
{
	struct glint_envmap *env = sun_env(1);
	int32_t pix[48 * 48];
	int n = sphere_interior(pix);
	double m = 0.004;
	double *ref = calloc((size_t)n, sizeof(double));
	double *foot = calloc((size_t)n, sizeof(double));
	double *hits = calloc((size_t)n, sizeof(double));
	near_mirror_lobe(env, 256, 1, pix, n, &m, 1, ref);
	near_mirror_lobe(env, 4, 0, pix, n, &m, 1, foot);
	near_mirror_lobe(env, 4, 1, pix, n, &m, 1, hits);
	double efoot = l1_error(foot, ref, n), ehits = l1_error(hits, ref, n);
	printf("  near-mirror under a softbox: error over the footprint "
	       "%.3f, on 4 hits %.3f\n",
	       efoot, ehits);
	CHECK(efoot < 0.6 * ehits, "footprint %.3f, 4 hits %.3f", efoot, ehits);
	/* More samples, closer: the spread's pixel points are shuffled
	 * among the lobe samples (paired by index, a point's position
	 * followed its direction's first uniform, and the error stalled:
	 * 0.031, 0.018, 0.016 at 8, 32, 128 samples; so it did when the
	 * pixel's hits took every fourth point of one set, each hit a
	 * quarter of the lobe: 0.035, 0.029, 0.025). */
	double e[3];
	for (int k = 0, ns = 8; k < 3; k++, ns *= 4) {
		near_mirror_lobe_ns(env, 4, ns, 0, pix, n, &m, 1, foot);
		e[k] = l1_error(foot, ref, n);
	}
	printf("  footprint at 8, 32, 128 samples: %.4f %.4f %.4f\n", e[0],
	       e[1], e[2]);
	CHECK(e[2] < 0.4 * e[0], "128 samples: error %.4f, 8: %.4f", e[2],
	      e[0]);
	free(ref);
	free(foot);
	free(hits);
	glint_envmap_free(env);
}

/* The specular lobe (red) of cache c's n pixels at roughness m (the
 * rest of the parameters as near_mirror_lobe's) into out. */
static void spread_lobes(struct glint_shade_cache *c, double m, int n,
			 double *out)
{
	double p[8] = { 0.1, 0.1, 0.1, 1, 1, 1, m, 1.5 };
	double *lobes = calloc((size_t)n * 2 * 3, sizeof(double));

	glint_shade_cache_lobes(c, p, lobes);
	for (int i = 0; i < n; i++)
		out[i] = lobes[(i * 2 + 1) * 3];
	free(lobes);
}

/* The largest |a - b| over n values. */
static double max_diff(const double *a, const double *b, int n)
{
	double d = 0;
	for (int i = 0; i < n; i++)
		d = fmax(d, fabs(a[i] - b[i]));
	return d;
}

/*
 * The footprint's blend fixed (glint_shade_cache_fix_footprint()): where
 * a lobe is about as wide as a pixel's turn of mirror direction, a share
 * of its samples, growing as it narrows, is spread over the pixel.  Fixed
 * at one roughness, the lobe there is the same bit for bit; at another
 * roughness it is shaded with the fixed share (not the one that follows:
 * the values differ where the share does), and NULL follows the
 * roughness again.  A joint cache fixes its parts': its values are those
 * of a part fixed alone.
 */
static void test_footprint_fixed(void)
{
	struct glint_envmap *env = sun_env(1);
	int32_t pix[48 * 48];
	int n = sphere_interior(pix);
	double m0 = 0.08, m1 = 0.12,
	       p0[8] = { 0.1, 0.1, 0.1, 1, 1, 1, m0, 1.5 };
	double *a = calloc((size_t)n, sizeof(double));
	double *b = calloc((size_t)n, sizeof(double));
	double *j = calloc((size_t)n * 2, sizeof(double));
	struct setup s;
	struct glint_shade_cache *c = NULL, *parts[2] = { NULL, NULL }, *joint;
	struct glint_shade_cache_opts o = { .static_samples = 4,
					    .light_samples = 8,
					    .lobe_samples = 8,
					    .nthreads = 2 };

	make_camera(&s.cam, 48, 48, 60, 0, 0);
	setup_sphere(&s, v3(0, 0, -3), 1, 4);
	/* c, and two caches made alike: one never fixed, one a part */
	struct glint_shade_cache **mk[3] = { &c, &parts[0], &parts[1] };
	for (int k = 0; k < 3; k++)
		CHECK(glint_shade_cache_new(&s.gb, pix, n, env,
					    &glint_model_torrance_sparrow, &o,
					    mk[k]) == 0,
		      "%s", glint_error_msg());
	spread_lobes(c, m0, n, a);
	glint_shade_cache_fix_footprint(c, p0);
	spread_lobes(c, m0, n, b);
	CHECK(max_diff(a, b, n) == 0, "at the fixed roughness: off by %g",
	      max_diff(a, b, n));
	spread_lobes(c, m1, n, b);
	glint_shade_cache_fix_footprint(c, NULL);
	spread_lobes(c, m1, n, a);
	double top = 0;
	for (int i = 0; i < n; i++)
		top = fmax(top, a[i]);
	printf("  at roughness %.2f, the blend fixed at %.2f: pixels differ "
	       "by up to %.3g of %.3g\n",
	       m1, m0, max_diff(a, b, n), top);
	CHECK(max_diff(a, b, n) > 1e-3 * top, "the fixed blend had no effect");
	/* NULL: the blend follows again, the same as a cache never fixed */
	spread_lobes(parts[0], m1, n, b);
	CHECK(max_diff(a, b, n) == 0, "unfixed: off by %g", max_diff(a, b, n));

	/* a joint cache of two parts, the second made as c */
	glint_shade_cache_fix_footprint(c, p0);
	spread_lobes(c, m1, n, a);
	CHECK(glint_shade_cache_join(parts, 2, &joint) == 0, "%s",
	      glint_error_msg());
	glint_shade_cache_fix_footprint(joint, p0);
	double p1[8] = { 0.1, 0.1, 0.1, 1, 1, 1, m1, 1.5 };
	double *lobes = calloc((size_t)n * 2 * 2 * 3, sizeof(double));
	glint_shade_cache_lobes(joint, p1, lobes);
	for (int i = 0; i < 2 * n; i++)
		j[i] = lobes[(i * 2 + 1) * 3];
	CHECK(max_diff(j + n, a, n) == 0,
	      "the joint cache's second part: off by %g",
	      max_diff(j + n, a, n));
	free(lobes);
	glint_shade_cache_free(joint);
	glint_shade_cache_free(c);
	teardown(&s);
	free(a);
	free(b);
	free(j);
	glint_envmap_free(env);
}

/* glint_permute(): a bijection of [0, n) for every n and seed, and
 * different seeds give different orders. */
static void test_permute(void)
{
	static const uint32_t ns[] = { 1, 2, 3, 5, 32, 33, 100, 256, 1000 };
	unsigned char seen[1000];

	for (size_t a = 0; a < sizeof(ns) / sizeof(*ns); a++)
		for (uint32_t seed = 0; seed < 8; seed++) {
			uint32_t n = ns[a], same = 0, bad = 0;
			memset(seen, 0, sizeof(seen));
			for (uint32_t i = 0; i < n; i++) {
				uint32_t j =
					glint_permute(i, n, seed * 2654435761u);
				bad += j >= n || seen[j < n ? j : 0]++;
				same += j ==
					glint_permute(i, n,
						      seed * 2654435761u + 1);
			}
			CHECK(!bad, "n %u seed %u: %u repeats or out of range",
			      n, seed, bad);
			CHECK(n < 32 || same < n / 4,
			      "n %u: %u of %u the same under the next seed", n,
			      same, n);
		}
}

/* glint_sobol2(): each block of 16 points from a multiple of 16, under
 * any seed, is a (0, 4, 2)-net: one point in each cell of every 2^a x
 * 2^(4-a) grid; the blocks of a pixel's hits stratify each hit alone. */
static void test_sobol_blocks(void)
{
	for (uint32_t seed = 0; seed < 4; seed++)
		for (uint32_t blk = 0; blk < 4; blk++)
			for (int a = 0; a <= 4; a++) {
				int nx = 1 << a, ny = 16 >> a, bad = 0;
				unsigned char cell[16] = { 0 };
				for (uint32_t k = 0; k < 16; k++) {
					double u[2];
					glint_sobol2(blk * 16 + k, seed * 77u,
						     u);
					int c = (int)(u[0] * nx) * ny +
						(int)(u[1] * ny);
					bad += cell[c]++ > 0;
				}
				CHECK(!bad,
				      "seed %u block %u, %d x %d: %d cells "
				      "twice",
				      seed, blk, nx, ny, bad);
			}
}

int main(void)
{
	RUN(test_render_factor);
	RUN(test_footprint);
	RUN(test_factor_derivative);
	RUN(test_footprint_rest);
	RUN(test_footprint_fixed);
	RUN(test_sample_pattern);
	RUN(test_permute);
	RUN(test_sobol_blocks);
	RUN(test_furnace_lambert);
	RUN(test_furnace_ts);
	RUN(test_silhouette);
	RUN(test_thin_lens);
	RUN(test_mesh_furnace);
	RUN(test_deterministic);
	RUN(test_pixel_step);
	return test_result();
}
