/* SPDX-License-Identifier: MIT */
/*
 * Sphere detection: on real photographs of a chrome and a matte sphere
 * (UW photometric-stereo images, ../shared/data/spheres) against the
 * circle of their hand-made masks, and on a simulated mirror-ball photo
 * against its exact silhouette.
 */
#include "test.h"

#include "capture/sphere_detect.h"
#include "core/error.h"
#include "core/formats.h"
#include "sim/probe_sim.h"

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
		printf("  %s.%d: (%.2f, %.2f) r %.2f, %d points over %.0f deg: "
		       "%.2f px from the mask's circle\n",
		       name, i, c.cx, c.cy, c.r, c.points, c.arc_deg, e);
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

int main(void)
{
	RUN(test_real);
	RUN(test_simulated_ball);
	RUN(test_large_frame);
	return test_result();
}
