/* SPDX-License-Identifier: MIT */
/*
 * Brackets on the simulated camera.  Its test card spans 6 decades plus a
 * disk 1000x brighter: the bracket must end with no saturated ROI pixel in
 * its shortest frame and the ROI's darkest pixels above the noise floor in
 * its longest; the darkest need more than the 2 s maximum exposure, so the
 * planner must raise gain and say so.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/bracket.h"
#include "core/error.h"

static void test_covers_range(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	int sat;
	double p01;

	CHECK(glint_camera_open("sim", "sim:noise=0", &clk, &cam) == 0, "%s",
	      glint_error_msg());
	glint_bracket_default_opts(&o);
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == 0, "%s",
	      glint_error_msg());
	CHECK(b.covered_low && b.covered_high && !b.truncated,
	      "coverage low %d high %d truncated %d with %d frames",
	      b.covered_low, b.covered_high, b.truncated, b.n);
	glint_frame_roi_stats(&b.frames[0], &all, &sat, &p01);
	CHECK(sat == 0, "%d saturated pixels in the shortest frame (%g s)", sat,
	      b.frames[0].exposure_s);
	glint_frame_roi_stats(&b.frames[b.n - 1], &all, &sat, &p01);
	CHECK(p01 >= o.floor_dn,
	      "darkest pixels %g DN above black in the "
	      "longest frame: expected >= %g",
	      p01, o.floor_dn);
	CHECK(b.used_gain && b.frames[b.n - 1].gain > 1,
	      "gain not raised (last frame gain %g, %g s)",
	      b.frames[b.n - 1].gain, b.frames[b.n - 1].exposure_s);
	for (int i = 1; i < b.n; i++) {
		double r = b.frames[i].exposure_s * b.frames[i].gain /
			   (b.frames[i - 1].exposure_s * b.frames[i - 1].gain);
		/* 1 EV, or less where a camera limit clamps it, within the
		 * camera's 10 us exposure step. */
		double prev = b.frames[i - 1].exposure_s;
		CHECK(r > 1.05 && r <= 2.0 * (1 + 1e-5 / prev) + 1e-9,
		      "step %d is %g x from %g s: expected 1 EV or less", i, r,
		      prev);
	}
	/* The time spent is at least the exposures it took. */
	double sum = 0;
	for (int i = 0; i < b.n; i++)
		sum += b.frames[i].exposure_s;
	CHECK(b.seconds >= sum,
	      "bracket took %g s of clock for %g s of "
	      "exposure",
	      b.seconds, sum);
	printf("%d frames, %.4f .. %.2f s, gain up to %g, %.1f s\n", b.n,
	       b.frames[0].exposure_s, b.frames[b.n - 1].exposure_s,
	       b.frames[b.n - 1].gain, b.seconds);
	glint_bracket_release(&b);
	glint_camera_close(cam);
}

static void test_caps_and_refusal(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };

	glint_camera_open("sim", "sim:noise=0", &clk, &cam);
	glint_bracket_default_opts(&o);
	o.max_frames = 3;
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == 0, "%s",
	      glint_error_msg());
	CHECK(b.n == 3 && b.truncated, "%d frames, truncated %d", b.n,
	      b.truncated);
	glint_bracket_release(&b);
	glint_camera_close(cam);

	glint_camera_open("sim", "sim:manual=0", &clk, &cam);
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == -ENOTSUP,
	      "a camera without manual exposure bracketed");
	CHECK_MSG(glint_error_msg(), "no manual exposure control");
	glint_camera_close(cam);
}

int main(void)
{
	glint_backends_register();
	RUN(test_covers_range);
	RUN(test_caps_and_refusal);
	return test_result();
}
