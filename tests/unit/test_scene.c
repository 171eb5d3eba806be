/* SPDX-License-Identifier: MIT */
/* Scene files: parsing, defaults, the circle form, and bad input. */
#include "test.h"

#include "core/error.h"
#include "fit/fit.h"
#include "fit/fit_data.h"
#include "fit/scene/scene.h"

#include <jansson.h>

static const char *write_file(const char *name, const char *text)
{
	const char *p = tmp_path(name);
	FILE *fp = fopen(p, "w");
	fputs(text, fp);
	fclose(fp);
	return p;
}

#define CAMERA                                                                 \
	"\"camera\": {\"width\": 640, \"height\": 480, \"focal_length_mm\": "  \
	"50, \"sensor_width_mm\": 36}"
#define ENV "\"environment\": {\"path\": \"env.hdr\"}"

static void test_good_scene(void)
{
	struct glint_scene s;
	const char *p = write_file(
		"good.json",
		"{\"units\": \"metres\", " CAMERA ", \"sphere\": "
		"{\"diameter_m\": 0.1, \"centre\": [0, 0, -1]}, " ENV ", "
		"\"render\": {\"samples_per_pixel\": 9, \"light_samples\": "
		"32}}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	CHECK_NEAR(s.cam.fpx, 50.0 / 36 * 640, 1e-9, "focal length in px");
	CHECK_NEAR(s.sphere_radius, 0.05, 1e-15, "radius");
	/* the file's samples kept; those it does not give, 128 a pixel */
	CHECK(s.spp == 9 && s.light_samples == 32 && s.brdf_samples == 14,
	      "render settings %d %d %d", s.spp, s.light_samples,
	      s.brdf_samples);
	CHECK(strstr(s.env_path, test_tmpdir()) == s.env_path,
	      "env path '%s' not resolved against the scene's folder",
	      s.env_path);
}

/* A camera with a blur gets 16 primary hits a pixel unless the file says;
 * the colour filter array names each site's colour. */
static void test_blur_and_mosaic(void)
{
	struct glint_scene s;
	const char *p = write_file(
		"plain.json", "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
			      "\"centre\": [0, 0, -1]}, " ENV "}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	CHECK(s.spp == 4 && s.cam.cfa[0] < 0, "plain: spp %d, cfa %d", s.spp,
	      s.cam.cfa[0]);
	CHECK(s.light_samples == 32 && s.brdf_samples == 32,
	      "plain: %d + %d samples a hit, expected 32 + 32", s.light_samples,
	      s.brdf_samples);
	p = write_file("mosaic.json",
		       "{\"camera\": {\"width\": 64, \"height\": 48, "
		       "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		       "\"psf_sigma_px\": 0.6, \"olpf\": true, \"cfa\": "
		       "\"GRBG\"}, \"sphere\": {\"diameter_m\": 0.1, "
		       "\"centre\": [0, 0, -1]}, " ENV "}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	CHECK(s.spp == 16, "blurred camera: spp %d, expected 16", s.spp);
	/* a pixel's 128 + 128 samples shared by its 16 hits */
	CHECK(s.light_samples == 8 && s.brdf_samples == 8,
	      "blurred camera: %d + %d samples a hit, expected 8 + 8",
	      s.light_samples, s.brdf_samples);
	CHECK(s.cam.cfa[0] == 1 && s.cam.cfa[1] == 0 && s.cam.cfa[2] == 2 &&
		      s.cam.cfa[3] == 1,
	      "GRBG read as %d %d %d %d", s.cam.cfa[0], s.cam.cfa[1],
	      s.cam.cfa[2], s.cam.cfa[3]);
	p = write_file("mosaic9.json",
		       "{\"camera\": {\"width\": 64, \"height\": 48, "
		       "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		       "\"olpf\": true}, \"sphere\": {\"diameter_m\": 0.1, "
		       "\"centre\": [0, 0, -1]}, " ENV
		       ", \"render\": {\"samples_per_pixel\": 9}}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	CHECK(s.spp == 9, "the file's spp with a blur: %d, expected 9", s.spp);
}

/* The fit's pixel sets on a demosaiced photo: one pixel of each s x s
 * block, and the mosaic's four sites equally often in the fine set and in
 * the coarse one; without a mosaic, every s-th row and column. */
static void check_picks(const signed char cfa[4], int s)
{
	int fine[4] = { 0 }, coarse[4] = { 0 }, n = 48 * s;

	for (int by = 0; by < n / s; by++)
		for (int bx = 0; bx < n / s; bx++) {
			int in_block = 0;
			for (int y = by * s; y < (by + 1) * s; y++)
				for (int x = bx * s; x < (bx + 1) * s; x++) {
					if (!fit_data_fine_pick(cfa, x, y, s))
						continue;
					in_block++;
					int site = (x & 1) + 2 * (y & 1);
					fine[site]++;
					coarse[site] += fit_data_coarse_pick(
						cfa, x, y, s);
					if (cfa[0] < 0)
						CHECK(x % s == 0 && y % s == 0,
						      "no mosaic, stride %d: "
						      "(%d, %d) picked",
						      s, x, y);
				}
			CHECK(in_block == 1,
			      "stride %d: block (%d, %d) gave %d", s, bx, by,
			      in_block);
		}
	int blocks = (n / s) * (n / s);
	for (int k = 0; k < 4 && cfa[0] >= 0; k++) {
		CHECK(fine[k] == blocks / 4,
		      "stride %d: site %d %d times of %d", s, k, fine[k],
		      blocks);
		CHECK(coarse[k] == blocks / 64,
		      "stride %d: coarse site %d %d times, expected %d", s, k,
		      coarse[k], blocks / 64);
	}
	if (cfa[0] < 0)
		CHECK(coarse[0] + coarse[1] + coarse[2] + coarse[3] ==
			      blocks / 16,
		      "no mosaic, stride %d: coarse %d", s,
		      coarse[0] + coarse[1] + coarse[2] + coarse[3]);
}

static void test_mosaic_picks(void)
{
	struct glint_pinhole cam;
	CHECK(glint_pinhole_set_cfa(&cam, "RGGB") == 0, "%s",
	      glint_error_msg());
	for (int s = 1; s <= 4; s++)
		check_picks(cam.cfa, s);
	glint_pinhole_set_cfa(&cam, NULL);
	for (int s = 1; s <= 4; s++)
		check_picks(cam.cfa, s);
}

static void test_circle_scene(void)
{
	struct glint_scene s;
	/* On the axis: D = R / sin(atan(r / f)). */
	const char *p = write_file(
		"circle.json",
		"{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, \"circle_px\": "
		"{\"cx\": 320, \"cy\": 240, \"r\": 100}}, " ENV "}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	double f = 50.0 / 36 * 640;
	double d = 0.05 / sin(atan(100 / f));
	CHECK_NEAR(s.sphere_centre.z, -d, 1e-12, "depth from the circle");
	CHECK_NEAR(s.sphere_centre.x, 0, 1e-12, "x on the axis");
}

static void expect_error(const char *name, const char *json, const char *frag1,
			 const char *frag2)
{
	struct glint_scene s;
	const char *p = write_file(name, json);
	CHECK(glint_scene_load(p, &s) < 0, "%s accepted", name);
	CHECK_MSG(glint_error_msg(), name);
	CHECK_MSG(glint_error_msg(), frag1);
	if (frag2)
		CHECK_MSG(glint_error_msg(), frag2);
}

static void test_bad_scenes(void)
{
	expect_error("syntax.json", "{\"camera\": {\"width\": 640,,}}",
		     "syntax.json:1:", NULL);
	expect_error("nocam.json", "{" ENV "}", "camera is missing", NULL);
	expect_error("focal.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": -5, \"sensor_width_mm\": 36}, "
		     "\"sphere\": {}, " ENV "}",
		     "camera.focal_length_mm = -5",
		     "expected a number in (0, 100000]");
	expect_error("width.json",
		     "{\"camera\": {\"width\": 64.5, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36}, "
		     "\"sphere\": {}, " ENV "}",
		     "camera.width = 64.5", "an integer");
	expect_error("both.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		     "\"pixel_pitch_um\": 4}, \"sphere\": {}, " ENV "}",
		     "exactly one of sensor_width_mm and pixel_pitch_um", NULL);
	expect_error("typo.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1], \"colour\": 1}, " ENV "}",
		     "sphere.colour: unknown key", NULL);
	expect_error("behind.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,1]}, " ENV "}",
		     "not in front of the camera", NULL);
	expect_error("noenv.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}}",
		     "environment is missing", NULL);
	expect_error("nan.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,\"x\"]}, " ENV "}",
		     "sphere.centre = [0,0,\"x\"]",
		     "expected an array of 3 finite numbers");
	expect_error("spp.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV
		     ", \"render\": {\"samples_per_pixel\": 0}}",
		     "render.samples_per_pixel = 0", "[1, 4096]");
	expect_error("nosamples.json",
		     "{" CAMERA ", \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV
		     ", \"render\": {\"light_samples\": 0, "
		     "\"brdf_samples\": 0}}",
		     "light_samples + brdf_samples is 0", "at least 1");
	expect_error("pose.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		     "\"up\": [0, 0, -1]}, \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV "}",
		     "parallel to the view direction", NULL);
	expect_error("lens.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		     "\"f_number\": 2.8}, \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV "}",
		     "needs camera.focus_distance_m", NULL);
	expect_error("cfa.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		     "\"cfa\": \"RGBG\"}, \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV "}",
		     "colour filter array 'RGBG'", "RGGB, GRBG, GBRG or BGGR");
	expect_error("cfa2.json",
		     "{\"camera\": {\"width\": 64, \"height\": 48, "
		     "\"focal_length_mm\": 5, \"sensor_width_mm\": 36, "
		     "\"cfa\": 4}, \"sphere\": {\"diameter_m\": 0.1, "
		     "\"centre\": [0,0,-1]}, " ENV "}",
		     "camera.cfa: expected a string", NULL);
	struct glint_scene s;
	CHECK(glint_scene_load(tmp_path("absent.json"), &s) < 0,
	      "missing file loaded");
	CHECK_MSG(glint_error_msg(), "absent.json");
}

/* The fit's env and lobe samples a hit follow the scene's hits a pixel
 * when not given: 32 a pixel over more than 4 hits, 8 a hit up to 4; the
 * cap on raising them the same at 256 a pixel; a given count kept. */
static void test_fit_samples(void)
{
	static const int spp[] = { 1, 4, 9, 16, 64 },
			 want[] = { 8, 8, 4, 2, 1 },
			 cap[] = { 64, 64, 28, 16, 4 };
	for (int i = 0; i < 5; i++) {
		struct glint_fit_opts o;
		glint_fit_default_opts(&o);
		glint_fit_resolve_samples(&o, spp[i]);
		CHECK(o.light_samples == want[i] && o.lobe_samples == want[i] &&
			      o.max_samples == cap[i],
		      "%d hits a pixel: %d + %d samples a hit, cap %d; "
		      "expected %d + %d, cap %d",
		      spp[i], o.light_samples, o.lobe_samples, o.max_samples,
		      want[i], want[i], cap[i]);
		o.light_samples = o.lobe_samples = 5;
		o.max_samples = 40;
		glint_fit_resolve_samples(&o, spp[i]);
		CHECK(o.light_samples == 5 && o.max_samples == 40,
		      "%d hits: given 5, cap 40 became %d, %d", spp[i],
		      o.light_samples, o.max_samples);
	}
	CHECK(glint_scene_samples_default(4) == 32 &&
		      glint_scene_samples_default(16) == 8 &&
		      glint_scene_samples_default(1) == 32,
	      "render samples a hit: %d at 4 hits, %d at 16, %d at 1",
	      glint_scene_samples_default(4), glint_scene_samples_default(16),
	      glint_scene_samples_default(1));
}

int main(void)
{
	RUN(test_good_scene);
	RUN(test_blur_and_mosaic);
	RUN(test_fit_samples);
	RUN(test_mosaic_picks);
	RUN(test_circle_scene);
	RUN(test_bad_scenes);
	return test_result();
}
