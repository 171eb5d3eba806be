/* SPDX-License-Identifier: MIT */
/*
 * The camera interface on the simulated camera: capabilities, frames that
 * carry the exposure actually applied (the sim applies a new exposure two
 * frames late, as real sensors do, and glint_camera_capture() drops those
 * frames), real frame timing on a fake clock, and refusals.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera/camera.h"
#include "core/error.h"
#include "sim/world.h"

#include <dirent.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

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

/* Mean signal above black of a noise-free 10 ms frame. */
static double mean_signal(struct glint_camera *cam)
{
	struct glint_frame f;
	double sum = 0;
	if (glint_camera_capture(cam, 0.01, 1, 5, &f, NULL) < 0)
		return -1;
	for (int i = 0; i < f.width * f.height; i++)
		sum += f.data[i] - f.black_level;
	sum /= f.width * f.height;
	glint_frame_release(&f);
	return sum;
}

static void write_world(const char *path, const char *text)
{
	FILE *fp = fopen(path, "w");
	CHECK(fp != NULL, "%s", path);
	if (fp) {
		fputs(text, fp);
		fclose(fp);
	}
}

/* scene=rig with world=FILE: the view follows the file (a real board's
 * lines, as tests/vm/sample_lines.py writes them), read at each frame. */
static void test_world_file(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	char path[64], dev[160];
	snprintf(path, sizeof(path), "/tmp/glint-world-%d", (int)getpid());
	snprintf(dev, sizeof(dev),
		 "sim:width=40,height=30,scene=rig,noise=0,world=%s", path);
	remove(path);
	CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0, "%s",
	      glint_error_msg());
	if (!cam)
		return;
	double missing = mean_signal(cam);
	write_world(path, "1 0\n");
	double probe = mean_signal(cam);
	write_world(path, "1 180.0\n");
	double sample = mean_signal(cam);
	write_world(path, "0 180\n");
	double sample_dark = mean_signal(cam);
	write_world(path, "1 90\n");
	double between = mean_signal(cam);
	/* a rig with lamps on lines of their own: bit k - 1 is lamp k */
	write_world(path, "2 180\n");
	double lamp2 = mean_signal(cam);
	write_world(path, "3 180\n");
	double both = mean_signal(cam);
	printf("world file: the sample under lamp 1 %.2f, lamp 2 %.2f, both "
	       "%.2f DN\n",
	       sample, lamp2, both);
	CHECK(lamp2 > 2 && fabs(lamp2 - sample) > 0.2 * sample,
	      "lamp 2 lights the sample as lamp 1 does: %g, %g", lamp2, sample);
	CHECK(fabs(both - (sample + lamp2)) < 0.05 * both,
	      "two lamps are not the sum of each: %g vs %g + %g", both, sample,
	      lamp2);
	printf("world file: missing %.2f, probe %.2f, sample %.2f, sample "
	       "lights off %.3f, turned 90 deg %.2f DN\n",
	       missing, probe, sample, sample_dark, between);
	CHECK(probe > 20 && sample > 20, "nothing in view: %g %g", probe,
	      sample);
	CHECK(fabs(probe - sample) > 0.05 * probe,
	      "probe and sample look the same");
	CHECK(sample_dark < 0.01 * sample, "lights off: %g of %g", sample_dark,
	      sample);
	CHECK(missing < 0.01 * probe, "no file should be a dark lab");
	CHECK(between < 0.5 * sample, "turned away: %g", between);
	glint_camera_close(cam);
	remove(path);
	CHECK(glint_camera_open("sim", "sim:scene=rig,world=", &clk, &cam) < 0,
	      "an empty world path accepted");
	CHECK_MSG(glint_error_msg(), "world");
}

/* scene_scale=K: the views rendered at 1/K and interpolated up keep the
 * scene's brightness and place (bench/rig_size's 12 MP frames). */
static void test_scene_scale(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	double m[2];
	for (int k = 0; k < 2; k++) {
		char dev[96];
		snprintf(dev, sizeof(dev),
			 "sim:width=96,height=72,scene=sample,noise=0%s",
			 k ? ",scene_scale=3" : "");
		CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0, "%s",
		      glint_error_msg());
		if (!cam)
			return;
		m[k] = mean_signal(cam);
		glint_camera_close(cam);
	}
	printf("scene_scale: mean %.2f DN rendered whole, %.2f at 1/3\n", m[0],
	       m[1]);
	CHECK(m[0] > 5 && fabs(m[1] - m[0]) < 0.05 * m[0], "%g against %g",
	      m[1], m[0]);
	CHECK(glint_camera_open("sim", "sim:scene=sample,scene_scale=0", &clk,
				&cam) < 0,
	      "scene_scale=0 accepted");
	CHECK_MSG(glint_error_msg(), "scene_scale");
}

/* Files in dir whose names start with prefix; the first into first. */
static int count_files(const char *dir, const char *prefix, char *first,
		       size_t n)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	int k = 0;
	if (!d)
		return 0;
	while ((e = readdir(d)))
		if (!strncmp(e->d_name, prefix, strlen(prefix)) && !k++)
			snprintf(first, n, "%s/%s", dir, e->d_name);
	closedir(d);
	return k;
}

/*
 * The rig views are made when a capture starts, not at a frame, and kept
 * on disk by what they depend on: a second camera of the same rig reads
 * them (the same frames, bit for bit, without noise); another material is
 * another file; a cached file that is not whole is rendered again.
 */
static void test_view_cache(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	char dir[64], world[80], dev[200], probe[512] = "", sample[512] = "";
	struct glint_frame f[2];

	snprintf(dir, sizeof(dir), "/tmp/glint-cache-%d", (int)getpid());
	snprintf(world, sizeof(world), "%s.world", dir);
	setenv("GLINT_SIM_CACHE", dir, 1);
	write_world(world, "1 180\n");
	snprintf(dev, sizeof(dev),
		 "sim:width=48,height=36,scene=rig,noise=0,world=%s", world);
	for (int k = 0; k < 2; k++) {
		CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0, "%s",
		      glint_error_msg());
		if (!cam)
			return;
		if (k == 0)
			CHECK(count_files(dir, "", probe, sizeof(probe)) == 0,
			      "views made at open: %s", probe);
		CHECK(glint_camera_start(cam) == 0, "%s", glint_error_msg());
		/* the view in sight made at the start, the other on a
		 * thread of its own, joined at the latest at close */
		CHECK(count_files(dir, "sample-", sample, sizeof(sample)) == 1,
		      "the start cached no sample view in %s", dir);
		CHECK(glint_camera_capture(cam, 0.01, 1, 6, &f[k], NULL) == 0,
		      "%s", glint_error_msg());
		glint_camera_close(cam);
		CHECK(count_files(dir, "probe-", probe, sizeof(probe)) == 1,
		      "no probe view cached in %s by the close", dir);
	}
	size_t n = (size_t)f[0].width * f[0].height;
	CHECK(f[0].data && f[1].data &&
		      !memcmp(f[0].data, f[1].data, n * sizeof(uint16_t)),
	      "the cached view gives other frames than the rendered one");
	/* a cached file cut short: rendered again, the file replaced */
	FILE *t = fopen(sample, "r+");
	CHECK(t && ftruncate(fileno(t), 100) == 0, "cannot cut %s", sample);
	if (t)
		fclose(t);
	CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0 &&
		      glint_camera_start(cam) == 0,
	      "%s", glint_error_msg());
	struct glint_frame g;
	CHECK(glint_camera_capture(cam, 0.01, 1, 6, &g, NULL) == 0 &&
		      !memcmp(g.data, f[0].data, n * sizeof(uint16_t)),
	      "a torn cache file was used");
	glint_frame_release(&g);
	glint_camera_close(cam);
	struct stat st;
	CHECK(stat(sample, &st) == 0 && st.st_size > 100,
	      "the torn cache file was not replaced");
	/* another material: another view */
	snprintf(dev, sizeof(dev),
		 "sim:width=48,height=36,scene=rig,noise=0,material=teflon,"
		 "world=%s",
		 world);
	CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0 &&
		      glint_camera_start(cam) == 0,
	      "%s", glint_error_msg());
	glint_camera_close(cam);
	CHECK(count_files(dir, "sample-", sample, sizeof(sample)) == 2,
	      "teflon's view shares the cache file of yellow plastic");
	/* no cache: the sample's view, made on the thread while the probe
	 * streams, is the frame the sample in sight gave */
	setenv("GLINT_SIM_CACHE", "off", 1);
	write_world(world, "1 0\n");
	snprintf(dev, sizeof(dev),
		 "sim:width=48,height=36,scene=rig,noise=0,world=%s", world);
	CHECK(glint_camera_open("sim", dev, &clk, &cam) == 0 &&
		      glint_camera_start(cam) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_camera_capture(cam, 0.01, 1, 6, &g, NULL) == 0, "%s",
	      glint_error_msg());
	glint_frame_release(&g);
	write_world(world, "1 180\n");
	CHECK(glint_camera_capture(cam, 0.01, 1, 6, &g, NULL) == 0 &&
		      !memcmp(g.data, f[0].data, n * sizeof(uint16_t)),
	      "the view made out of sight gives other frames");
	glint_frame_release(&g);
	glint_camera_close(cam);
	glint_frame_release(&f[0]);
	glint_frame_release(&f[1]);
	char cmd[160];
	snprintf(cmd, sizeof(cmd), "rm -rf '%s' '%s'", dir, world);
	CHECK(system(cmd) == 0, "%s", cmd);
	unsetenv("GLINT_SIM_CACHE");
}

static void write_text(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");
	if (f) {
		fputs(text, f);
		fclose(f);
	}
}

/*
 * A scenario file (sim/scenario.h) configures the camera as its device
 * string does, bad keys are named, and the world is the scenario's: a
 * board's lights off in it darken its camera, not a camera of another
 * world.
 */
static void test_scenario(void)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *a = NULL, *b = NULL;
	struct glint_camera_info in;
	char path[64], dev[128];
	snprintf(path, sizeof(path), "/tmp/glint-scenario-%d.json",
		 (int)getpid());

	write_text(path,
		   "{\"camera\": {\"width\": 36, \"height\": 20, "
		   "\"latency\": 1, \"noise\": false, \"seed\": 5, "
		   "\"decades\": 3},\n \"presses\": [{\"at_s\": 0.1}]}\n");
	snprintf(dev, sizeof(dev), "sim:scenario=%s", path);
	CHECK(glint_camera_open("sim", dev, &clk, &a) == 0, "%s",
	      glint_error_msg());
	CHECK(glint_camera_open("sim",
				"sim:width=36,height=20,latency=1,noise=0,"
				"seed=5,decades=3",
				&clk, &b) == 0,
	      "%s", glint_error_msg());
	if (a && b) {
		struct glint_frame fa, fb;
		int da, db;
		glint_camera_describe(a, &in);
		CHECK(in.width == 36 && in.height == 20, "%dx%d", in.width,
		      in.height);
		CHECK(glint_camera_capture(a, 0.004, 1, 4, &fa, &da) == 0 &&
			      glint_camera_capture(b, 0.004, 1, 4, &fb, &db) ==
				      0,
		      "%s", glint_error_msg());
		CHECK(da == 1 && db == 1, "dropped %d and %d, latency 1", da,
		      db);
		CHECK(!memcmp(fa.data, fb.data,
			      (size_t)36 * 20 * sizeof(*fa.data)),
		      "the scenario's camera differs from the device "
		      "string's");
		glint_frame_release(&fa);
		glint_frame_release(&fb);
	}
	glint_camera_close(a);
	glint_camera_close(b);
	a = b = NULL;

	static const struct {
		const char *text, *named;
	} bad[] = {
		{ "{\"camera\": {\"widht\": 30}}", "widht" },
		{ "{\"camera\": {\"scene\": \"moon\"}}", "moon" },
		{ "{\"camera\": {\"width\": 1}}", "width" },
		{ "{\"camera\": {\"noise\": \"yes\"}}", "noise" },
		{ "{\"camera\": [1]}", "camera" },
		{ "{\"lamps\": 3}", "lamps" },
	};
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		write_text(path, bad[i].text);
		CHECK(glint_camera_open("sim", dev, &clk, &a) < 0,
		      "%s accepted", bad[i].text);
		CHECK_MSG(glint_error_msg(), path);
		CHECK_MSG(glint_error_msg(), bad[i].named);
		glint_camera_close(a);
		a = NULL;
	}

	/* The world: the scenario's, not the scenario-less cameras'. */
	write_text(path, "{\"camera\": {\"width\": 40, \"height\": 30, "
			 "\"scene\": \"rig\", \"noise\": false}}");
	struct glint_sim_world *w = NULL, *w2 = NULL, *other = NULL;
	CHECK(glint_sim_world_open(path, &w) == 0 &&
		      glint_sim_world_open(path, &w2) == 0 &&
		      glint_sim_world_open(NULL, &other) == 0,
	      "%s", glint_error_msg());
	CHECK(w && w == w2 && other != w, "one world per scenario");
	CHECK(glint_camera_open("sim", dev, &clk, &a) == 0 &&
		      glint_camera_open("sim",
					"sim:width=40,height=30,scene=rig,"
					"noise=0",
					&clk, &b) == 0,
	      "%s", glint_error_msg());
	if (a && b && w) {
		double lit = mean_signal(a), lit_b = mean_signal(b);
		struct glint_sim_state st = { 0, GLINT_SIM_VIEW_PROBE, 0 };
		glint_sim_world_set(w, &st);
		double dark = mean_signal(a), still = mean_signal(b);
		printf("scenario world: lit %.2f, lights off %.3f; the other "
		       "world's camera %.2f then %.2f DN\n",
		       lit, dark, lit_b, still);
		CHECK(lit > 20 && dark < 0.01 * lit,
		      "the scenario's lights off: %g of %g", dark, lit);
		CHECK(fabs(still - lit_b) < 0.01 * lit_b,
		      "another world's camera changed: %g then %g", lit_b,
		      still);
	}
	glint_camera_close(a);
	glint_camera_close(b);
	glint_sim_world_close(w);
	glint_sim_world_close(w2);
	glint_sim_world_close(other);
	remove(path);
}

int main(void)
{
	glint_backends_register();
	RUN(test_describe);
	RUN(test_applied_exposure);
	RUN(test_refusals);
	RUN(test_world_file);
	RUN(test_scene_scale);
	RUN(test_view_cache);
	RUN(test_scenario);
	return test_result();
}
