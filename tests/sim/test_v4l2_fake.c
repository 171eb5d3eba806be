/* SPDX-License-Identifier: MIT */
/*
 * The V4L2 backend through the real ioctl protocol, against the fake
 * device (tests/fake_v4l2, LD_PRELOADed by meson) that serves the
 * simulated sensor: format choice and unpacking of every format glint
 * reads, brackets whose labelled exposures match the pixels, and each
 * injected fault ending in a clear error.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera/bracket.h"
#include "core/error.h"

#include <stdlib.h>

#define DEV "/dev/video0"

static struct glint_camera *open_fake(const char *env, const char *device)
{
	struct glint_camera *cam = NULL;
	setenv("FAKE_V4L2", env, 1);
	int ret = glint_camera_open("v4l2", device ? device : DEV, NULL, &cam);
	CHECK(ret == 0, "FAKE_V4L2=%s: %s", env, glint_error_msg());
	return cam;
}

/* The simulated sensor's own frame, noise-free, at 10 ms. */
static int reference(struct glint_frame *f)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	int ret = glint_camera_open("sim", "sim:noise=0", &clk, &cam);
	if (ret == 0)
		ret = glint_camera_capture(cam, 0.01, 1, 6, f, NULL);
	glint_camera_close(cam);
	return ret;
}

static void test_not_present(void)
{
	struct glint_camera *cam;
	unsetenv("FAKE_V4L2");
	int ret = glint_camera_open("v4l2", "/dev/video77", NULL, &cam);
	CHECK(ret < 0, "opened a device that does not exist");
	CHECK_MSG(glint_error_msg(), "/dev/video77");
}

static void test_formats(void)
{
	static const struct {
		const char *offer, *chosen;
		int bits;
	} cases[] = {
		{ "SRGGB8:SRGGB10P:SRGGB12:YUYV", "SRGGB12", 12 },
		{ "YUYV:SRGGB12P", "SRGGB12P", 12 },
		{ "SRGGB10P", "SRGGB10P", 10 },
		{ "SRGGB10:RGB24", "SRGGB10", 10 },
		{ "SRGGB8", "SRGGB8", 8 },
		{ "SRGGB16:SRGGB12", "SRGGB16", 16 },
		{ "GREY:Y16", "Y16", 16 },
		{ "GREY", "GREY", 8 },
	};
	struct glint_frame ref;

	CHECK(reference(&ref) == 0, "%s", glint_error_msg());
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char env[128];
		struct glint_frame f;
		struct glint_camera_info in;
		snprintf(env, sizeof(env), "formats=%s,noise=0",
			 cases[i].offer);
		struct glint_camera *cam = open_fake(env, NULL);
		if (!cam)
			continue;
		glint_camera_describe(cam, &in);
		CHECK(in.bit_depth == cases[i].bits, "%s: %d bits",
		      cases[i].offer, in.bit_depth);
		CHECK(glint_camera_capture(cam, 0.01, 1, 6, &f, NULL) == 0,
		      "%s: %s", cases[i].offer, glint_error_msg());
		if (f.data) {
			CHECK(!strcmp(f.source_format, cases[i].chosen),
			      "offered %s: chose %s, expected %s",
			      cases[i].offer, f.source_format, cases[i].chosen);
			/* Every sample equals the sensor's, at the format's
			 * depth. */
			int bad = 0;
			for (int k = 0; k < f.width * f.height; k++) {
				unsigned v = ref.data[k];
				unsigned want =
					f.bit_depth >= 12
						? v << (f.bit_depth - 12)
						: v >> (12 - f.bit_depth);
				bad += f.data[k] != want;
			}
			CHECK(bad == 0, "%s: %d of %d samples differ",
			      cases[i].chosen, bad, f.width * f.height);
			double black = 64.0 * pow(2, f.bit_depth - 12);
			CHECK_NEAR(f.black_level, floor(black), 0,
				   "black level from V4L2_CID_BLACK_LEVEL");
			glint_frame_release(&f);
		}
		glint_camera_close(cam);
	}
	glint_frame_release(&ref);
}

/* RGB24 and YUYV are camera-encoded (linear = 0); YUYV decodes to the
 * same R'G'B' as RGB24 within chroma subsampling and rounding. */
static void test_encoded_formats(void)
{
	struct glint_frame a = { 0 }, b = { 0 };
	struct glint_camera *cam = open_fake("formats=RGB24,noise=0", NULL);
	if (cam)
		CHECK(glint_camera_capture(cam, 0.01, 1, 6, &a, NULL) == 0,
		      "%s", glint_error_msg());
	glint_camera_close(cam);
	cam = open_fake("formats=YUYV,noise=0", NULL);
	if (cam)
		CHECK(glint_camera_capture(cam, 0.01, 1, 6, &b, NULL) == 0,
		      "%s", glint_error_msg());
	glint_camera_close(cam);
	if (!a.data || !b.data)
		return;
	CHECK(a.channels == 3 && !a.linear && !strcmp(a.format, "RGB16"),
	      "RGB24: %d channels, linear %d, %s", a.channels, a.linear,
	      a.format);
	int n = a.width * a.height * 3, close = 0;
	for (int k = 0; k < n; k++)
		close += abs((int)a.data[k] - (int)b.data[k]) <= 3;
	CHECK(close >= 0.9 * n, "YUYV vs RGB24: %d of %d samples within 3",
	      close, n);
	glint_frame_release(&a);
	glint_frame_release(&b);
}

/* Mean ratio of two frames' signals over pixels well exposed in both. */
static double signal_ratio(const struct glint_frame *hi,
			   const struct glint_frame *lo)
{
	double s_hi = 0, s_lo = 0;
	int top = (1 << hi->bit_depth) - 1;
	for (int k = 0; k < hi->width * hi->height; k++)
		if (hi->data[k] < 0.9 * top &&
		    lo->data[k] > 4 * lo->black_level) {
			s_hi += hi->data[k] - hi->black_level;
			s_lo += lo->data[k] - lo->black_level;
		}
	return s_lo > 0 ? s_hi / s_lo : 0;
}

/* A bracket through V4L2: covers the card, labels match the pixels. */
static int bracket_labels_ok(const char *device, int *nframes, int strict)
{
	struct glint_camera *cam = open_fake("noise=0,latency=1", device);
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	int ok = 1;

	if (!cam)
		return -1;
	glint_bracket_default_opts(&o);
	o.max_frames = 24;
	int ret = glint_bracket_capture(cam, &all, &o, &glint_clock_real, &b);
	CHECK(ret == 0, "%s", glint_error_msg());
	if (ret < 0) {
		glint_camera_close(cam);
		return -1;
	}
	CHECK(!strict || (b.covered_low && b.covered_high),
	      "coverage low %d high %d, %d frames", b.covered_low,
	      b.covered_high, b.n);
	for (int i = 0; strict && i < b.n; i++) {
		int sat;
		double p01;
		glint_frame_roi_stats(&b.frames[i], &all, &sat, &p01);
		fprintf(stderr, "  %g s x%g: %d saturated, 1%% %g DN\n",
			b.frames[i].exposure_s, b.frames[i].gain, sat, p01);
	}
	*nframes = b.n;
	for (int i = 1; i < b.n; i++) {
		double want =
			b.frames[i].exposure_s * b.frames[i].gain /
			(b.frames[i - 1].exposure_s * b.frames[i - 1].gain);
		double got = signal_ratio(&b.frames[i], &b.frames[i - 1]);
		if (fabs(got / want - 1) > 0.05) {
			fprintf(stderr,
				"  frame %d: labelled %g s x%g, pixels say "
				"%.3g x the previous, labels %.3g x\n",
				i, b.frames[i].exposure_s, b.frames[i].gain,
				got, want);
			ok = 0;
		}
	}
	glint_bracket_release(&b);
	glint_camera_close(cam);
	return ok;
}

static void test_bracket(void)
{
	int n = 0;
	/* The backend's default latency (2) matches the fake sensor's
	 * (frame in progress + 1). */
	CHECK(bracket_labels_ok(DEV, &n, 1) == 1,
	      "labelled exposures disagree with the pixels");
	printf("v4l2 bracket on the fake device: %d frames, labels match "
	       "pixels\n",
	       n);
	/* Told the sensor is faster than it is, the backend mislabels
	 * frames, and the pixel check catches it: the check can fail. */
	CHECK(bracket_labels_ok(DEV ":latency=0", &n, 0) == 0,
	      "latency 0 should have mislabelled frames");
}

static void expect_fault(const char *env, const char *device, int code,
			 const char *frag)
{
	struct glint_camera *cam = NULL;
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	int ret;

	setenv("FAKE_V4L2", env, 1);
	ret = glint_camera_open("v4l2", device ? device : DEV, NULL, &cam);
	if (ret == 0) {
		glint_bracket_default_opts(&o);
		ret = glint_bracket_capture(cam, &all, &o, &glint_clock_real,
					    &b);
		if (ret == 0)
			glint_bracket_release(&b);
		glint_camera_close(cam);
	}
	CHECK(ret == -code, "FAKE_V4L2=%s: returned %d (%s), expected -%d", env,
	      ret, glint_error_msg(), code);
	CHECK_MSG(glint_error_msg(), frag);
	fprintf(stderr, "  %s -> %s\n", env, glint_error_msg());
}

static void test_faults(void)
{
	expect_fault("enodev_after=5", NULL, ENODEV, "disappeared");
	expect_fault("eio_at=4", NULL, EIO, "VIDIOC_DQBUF");
	expect_fault("stall_after=3", NULL, ETIMEDOUT, "no frame within");
	expect_fault("refuse=exposure", NULL, EACCES, "exposure_time_absolute");
	expect_fault("refuse=gain", NULL, EACCES, "analogue_gain");
	expect_fault("manual=0", NULL, ENOTSUP, "no manual exposure");
	expect_fault("busy=1", NULL, EBUSY, "another program");
	expect_fault("short_from=2", NULL, EIO, "short frame");
	expect_fault("formats=MJPG", NULL, ENOTSUP, "MJPG");
	expect_fault("", DEV ":latency=99", EINVAL, "latency");
}

int main(void)
{
	glint_backends_register();
	if (!getenv("LD_PRELOAD") ||
	    !strstr(getenv("LD_PRELOAD"), "fakev4l2")) {
		fprintf(stderr, "skip: run with LD_PRELOAD=libfakev4l2.so "
				"(meson test does)\n");
		return 77;
	}
	RUN(test_not_present);
	RUN(test_formats);
	RUN(test_encoded_formats);
	RUN(test_bracket);
	RUN(test_faults);
	return test_result();
}
