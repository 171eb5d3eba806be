/* SPDX-License-Identifier: MIT */
/* Scene files: parsing, defaults, the circle form, and bad input. */
#include "test.h"

#include "core/error.h"
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
		"\"render\": {\"samples_per_pixel\": 9}}");
	CHECK(glint_scene_load(p, &s) == 0, "%s", glint_error_msg());
	CHECK_NEAR(s.cam.fpx, 50.0 / 36 * 640, 1e-9, "focal length in px");
	CHECK_NEAR(s.sphere_radius, 0.05, 1e-15, "radius");
	CHECK(s.spp == 9 && s.light_samples == 32, "render settings %d %d",
	      s.spp, s.light_samples);
	CHECK(strstr(s.env_path, test_tmpdir()) == s.env_path,
	      "env path '%s' not resolved against the scene's folder",
	      s.env_path);
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
	struct glint_scene s;
	CHECK(glint_scene_load(tmp_path("absent.json"), &s) < 0,
	      "missing file loaded");
	CHECK_MSG(glint_error_msg(), "absent.json");
}

int main(void)
{
	RUN(test_good_scene);
	RUN(test_circle_scene);
	RUN(test_bad_scenes);
	return test_result();
}
