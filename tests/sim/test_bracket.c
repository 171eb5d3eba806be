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

#include "capture/camera/bracket.h"
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
	/* Unsaturated frames shorter than the longest are not kept, so a
	 * capped bracket may keep fewer than the cap. */
	CHECK(b.n >= 1 && b.n <= 3 && b.truncated, "%d frames, truncated %d",
	      b.n, b.truncated);
	glint_bracket_release(&b);
	glint_camera_close(cam);

	glint_camera_open("sim", "sim:manual=0", &clk, &cam);
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == -ENOTSUP,
	      "a camera without manual exposure bracketed");
	CHECK_MSG(glint_error_msg(), "no manual exposure control");
	glint_camera_close(cam);
}

/* The ROI statistics against a sort: the quantile of codes each spread
 * over [c - 1/2, c + 1/2), on a frame of known values, in a ROI. */
static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void test_roi_stats(void)
{
	enum { W = 40, H = 30 };
	uint16_t data[W * H];
	double v[W * H];
	struct glint_frame f = { .width = W,
				 .height = H,
				 .channels = 1,
				 .bit_depth = 12,
				 .data = data,
				 .black_level = 64 };
	struct glint_roi roi = { 5, 4, 35, 24 };
	int n = 0, sat;
	double p01;
	unsigned x = 12345;

	for (int i = 0; i < W * H; i++) {
		x = x * 1103515245u + 12345u;
		data[i] = (uint16_t)(60 + (x >> 16) % 40); /* 60..99 */
	}
	data[10 * W + 10] = 4095; /* saturated, inside the ROI */
	data[10 * W + 10 + 1] = 4095;
	data[0] = 4095; /* outside it */
	for (int y = roi.y0; y < roi.y1; y++)
		for (int xx = roi.x0; xx < roi.x1; xx++)
			v[n++] = data[y * W + xx];
	qsort(v, (size_t)n, sizeof(double), cmp_double);
	/* The 1 % quantile: the code whose samples reach 1 % of the ROI's,
	 * below its bin's lower edge by the share of the bin still needed. */
	double q = 0.01 * n, below = 0, in_bin = 0;
	int i = 0;
	while (i + 1 < n && i + 1 < q)
		i++;
	double code = v[i];
	for (int j = 0; j < n; j++) {
		below += v[j] < code;
		in_bin += v[j] == code;
	}
	double want = code - 0.5 + (q - below) / in_bin - f.black_level;
	glint_frame_roi_stats(&f, &roi, &sat, &p01);
	CHECK(sat == 2, "%d saturated samples in the ROI, expected 2", sat);
	CHECK(fabs(p01 - want) < 1e-9, "1st percentile %g, sorted %g", p01,
	      want);
	CHECK(fabs(p01 - (60 - 64)) < 1, "1st percentile %g, codes from 60",
	      p01);
}

/* Metered by its own frames: nothing spent before the bracket, which
 * starts at the shortest exposure and keeps only the longest unclipped
 * frame; metering apart (the previous way) still works and says what it
 * spent. */
static void test_metering(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_camera_info in;
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };

	CHECK(glint_camera_open("sim", "sim:noise=0", &clk, &cam) == 0, "%s",
	      glint_error_msg());
	glint_camera_describe(cam, &in);
	glint_bracket_default_opts(&o);
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == 0, "%s",
	      glint_error_msg());
	CHECK(b.metering_frames == 0, "%d metering frames", b.metering_frames);
	/* The test card's brightest disk clips from about 0.3 ms: the
	 * frames from 10 us below that were replaced, and say so. */
	CHECK(b.superseded >= 3, "%d unclipped frames superseded",
	      b.superseded);
	/* Up from the camera's shortest exposure, of the unsaturated frames
	 * only the longest kept: the shortest frame is unclipped, the next
	 * clips. */
	int sat;
	double p01;
	glint_frame_roi_stats(&b.frames[0], &all, &sat, &p01);
	CHECK(sat == 0 && b.frames[0].exposure_s > in.exposure_min_s,
	      "shortest frame %g s (camera minimum %g s), %d saturated",
	      b.frames[0].exposure_s, in.exposure_min_s, sat);
	glint_frame_roi_stats(&b.frames[1], &all, &sat, &p01);
	CHECK(sat > 0, "the second frame (%g s) is not clipped either",
	      b.frames[1].exposure_s);
	CHECK(b.covered_low && b.covered_high, "coverage %d %d", b.covered_low,
	      b.covered_high);
	int n = b.n;
	glint_bracket_release(&b);

	o.meter_apart = 1;
	CHECK(glint_bracket_capture(cam, &all, &o, &clk, &b) == 0, "%s",
	      glint_error_msg());
	CHECK(b.metering_frames >= 1 && b.metering_frames <= 5,
	      "%d metering frames", b.metering_frames);
	CHECK(b.covered_low && b.covered_high, "coverage %d %d", b.covered_low,
	      b.covered_high);
	printf("metered by its frames: %d frames; metered apart: %d + %d\n", n,
	       b.metering_frames, b.n);
	glint_bracket_release(&b);
	glint_camera_close(cam);
}

int main(void)
{
	glint_backends_register();
	RUN(test_roi_stats);
	RUN(test_metering);
	RUN(test_covers_range);
	RUN(test_caps_and_refusal);
	return test_result();
}
