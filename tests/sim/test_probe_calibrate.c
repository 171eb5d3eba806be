/* SPDX-License-Identifier: MIT */
/*
 * A probe calibrated by a gray ball (capture/probe/probe_calibrate.h),
 * against ground truth.  The light is the sun-sky class (sim/
 * light_class.h: a sun 0.53 degrees across holding most of the
 * irradiance).  The chrome ball is rendered forward by the simulator
 * (sim/probe_sim.c), blurred by the sim camera's optics, and made wrong
 * the two ways a real probe is: its channels scaled by 0.9, 1, 1.12 (a
 * mirror whose reflectance is not its specification) and the sun clipped
 * (saturated in the shortest frame: weight 0), then unwrapped by glint.
 * The gray ball (albedo 0.18) is rendered under the true map by the
 * independent reference renderer (sim/reference.h).  The calibration
 * must give back the map's scale within 3 % and the sun's flux within 5 %
 * (and within 3 of their sigmas) where the probe alone had the sun's flux
 * far too low, and the sun's direction within 0.5 degrees where the
 * clipped spot's centroid put it 0.85 off; and refuse a gray ball whose
 * albedo is given 10x wrong and a "gray" ball that is the mirror, naming
 * why.  `glint probe calibrate` (argv[1]) does the same from files.
 */
#include "test.h"

#include "capture/probe/probe_calibrate.h"
#include "core/error.h"
#include "fit/brdf/model.h"
#include "sim/light_class.h"
#include "sim/probe_sim.h"
#include "sim/reference.h"
#include "sim/sensor.h"

#include <errno.h>
#include <sys/wait.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

enum { W = 320, H = 240 };
static const double FPX = 640, RADIUS_PX = 96;
static const double MIRROR_SCALE[3] = { 0.9, 1.0, 1.12 };
static const double ALBEDO = 0.18;
static const char *glint_path; /* the command, when given */

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static double ball_distance(void)
{
	return 1 / sin(atan(RADIUS_PX / FPX));
}

static void ball_geom(struct glint_unwrap_opts *o)
{
	glint_unwrap_default_opts(o);
	o->fpx = FPX;
	o->ball_cx = W / 2.0;
	o->ball_cy = H / 2.0;
	o->ball_r = RADIUS_PX;
}

/* The probe photo, wrong as described above, with its merge's variance
 * and weights; unwrapped by glint into dir/probe.exr and its sources. */
static int unwrap_probe(const struct glint_image *truth, const char *env_path,
			double *clip_level)
{
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };
	struct glint_image *img = NULL;
	struct glint_sensor s;
	int ret = glint_sim_mirror_ball(truth, W, H, FPX,
					v3(0, 0, -ball_distance()), 1, n, k, 12,
					&img);
	CHECK(ret == 0, "%s", glint_error_msg());
	if (ret < 0)
		return ret;
	glint_sensor_default(&s);
	CHECK(glint_sensor_optics(&s, img) == 0, "%s", glint_error_msg());
	struct glint_image *var = glint_image_new(W, H),
			   *wt = glint_image_new(W, H);
	gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
	gsl_rng_set(rng, 5);
	/* Clipped at 100 x the ball's median: the sun alone. */
	double *g = malloc(sizeof(double) * W * H), clip;
	int ng = 0;
	for (size_t i = 0; i < (size_t)W * H; i++)
		if (img->data[i * 3 + 1] > 0)
			g[ng++] = img->data[i * 3 + 1];
	qsort(g, (size_t)ng, sizeof(double), cmp_double);
	clip = 100 * g[ng / 2];
	free(g);
	*clip_level = clip;
	int clipped = 0;
	for (size_t i = 0; i < (size_t)W * H; i++) {
		int sat = 0;
		for (int c = 0; c < 3; c++) {
			float *v = &img->data[i * 3 + c];
			*v = (float)(*v * MIRROR_SCALE[c]);
			if (*v > clip) {
				*v = (float)clip;
				sat = 1;
			}
			double sd = 0.01 * *v + 1e-4;
			if (!sat) /* a clipped value is the range's end */
				*v += (float)gsl_ran_gaussian(rng, sd);
			var->data[i * 3 + c] = (float)(sd * sd);
		}
		clipped += sat;
		for (int c = 0; c < 3; c++)
			wt->data[i * 3 + c] = sat ? 0.0f : 1.0f;
	}
	gsl_rng_free(rng);
	CHECK(clipped > 0, "the sun is clipped in the probe (%d pixels)",
	      clipped);
	struct glint_unwrap_opts o;
	ball_geom(&o);
	o.psf_sigma_px = s.psf_sigma_px;
	o.olpf = 1;
	o.variance = var;
	o.weights = wt;
	ret = glint_probe_unwrap_write(img, &o, env_path, NULL, NULL);
	CHECK(ret == 0, "unwrap: %s", glint_error_msg());
	glint_image_free(img);
	glint_image_free(var);
	glint_image_free(wt);
	return ret;
}

/* The gray ball under the true map, from the reference renderer. */
static struct glint_image *gray_ball(const struct glint_image *truth)
{
	struct glint_scene sc;
	struct glint_envmap *env = NULL;
	struct glint_reference_opts ro;
	const struct glint_model *lambert = glint_model_find("lambert");
	double p[GLINT_MAX_PARAMS] = { ALBEDO, ALBEDO, ALBEDO };
	struct glint_image *img = glint_image_new(W, H),
			   *copy = glint_image_dup(truth);

	glint_scene_defaults(&sc);
	double pitch = 1e-6;
	glint_pinhole_init(&sc.cam, W, H, FPX * pitch, pitch, 0, 0, v3(0, 0, 0),
			   v3(0, 0, -1), v3(0, 1, 0));
	sc.sphere_radius = 1;
	sc.sphere_centre = v3(0, 0, -ball_distance());
	double rot[3] = { 0, 0, 0 };
	CHECK(lambert != NULL, "the lambert model");
	if (!lambert || glint_envmap_new(copy, rot, 1, "truth", &env) < 0) {
		CHECK(0, "%s", glint_error_msg());
		glint_image_free(img);
		return NULL;
	}
	glint_reference_default_opts(&ro);
	/* Enough samples that the sun's heavy-tailed Monte Carlo noise
	 * does not move the scale: at 4 x 16 a pixel the true map itself
	 * gave 0.965 for 1. */
	ro.spp = 9;
	ro.samples = 64;
	CHECK(glint_reference_render(&sc, env, lambert, p, &ro, img) == 0, "%s",
	      glint_error_msg());
	glint_envmap_free(env);
	return img;
}

static void test_calibrate(void)
{
	struct glint_image *truth = NULL, *env = NULL, *gray;
	char env_path[512], src_path[512];
	double clip;
	struct vec3 sun_dir;
	double sun[3];

	snprintf(env_path, sizeof(env_path), "%s/probe.exr", test_tmpdir());
	snprintf(src_path, sizeof(src_path), "%s/probe-sources.json",
		 test_tmpdir());
	CHECK(glint_sim_light_class("sun-sky", 1024, &truth) == 0, "%s",
	      glint_error_msg());
	CHECK(glint_sim_light_class_sources("sun-sky", &sun_dir, &sun, 1) == 1,
	      "one sun");
	if (!truth || unwrap_probe(truth, env_path, &clip) < 0)
		return;
	struct glint_light_sources src;
	CHECK(glint_image_read(env_path, &env) == 0, "%s", glint_error_msg());
	CHECK(glint_probe_sources_read(src_path, &src) == 0, "%s",
	      glint_error_msg());
	gray = gray_ball(truth);
	if (!env || !gray || src.n < 1) {
		CHECK(src.n >= 1, "the probe found %d sources", src.n);
		goto out;
	}
	/* The sun among the probe's sources: the one nearest its
	 * direction. */
	int ks = 0;
	for (int k = 1; k < src.n; k++)
		if (v3_dot(src.s[k].dir, sun_dir) >
		    v3_dot(src.s[ks].dir, sun_dir))
			ks = k;
	CHECK(src.s[ks].saturated, "the probe marks the sun clipped");
	printf("probe alone: %d sources; the sun's flux %.3f %.3f %.3f of "
	       "the truth's (clipped at %.3g)\n",
	       src.n, src.s[ks].flux[0] / sun[0], src.s[ks].flux[1] / sun[1],
	       src.s[ks].flux[2] / sun[2], clip);
	CHECK(src.s[ks].flux[1] < 0.5 * sun[1],
	      "the clipped probe's sun is far too dim: %.3f of the truth",
	      src.s[ks].flux[1] / sun[1]);

	struct glint_unwrap_opts geom;
	struct glint_calibrate_opts co;
	struct glint_calibration cal;
	ball_geom(&geom);
	glint_calibrate_default_opts(&co);
	for (int c = 0; c < 3; c++) {
		co.albedo[c] = ALBEDO;
		co.albedo_sigma[c] = 0.002;
	}
	int ret = glint_probe_calibrate(env, &src, gray, &geom, &co, &cal);
	CHECK(ret == 0, "calibrate: %s", glint_error_msg());
	if (ret == 0) {
		printf("gray ball: %d pixels, relative RMS %.4f\n", cal.pixels,
		       cal.rel_rms[1]);
		for (int c = 0; c < 3; c++) {
			double want = 1 / MIRROR_SCALE[c];
			double e = cal.scale[c] - want;
			const struct glint_calibrated_source *cs = &cal.src[ks];
			double ef = cs->flux[c] - sun[c];
			printf("channel %d: scale %.4f +- %.4f (truth %.4f); "
			       "sun %.4f +- %.4f (truth %.4f, from the %s)\n",
			       c, cal.scale[c], cal.scale_sigma[c], want,
			       cs->flux[c], cs->flux_sigma[c], sun[c],
			       cs->from_gray ? "gray ball" : "probe");
			CHECK(fabs(e) < 0.03 * want &&
				      fabs(e) < 3 * cal.scale_sigma[c],
			      "channel %d scale %.4f for %.4f (sigma %.4f)", c,
			      cal.scale[c], want, cal.scale_sigma[c]);
			CHECK(cs->from_gray,
			      "the sun's flux from the gray ball");
			CHECK(fabs(ef) < 0.05 * sun[c] &&
				      fabs(ef) < 3 * cs->flux_sigma[c],
			      "channel %d sun %.4f for %.4f (sigma %.4f)", c,
			      cs->flux[c], sun[c], cs->flux_sigma[c]);
		}
		double off = acos(fmin(1, v3_dot(cal.src[ks].dir, sun_dir))) *
			     180 / M_PI;
		printf("the sun's direction %.3f deg off (sigma %.3f; the "
		       "probe's %.3f)\n",
		       off, cal.src[ks].dir_sigma_deg,
		       acos(fmin(1, v3_dot(src.s[ks].dir, sun_dir))) * 180 /
			       M_PI);
		CHECK(off < 0.5 && off < 3 * cal.src[ks].dir_sigma_deg,
		      "the sun's direction from the gray ball %.3f deg off "
		      "(sigma %.3f)",
		      off, cal.src[ks].dir_sigma_deg);
		/* Applied: the map's sun is the calibrated one, no longer
		 * marked clipped. */
		glint_probe_calibration_apply(&cal, env, &src);
		CHECK(!src.s[ks].saturated &&
			      fabs(src.s[ks].flux[1] / sun[1] - 1) < 0.05,
		      "applied: the sun's flux %.4f, clipped %d",
		      src.s[ks].flux[1], src.s[ks].saturated);
		char cal_path[512];
		snprintf(cal_path, sizeof(cal_path), "%s/cal.json",
			 test_tmpdir());
		CHECK(glint_probe_calibration_write(cal_path, env_path, "gray",
						    &cal) == 0,
		      "%s", glint_error_msg());
	}

	/* The command: the same calibration from files, its outputs read
	 * back; a missing --albedo and an output over an input refused. */
	if (glint_path) {
		char gray_path[512], out_path[512], cmd[4096];
		struct glint_light_sources cs;
		snprintf(gray_path, sizeof(gray_path), "%s/gray.exr",
			 test_tmpdir());
		snprintf(out_path, sizeof(out_path), "%s/calibrated.exr",
			 test_tmpdir());
		CHECK(glint_image_write(gray_path, gray, NULL) == 0, "%s",
		      glint_error_msg());
		snprintf(cmd, sizeof(cmd),
			 "'%s' probe calibrate -q '%s' '%s' --focal-px %g "
			 "--ball %g,%g,%g --albedo %g --albedo-sigma 0.002 "
			 "-o '%s'",
			 glint_path, env_path, gray_path, FPX, W / 2.0, H / 2.0,
			 RADIUS_PX, ALBEDO, out_path);
		int st = system(cmd);
		CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "%s: status %d",
		      cmd, st);
		snprintf(cmd, sizeof(cmd), "%s/calibrated-sources.json",
			 test_tmpdir());
		CHECK(glint_probe_sources_read(cmd, &cs) == 0 && cs.n == src.n,
		      "%s: %s", cmd, glint_error_msg());
		if (cs.n == src.n)
			CHECK(fabs(cs.s[ks].flux[1] / sun[1] - 1) < 0.05 &&
				      !cs.s[ks].saturated,
			      "the command's sun: %.4f (truth %.4f)",
			      cs.s[ks].flux[1], sun[1]);
		snprintf(cmd, sizeof(cmd), "%s/calibrated-calibration.json",
			 test_tmpdir());
		CHECK(access(cmd, R_OK) == 0, "%s written", cmd);
		snprintf(cmd, sizeof(cmd),
			 "'%s' probe calibrate -q '%s' '%s' --focal-px 640 "
			 "-o '%s/x.exr' 2>/dev/null",
			 glint_path, env_path, gray_path, test_tmpdir());
		st = system(cmd);
		CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 2,
		      "no --albedo: status %d", st);
		snprintf(cmd, sizeof(cmd),
			 "'%s' probe calibrate -q '%s' '%s' --focal-px 640 "
			 "--albedo 0.18 -o '%s' --force 2>/dev/null",
			 glint_path, env_path, gray_path, gray_path);
		st = system(cmd);
		CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 1,
		      "the gray ball's photo as the output: status %d", st);
		struct glint_image *still = NULL;
		CHECK(glint_image_read(gray_path, &still) == 0 &&
			      !memcmp(still->data, gray->data,
				      sizeof(float) * 3 * W * H),
		      "the input is kept");
		glint_image_free(still);
	}

	/* Refusals, named: the albedo 10x wrong; the mirror as the gray
	 * ball. */
	for (int c = 0; c < 3; c++)
		co.albedo[c] = ALBEDO / 10;
	ret = glint_probe_calibrate(env, &src, gray, &geom, &co, &cal);
	CHECK(ret == -EINVAL, "an albedo 10x wrong is refused (%d)", ret);
	CHECK_MSG(glint_error_msg(), "albedo");
	for (int c = 0; c < 3; c++)
		co.albedo[c] = ALBEDO;
	struct glint_image *mirror = NULL;
	double n[3] = { 3.2, 3.2, 3.2 }, kk[3] = { 3.3, 3.3, 3.3 };
	glint_sim_mirror_ball(truth, W, H, FPX, v3(0, 0, -ball_distance()), 1,
			      n, kk, 3, &mirror);
	ret = glint_probe_calibrate(env, &src, mirror, &geom, &co, &cal);
	CHECK(ret == -EINVAL, "a mirror as the gray ball is refused (%d)", ret);
	CHECK_MSG(glint_error_msg(), "matte");
	glint_image_free(mirror);
out:
	glint_image_free(truth);
	glint_image_free(env);
	glint_image_free(gray);
}

int main(int argc, char **argv)
{
	glint_path = argc > 1 ? argv[1] : NULL;
	RUN(test_calibrate);
	return test_result();
}
