/* SPDX-License-Identifier: MIT */
/*
 * The camera interface on the simulated camera: capabilities, frames that
 * carry the exposure actually applied (the sim applies a new exposure two
 * frames late, as real sensors do, and glint_camera_capture() drops those
 * frames), real frame timing on a fake clock, and refusals.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera.h"
#include "core/error.h"

static void test_describe(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_camera_info in;

	CHECK(glint_camera_open("sim", "sim:width=32,height=24", &clk, &cam) ==
		      0,
	      "%s", glint_error_msg());
	if (!cam)
		return;
	glint_camera_describe(cam, &in);
	CHECK(in.width == 32 && in.height == 24 && in.manual_exposure &&
		      !strcmp(in.formats[0], "RGGB16") && in.bit_depth == 12,
	      "%dx%d manual %d format %s bits %d", in.width, in.height,
	      in.manual_exposure, in.formats[0], in.bit_depth);
	glint_camera_close(cam);
}

static void test_applied_exposure(void)
{
	struct glint_fake_clock fc = { 100 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_frame f;
	int dropped;

	glint_camera_open("sim", "sim:latency=2,noise=0", &clk, &cam);
	/* 4 ms requested; the sim lands it two frames later. */
	CHECK(glint_camera_capture(cam, 0.004, 2, 5, &f, &dropped) == 0, "%s",
	      glint_error_msg());
	CHECK(fabs(f.exposure_s - 0.004) < 1e-9 && f.gain == 2,
	      "frame reports %g s, gain %g", f.exposure_s, f.gain);
	CHECK(dropped == 2, "dropped %d frames, expected the latency 2",
	      dropped);
	/* Frame timing: three frames at >= 1/30 s each, the last one
	 * exposed for 4 ms. */
	CHECK(fabs((f.t_end - f.t_start) - 0.004) < 1e-12 &&
		      f.t_start >= 100 + 2.0 / 30 - 1e-9,
	      "exposure window [%g, %g]", f.t_start, f.t_end);
	/* Twice the exposure, noise-free: twice the signal above black. */
	struct glint_frame g;
	double s1 = 0, s2 = 0;
	CHECK(glint_camera_capture(cam, 0.008, 2, 5, &g, NULL) == 0, "%s",
	      glint_error_msg());
	for (int i = 0; i < f.width * f.height; i++) {
		if (g.data[i] >= 4095 || f.data[i] < 200)
			continue; /* clipped or in the noise */
		s1 += f.data[i] - f.black_level;
		s2 += g.data[i] - g.black_level;
	}
	CHECK(fabs(s2 / s1 - 2) < 0.01, "signal ratio %g for 2x exposure",
	      s2 / s1);
	/* A long exposure stretches the frame period. */
	double t_before = fc.t;
	glint_frame_release(&g);
	CHECK(glint_camera_capture(cam, 0.5, 1, 5, &g, NULL) == 0, "%s",
	      glint_error_msg());
	CHECK(fc.t - t_before >= 0.5, "a 0.5 s exposure took %g s of clock",
	      fc.t - t_before);
	glint_frame_release(&f);
	glint_frame_release(&g);
	glint_camera_close(cam);
}

static void test_refusals(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_frame f;

	glint_camera_open("sim", "sim:manual=0", &clk, &cam);
	CHECK(glint_camera_capture(cam, 0.01, 1, 3, &f, NULL) == -ENOTSUP,
	      "a camera without manual exposure bracketed");
	CHECK_MSG(glint_error_msg(), "no manual exposure control");
	glint_camera_close(cam);

	glint_camera_open("sim", NULL, &clk, &cam);
	CHECK(glint_camera_capture(cam, 5, 1, 3, &f, NULL) == -ERANGE,
	      "5 s accepted");
	CHECK_MSG(glint_error_msg(), "exposure 5 s outside its range");
	/* More latency than the drop budget allows. */
	glint_camera_close(cam);
	glint_camera_open("sim", "sim:latency=4", &clk, &cam);
	CHECK(glint_camera_capture(cam, 0.02, 1, 2, &f, NULL) == -ETIMEDOUT,
	      "unconfirmed exposure accepted");
	CHECK_MSG(glint_error_msg(), "not applied after 3 frames");
	glint_camera_close(cam);

	CHECK(glint_camera_open("v4l3", NULL, &clk, &cam) < 0,
	      "unknown backend opened");
	CHECK(glint_camera_open("sim", "sim:widht=3", &clk, &cam) < 0,
	      "misspelt option accepted");
	CHECK_MSG(glint_error_msg(), "option widht=3");
}

int main(void)
{
	glint_backends_register();
	RUN(test_describe);
	RUN(test_applied_exposure);
	RUN(test_refusals);
	return test_result();
}
