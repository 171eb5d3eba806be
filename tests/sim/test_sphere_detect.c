/* SPDX-License-Identifier: MIT */
/*
 * Sphere detection: on real photographs of a chrome and a matte sphere
 * (UW photometric-stereo images, ../shared/data/spheres) against the
 * circle of their hand-made masks, and on a simulated mirror-ball photo
 * against its exact silhouette.
 */
#include "test.h"

#include "capture/hdr/hdr_linear.h"
#include "capture/probe/sphere_detect.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"
#include "sim/camera_sim.h"
#include "sim/probe_sim.h"
#include "sim/sensor.h"

static void real_set(const char *name)
{
	char rel[128];
	struct glint_image *mask, *img;
	struct glint_circle mc, c;

	snprintf(rel, sizeof(rel), "spheres/uw_psm/%s/%s.mask.tga", name, name);
	const char *p = shared_file(rel);
	if (!p) {
		printf("skip: %s absent\n", rel);
		return;
	}
	CHECK(glint_image_read(p, &mask) == 0, "%s", glint_error_msg());
	CHECK(glint_mask_circle(mask, &mc) == 0, "%s", glint_error_msg());
	double worst = 0;
	int within1 = 0, within15 = 0;
	for (int i = 0; i < 12; i++) {
		snprintf(rel, sizeof(rel), "spheres/uw_psm/%s/%s.%d.tga", name,
			 name, i);
		p = shared_file(rel);
		if (!p || glint_image_read(p, &img) < 0) {
			CHECK(0, "%s: %s", rel, glint_error_msg());
			continue;
		}
		int ret = glint_sphere_detect(img, 0, 0, &c);
		double e = ret < 0 ? INFINITY
				   : fmax(hypot(c.cx - mc.cx, c.cy - mc.cy),
					  fabs(c.r - mc.r));
		worst = fmax(worst, e);
		within1 += e <= 1;
		within15 += e <= 1.5;
		printf("  %s.%d: (%.2f, %.2f) r %.2f, %d points over %.0f deg, "
		       "rim %.2f, z %.1f, run %.0f deg, slope %.3f: %.2f px "
		       "from "
		       "the mask's circle\n",
		       name, i, c.cx, c.cy, c.r, c.points, c.arc_deg,
		       c.rim_share, c.rim_z, c.rim_run_deg, c.rim_slope, e);
		glint_image_free(img);
	}
	printf("%s: mask circle (%.2f, %.2f) r %.2f; %d of 12 photos within "
	       "1 px, %d within 1.5 px, worst %.2f px\n",
	       name, mc.cx, mc.cy, mc.r, within1, within15, worst);
	/* Measured: 9 (chrome) and 10 (gray) within 1.5 px; the others
	 * show a rim dark against a dark background, or a lit terminator
	 * that is a stronger arc than the rim. */
	CHECK(within15 >= 8, "%s: only %d of 12 photos within 1.5 px", name,
	      within15);
	glint_image_free(mask);
}

static void test_real(void)
{
	real_set("chrome");
	real_set("gray");
}

/* A chrome ball on the camera's axis at distance d (radius 1) in a w x h
 * frame reflecting the Venice map, found within tol px of its silhouette:
 * a circle of radius f tan(asin(1 / d)) centred on the frame.  Returns
 * the photo (the caller's). */
static struct glint_image *on_axis_ball(const char *what, int w, int h,
					double fpx, double d, int spp,
					double tol)
{
	struct glint_image *env, *photo = NULL;
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };
	CHECK(glint_image_read(GLINT_DATA_DIR "/env/venice_sunset_1k.hdr",
			       &env) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_sim_mirror_ball(env, w, h, fpx, v3(0, 0, -d), 1, n, k, spp,
				    &photo) == 0,
	      "%s", glint_error_msg());
	glint_image_free(env);
	if (!photo)
		return NULL;
	struct glint_circle c;
	CHECK(glint_sphere_detect(photo, 0, 0, &c) == 0, "%s",
	      glint_error_msg());
	double r = fpx * tan(asin(1 / d)), cx = 0.5 * w, cy = 0.5 * h;
	printf("%s: (%.3f, %.3f) r %.3f, truth (%g, %g) r %.3f\n", what, c.cx,
	       c.cy, c.r, cx, cy, r);
	CHECK(hypot(c.cx - cx, c.cy - cy) < tol && fabs(c.r - r) < tol,
	      "%s detected at (%.2f, %.2f) r %.2f", what, c.cx, c.cy, c.r);
	return photo;
}

static void test_simulated_ball(void)
{
	struct glint_image *photo =
		on_axis_ball("simulated ball", 480, 400, 2000, 12, 3, 0.3);
	if (!photo)
		return;
	/* A black image has nothing to find. */
	struct glint_circle c;
	memset(photo->data, 0, sizeof(float) * 3 * 480 * 400);
	CHECK(glint_sphere_detect(photo, 0, 0, &c) < 0,
	      "found a ball in black");
	CHECK_MSG(glint_error_msg(), "black");
	glint_image_free(photo);
}

/* A 12 MP frame (a Pi HQ-class sensor) with the ball against the map's
 * detailed backdrop: its rim is a small share of the edges, which is where
 * detecting on the full frame alone failed (bench/rig_size). */
static void test_large_frame(void)
{
	glint_image_free(
		on_axis_ball("12 MP ball", 4056, 3040, 8112, 8, 1, 0.5));
}

/* xorshift64*: the null frames' own generator, seeded per frame. */
static double rnd(uint64_t *s)
{
	*s ^= *s >> 12;
	*s ^= *s << 25;
	*s ^= *s >> 27;
	return (double)((*s * 2685821657736338717ull) >> 11) * 0x1p-53;
}

static double gauss(uint64_t *s)
{
	double u = fmax(rnd(s), 1e-300), v = rnd(s);
	return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}

/* Smooth value noise at cell size `cell`: bilinear between random
 * lattice values. */
static double value_noise(const float *lat, int lw, double x, double y,
			  double cell)
{
	double fx = x / cell, fy = y / cell;
	int ix = (int)fx, iy = (int)fy;
	double tx = fx - ix, ty = fy - iy;
	const float *p = lat + (size_t)iy * lw + ix;
	return (1 - ty) * ((1 - tx) * p[0] + tx * p[1]) +
	       ty * ((1 - tx) * p[lw] + tx * p[lw + 1]);
}

static const char *const null_kinds[] = {
	"noise",   "blank",	 "vignette",	 "gradient",
	"texture", "rectangles", "checkerboard", "grating",
};
enum { NKINDS = 8 };

/*
 * Frame `index` of the null set: an image holding no sphere, kind
 * index % NKINDS, of a random size, with sensor-like noise on top:
 * pure noise; a blank frame; a vignetted blank (cos^4 falloff about a
 * random centre: concentric iso-lines, the nearest a flat field comes
 * to a circle); a linear gradient; smooth multi-scale texture (value
 * noise, an HDR range); random overlapping rectangles; a checkerboard;
 * a sine grating.
 */
static struct glint_image *null_frame(int index, const char **kind)
{
	uint64_t s = 0x9e3779b97f4a7c15ull ^ (uint64_t)(index + 1) * 7919;
	for (int k = 0; k < 4; k++)
		rnd(&s);
	int w = 64 + (int)(rnd(&s) * 257), h = 64 + (int)(rnd(&s) * 193);
	int type = index % NKINDS;
	struct glint_image *img = glint_image_new(w, h);
	int lw = w / 4 + 3, lh = h / 4 + 3;
	float *lat = malloc(sizeof(float) * (size_t)lw * lh * 3);
	double noise = exp(log(1e-3) + rnd(&s) * log(1e2)); /* 0.1 % .. 10 % */
	double vx = rnd(&s) * w, vy = rnd(&s) * h, vf = (0.5 + rnd(&s)) * w;
	double ang = rnd(&s) * 2 * M_PI, freq = 0.03 + 0.3 * rnd(&s);
	int sq = 4 + (int)(rnd(&s) * 28);
	*kind = null_kinds[type];
	if (!img || !lat) {
		free(lat);
		glint_image_free(img);
		return NULL;
	}
	for (size_t i = 0; i < (size_t)lw * lh * 3; i++)
		lat[i] = (float)rnd(&s);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			double v = 1;
			if (type == 0)
				v = 0.5;
			else if (type == 2) {
				double r2 = ((x - vx) * (x - vx) +
					     (y - vy) * (y - vy)) /
					    (vf * vf);
				v = 1 / ((1 + r2) * (1 + r2));
			} else if (type == 3)
				v = 0.2 +
				    (cos(ang) * x + sin(ang) * y) / (w + h);
			else if (type == 4)
				v = exp(3 * (value_noise(lat, lw, x, y, 4) +
					     value_noise(lat + lw * lh, lw, x,
							 y, 2) -
					     1));
			else if (type == 6)
				v = ((x / sq + y / sq) & 1) ? 1 : 0.2;
			else if (type == 7)
				v = 1 + 0.5 * sin(freq * (cos(ang) * x +
							  sin(ang) * y));
			float *p = glint_image_px(img, x, y);
			for (int c = 0; c < 3; c++)
				p[c] = (float)fmax(
					v * (1 + noise * gauss(&s)) +
						(type == 0 ? 0.5 * gauss(&s)
							   : 0),
					0);
		}
	if (type == 5) /* rectangles, overlapping, of random levels */
		for (int k = 0; k < 30; k++) {
			int x0 = (int)(rnd(&s) * w), y0 = (int)(rnd(&s) * h);
			int x1 = x0 + 4 + (int)(rnd(&s) * w / 2),
			    y1 = y0 + 4 + (int)(rnd(&s) * h / 2);
			double lv = exp(4 * rnd(&s) - 2);
			for (int y = y0; y < y1 && y < h; y++)
				for (int x = x0; x < x1 && x < w; x++) {
					float *p = glint_image_px(img, x, y);
					for (int c = 0; c < 3; c++)
						p[c] = (float)(lv *
							       (1 +
								noise * gauss(&s)));
				}
		}
	free(lat);
	return img;
}

/*
 * The false-alarm rate: detection on GLINT_DETECT_FRAMES (default 250)
 * frames that hold no sphere finds nothing in any (the thresholds allow
 * at most 1 in 1000: 250 frames with none found bound the rate below
 * 1.2 % at 95 %, and a run of 1000 is how the thresholds were set).
 * Prints each kind's highest statistics, the margin to the thresholds.
 */
static void test_false_alarms(void)
{
	const char *env = getenv("GLINT_DETECT_FRAMES");
	int n = env ? atoi(env) : 250, found = 0;
	double top_share[NKINDS] = { 0 }, top_z[NKINDS] = { 0 };
	double top_run[NKINDS] = { 0 }, top_slope[NKINDS] = { 0 };
	double t0 = glint_clock_monotonic();

	for (int i = 0; i < n; i++) {
		const char *kind;
		struct glint_image *img = null_frame(i, &kind);
		struct glint_circle c;
		CHECK(img, "frame %d: out of memory", i);
		if (!img)
			continue;
		int ret = glint_sphere_detect(img, 0, 0, &c);
		int t = i % NKINDS;
		top_share[t] = fmax(top_share[t], c.rim_share);
		top_z[t] = fmax(top_z[t], c.rim_z);
		top_run[t] = fmax(top_run[t], c.rim_run_deg);
		top_slope[t] = fmax(top_slope[t], c.rim_slope);
		if (ret == 0) {
			found++;
			printf("  false find in frame %d (%s, %dx%d): (%.1f, "
			       "%.1f) r %.1f, rim %.2f, z %.1f, run %.0f deg, "
			       "slope %.3f\n",
			       i, kind, img->width, img->height, c.cx, c.cy,
			       c.r, c.rim_share, c.rim_z, c.rim_run_deg,
			       c.rim_slope);
		} else if (ret != -ENOENT && ret != -ERANGE) {
			CHECK(0, "frame %d (%s): %s", i, kind,
			      glint_error_msg());
		}
		glint_image_free(img);
	}
	for (int t = 0; t < NKINDS; t++)
		printf("  %-12s highest rim share %.3f, z %.1f, run %.0f deg, "
		       "slope %.3f\n",
		       null_kinds[t], top_share[t], top_z[t], top_run[t],
		       top_slope[t]);
	printf("false alarms: %d of %d frames with no sphere (%.1f s)\n", found,
	       n, glint_clock_monotonic() - t0);
	CHECK(found * 1000 <= n, "%d false finds in %d frames", found, n);
}

/* A small ball (radius 25 px in a 96 x 72 frame, as the vm suite's rig
 * takes it): its short rim passes on its share, not on z alone. */
static void test_small_ball(void)
{
	glint_image_free(on_axis_ball("small ball", 96, 72, 192, 7.75, 3, 0.5));
}

/* The rig's sample sphere in a 96 x 72 frame (the VM test's camera)
 * through a lens of 0.86 px (wider than the rig's, data/rig-sim.json) and
 * the OLPF: the blur widens the rim's edge band, and the low-contrast rim
 * against the ground must still count. */
static void test_small_blurred_sample(void)
{
	struct glint_image *photo = NULL;
	struct glint_sensor s;
	struct glint_circle c;
	CHECK(glint_sim_sample_scene(96, 72, "yellow-plastic", 1, &photo) == 0,
	      "%s", glint_error_msg());
	if (!photo)
		return;
	glint_sensor_default(&s);
	s.psf_sigma_px = 0.86;
	s.olpf = 1;
	CHECK(glint_sensor_optics(&s, photo) == 0, "%s", glint_error_msg());
	int ret = glint_sphere_detect(photo, 0, 0, &c);
	double r = 0.35 * 72;
	printf("blurred sample: (%.3f, %.3f) r %.3f, rim %.2f, z %.1f, truth "
	       "(48, 36) r %.3f\n",
	       c.cx, c.cy, c.r, c.rim_share, c.rim_z, r);
	CHECK(ret == 0, "%s", glint_error_msg());
	/* the centre sits half a pixel high: the bright sky above blurs
	 * into the rim more than the ground below (a quarter of the rig's
	 * sample's size, test_rig_sample) */
	CHECK(hypot(c.cx - 48, c.cy - 36) < 0.8 && fabs(c.r - r) < 0.6,
	      "blurred sample detected at (%.2f, %.2f) r %.2f", c.cx, c.cy,
	      c.r);
	glint_image_free(photo);
}

/* The shipped rig's sample as its camera takes it (320 x 240, the
 * ball 84 px in radius, yellow plastic under the rig's map): the lens,
 * the OLPF, the Bayer mosaic and the merge's demosaic.  Where the sky
 * behind the ball is brighter than its rim and falls towards the
 * horizon, the gradient's peak sits a third of a pixel out: the circle
 * came out 0.28 px high, enough to move ior by 0.015 and specular by
 * 5 %.  The rim's profile model puts it within a tenth of a pixel. */
static void test_rig_sample(void)
{
	struct glint_image *photo = NULL, *rad = NULL, *var = NULL, *ok = NULL;
	struct glint_sensor s;
	struct glint_circle c;
	int w = 320, h = 240;
	CHECK(glint_sim_sample_scene(w, h, "yellow-plastic", 1, &photo) == 0,
	      "%s", glint_error_msg());
	if (!photo)
		return;
	glint_sensor_default(&s);
	s.olpf = 1;
	CHECK(glint_sensor_optics(&s, photo) == 0, "%s", glint_error_msg());
	struct glint_raw_hdr raw = { w, h, "RGGB16", NULL, NULL, NULL };
	raw.x = calloc((size_t)w * h, sizeof(float));
	raw.var = calloc((size_t)w * h, sizeof(float));
	raw.valid = calloc((size_t)w * h, 1);
	CHECK(raw.x && raw.var && raw.valid, "out of memory");
	for (int y = 0; raw.valid && y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			/* RGGB: R at even (x, y), B at odd, G between */
			raw.x[i] =
				glint_image_px(photo, x, y)[(y & 1) + (x & 1)];
			raw.var[i] = 1;
			raw.valid[i] = 1;
		}
	CHECK(glint_hdr_demosaic(&raw, &rad, &var, &ok) == 0, "%s",
	      glint_error_msg());
	int ret = rad ? glint_sphere_detect(rad, 0, 0, &c) : -1;
	double r = 0.35 * h;
	printf("rig sample: (%.3f, %.3f) r %.3f, truth (160, 120) r %.3f\n",
	       c.cx, c.cy, c.r, r);
	CHECK(ret == 0, "%s", glint_error_msg());
	CHECK(hypot(c.cx - 160, c.cy - 120) < 0.1 && fabs(c.r - r) < 0.1,
	      "rig sample detected at (%.3f, %.3f) r %.3f", c.cx, c.cy, c.r);
	free(raw.x);
	free(raw.var);
	free(raw.valid);
	glint_image_free(photo);
	glint_image_free(rad);
	glint_image_free(var);
	glint_image_free(ok);
}

int main(void)
{
	RUN(test_false_alarms);
	RUN(test_real);
	RUN(test_simulated_ball);
	RUN(test_large_frame);
	RUN(test_small_ball);
	RUN(test_small_blurred_sample);
	RUN(test_rig_sample);
	return test_result();
}
