/* SPDX-License-Identifier: MIT */
/*
 * The reference renderer's pixels integrate their area (sim/reference.c):
 * a near-mirror sphere under a disc of light, whose reflection's edge
 * crosses pixels, rendered twice with independent seeds.  Where a
 * pixel's positions are stratified (a 4 x 4 grid; 15 Latin-hypercube
 * rows) the two renders' highlight pixels agree far more closely than
 * independent positions let them (half as far apart, measured: see the
 * checks).
 */
#include "test.h"

#include "core/error.h"
#include "fit/brdf/model.h"
#include "sim/reference.h"

/* A 512 x 256 map: sky 0.05 and, towards (0.2, 0.3, 1), a disc of 0.1
 * rad radius at 100. */
static struct glint_envmap *disc_env(void)
{
	struct glint_image *img = glint_image_new(512, 256);
	struct glint_envmap *env = NULL;
	struct vec3 sun = v3_norm(v3(0.2, 0.3, 1));

	for (int y = 0; y < 256; y++)
		for (int x = 0; x < 512; x++) {
			struct vec3 d = glint_latlong_uv_to_dir(
				(x + 0.5) / 512, (y + 0.5) / 256);
			float *px = glint_image_px(img, x, y);
			px[0] = px[1] = px[2] =
				v3_dot(d, sun) > cos(0.1) ? 100 : 0.05f;
		}
	CHECK(glint_envmap_new(img, NULL, 1, "disc", &env) == 0, "%s",
	      glint_error_msg());
	return env;
}

/* The 64 px scene of test_highlight_pixels(): the sphere 18 px in
 * radius, the disc's reflection about 2 px across. */
static void highlight_scene(struct glint_scene *sc)
{
	glint_scene_defaults(sc);
	glint_pinhole_init(&sc->cam, 64, 64, 0.1, 0.036 / 64, 0, 0, v3(0, 0, 0),
			   v3(0, 0, -1), v3(0, 1, 0));
	sc->sphere_centre = v3(0, 0, -0.5);
	sc->sphere_radius = 0.05;
}

/* Renders in pairs of seeds (1 and 2, 3 and 4, 5 and 6) at spp a pixel:
 * the mean absolute difference of a pair's highlight pixels (mean value
 * above 1) over the highlight's mean value, over the three pairs. */
static double seed_spread_opts(const struct glint_scene *sc,
			       const struct glint_envmap *env,
			       struct glint_reference_opts ro, int *nhi,
			       double *mean)
{
	static const double p[8] = { 0, 0, 0, 0.7, 0.7, 0.7, 0.002, 2.6 };
	struct glint_image *a = glint_image_new(sc->cam.width, sc->cam.height);
	struct glint_image *b = glint_image_new(sc->cam.width, sc->cam.height);
	double diff = 0, sum = 0, all = 0;

	*nhi = 0;
	for (uint32_t seed = 1; seed < 7; seed += 2) {
		ro.seed = seed;
		CHECK(glint_reference_render(sc, env,
					     &glint_model_torrance_sparrow, p,
					     &ro, a) == 0,
		      "%s", glint_error_msg());
		ro.seed = seed + 1;
		CHECK(glint_reference_render(sc, env,
					     &glint_model_torrance_sparrow, p,
					     &ro, b) == 0,
		      "%s", glint_error_msg());
		for (int i = 0; i < sc->cam.width * sc->cam.height; i++) {
			double va = a->data[3 * i], vb = b->data[3 * i];
			all += va + vb;
			if ((va + vb) / 2 <= 1)
				continue;
			diff += fabs(va - vb);
			sum += (va + vb) / 2;
			(*nhi)++;
		}
	}
	*nhi /= 3;
	if (mean)
		*mean = all / (6.0 * sc->cam.width * sc->cam.height);
	glint_image_free(a);
	glint_image_free(b);
	return sum > 0 ? diff / sum : NAN;
}

static double seed_spread(const struct glint_scene *sc,
			  const struct glint_envmap *env, int spp, int *nhi)
{
	struct glint_reference_opts ro;

	glint_reference_default_opts(&ro);
	ro.spp = spp;
	ro.samples = 4;
	return seed_spread_opts(sc, env, ro, nhi, NULL);
}

static void test_highlight_pixels(void)
{
	struct glint_envmap *env = disc_env();
	struct glint_scene sc;
	int nhi;

	if (!env)
		return;
	/* 64 px, the sphere 18 px in radius: its mirror direction turns
	 * 0.11 rad a pixel, so the disc's reflection is 2 px across. */
	highlight_scene(&sc);
	double grid = seed_spread(&sc, env, 16, &nhi);
	printf("  4 x 4 grid: %d highlight pixels, seeds apart by %.4f\n", nhi,
	       grid);
	CHECK(nhi >= 4, "%d highlight pixels", nhi);
	/* Measured: 0.088 stratified, 0.171 with independent
	 * positions. */
	CHECK(grid < 0.12, "4 x 4 grid: seeds apart by %.4f", grid);
	double lhs = seed_spread(&sc, env, 15, &nhi);
	printf("  15 Latin-hypercube rows: seeds apart by %.4f\n", lhs);
	/* Measured: 0.088, and 0.151 independent. */
	CHECK(lhs < 0.12, "15 rows: seeds apart by %.4f", lhs);

	/* No samples: refused, not an image of zeros. */
	struct glint_reference_opts ro;
	struct glint_image *img = glint_image_new(64, 64);
	glint_reference_default_opts(&ro);
	ro.spp = 0;
	static const double p[8] = { 0, 0, 0, 1, 1, 1, 0.1, 1.5 };
	CHECK(glint_reference_render(&sc, env, &glint_model_torrance_sparrow, p,
				     &ro, img) < 0,
	      "spp 0 accepted");
	CHECK_MSG(glint_error_msg(), "0 samples per pixel");
	glint_image_free(img);
	glint_envmap_free(env);
}

/* Adaptive sampling (opts.rel_noise): the highlight's pixels, whose
 * first round is far noisier than rel_noise, get more rounds, so two
 * seeds agree more closely than at one round; the image's mean stays
 * that of the plain render (its value is the extra rounds' mean alone);
 * rounds are counted and capped. */
static void test_adaptive(void)
{
	struct glint_envmap *env = disc_env();
	struct glint_scene sc;
	struct glint_reference_opts ro;
	int nhi, npx = 64 * 64;
	long rounds = 0;
	double mean_plain, mean_adapt, mean_fine;

	if (!env)
		return;
	highlight_scene(&sc);
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	ro.samples = 4;
	double plain = seed_spread_opts(&sc, env, ro, &nhi, &mean_plain);
	ro.rel_noise = 0.02;
	ro.max_rounds = 16;
	ro.rounds = &rounds;
	double adapt = seed_spread_opts(&sc, env, ro, &nhi, &mean_adapt);
	printf("  highlight seeds apart by %.4f at one round, %.4f adaptive "
	       "(%.2f rounds a pixel)\n",
	       plain, adapt, (double)rounds / npx);
	CHECK(adapt < 0.6 * plain, "adaptive: seeds apart by %.4f, %.4f plain",
	      adapt, plain);
	CHECK(rounds > npx && rounds < 16L * npx,
	      "%ld rounds over %d pixels (1 to 16 each)", rounds, npx);
	/* the mean against a plain render at 16 times the samples: what it
	 * catches is a value not normalised over its rounds (a refined pixel
	 * off by its round count); measured 0.04856 adaptive against 0.04900,
	 * the one-round render 0.04852, so 2 % is their own noise.  Keeping
	 * the first round in the value leans it too little on this scene to
	 * show here (0.04902). */
	glint_reference_default_opts(&ro);
	ro.spp = 64;
	ro.samples = 4;
	seed_spread_opts(&sc, env, ro, &nhi, &mean_fine);
	printf("  image mean %.5f plain, %.5f adaptive, %.5f at 64 spp\n",
	       mean_plain, mean_adapt, mean_fine);
	CHECK(fabs(mean_adapt / mean_fine - 1) < 0.02,
	      "adaptive mean %.5f against %.5f", mean_adapt, mean_fine);

	/* A cap of no rounds: refused. */
	struct glint_image *img = glint_image_new(64, 64);
	static const double p[8] = { 0, 0, 0, 1, 1, 1, 0.1, 1.5 };
	glint_reference_default_opts(&ro);
	ro.rel_noise = 0.01;
	ro.max_rounds = 0;
	CHECK(glint_reference_render(&sc, env, &glint_model_torrance_sparrow, p,
				     &ro, img) < 0,
	      "max_rounds 0 accepted");
	CHECK_MSG(glint_error_msg(), "at most 0 rounds");
	glint_image_free(img);
	glint_envmap_free(env);
}

int main(void)
{
	RUN(test_highlight_pixels);
	RUN(test_adaptive);
	return test_result();
}
