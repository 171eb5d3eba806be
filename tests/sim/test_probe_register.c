/* SPDX-License-Identifier: MIT */
/*
 * Two-view probe registration on simulated captures: the Venice map
 * photographed on a mirror ball from two camera orientations about 90
 * degrees apart (forward renderer, sim/probe_sim.c), both unwrapped; the
 * known rotation between them recovered from noisy point correspondences
 * (within 0.5 degrees) and automatically (within 1 degree); the blend
 * covers the whole sphere.
 */
#include "test.h"

#include "capture/probe/probe.h"
#include "capture/probe/probe_register.h"
#include "core/error.h"
#include "fit/scene/envmap.h"

#include <stdint.h>
#include "sim/probe_sim.h"

static uint64_t rng = 88172645463325252ull;
static double uniform(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return (double)(rng >> 11) / 9007199254740992.0;
}

/* A small random rotation of d (about 0.2 degrees RMS). */
static struct vec3 jitter(struct vec3 d)
{
	struct mat3 m = m3_rotation_xyz_deg(0.2 * (uniform() - 0.5) * 2,
					    0.2 * (uniform() - 0.5) * 2,
					    0.2 * (uniform() - 0.5) * 2);
	return m3_mul(&m, d);
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

int main(void)
{
	struct glint_image *big, *env1, *env2, *ph[2], *e[2], *m[2], *dn[2];
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };

	if (glint_image_read(GLINT_DATA_DIR "/env/venice_sunset_1k.hdr", &big) <
	    0) {
		fprintf(stderr, "%s\n", glint_error_msg());
		return 1;
	}
	glint_probe_convert(big, GLINT_PROBE_LATLONG, GLINT_PROBE_LATLONG, 256,
			    128, &env1);
	/* View 2's frame to view 1's: the camera turned 90 degrees with a
	 * slight tilt.  L1(d) = L2(R^T d), i.e. L2(d2) = L1(R d2). */
	struct mat3 truth = m3_rotation_xyz_deg(3, 90, -2);
	env2 = glint_image_new(256, 128);
	for (int y = 0; y < 128; y++)
		for (int x = 0; x < 256; x++) {
			struct vec3 d;
			glint_probe_pixel_dir(GLINT_PROBE_LATLONG, 256, 128,
					      x + 0.5, y + 0.5, &d);
			glint_probe_lookup(env1, GLINT_PROBE_LATLONG,
					   m3_mul(&truth, d),
					   glint_image_px(env2, x, y));
		}
	struct glint_unwrap_opts o;
	glint_unwrap_default_opts(&o);
	o.fpx = 3000;
	o.ball_cx = 350;
	o.ball_cy = 300;
	o.ball_r = 3000 * tan(asin(1.0 / 25));
	o.width = 256;
	o.height = 128;
	for (int v = 0; v < 2; v++) {
		CHECK(glint_sim_mirror_ball(v ? env2 : env1, 700, 600, 3000,
					    v3(0, 0, -25), 1, n, k, 4,
					    &ph[v]) == 0,
		      "%s", glint_error_msg());
		CHECK(glint_probe_unwrap(ph[v], &o, &e[v], &m[v], &dn[v]) == 0,
		      "%s", glint_error_msg());
	}

	/* Correspondences: 30 directions reliable in both views, each end
	 * jittered by ~0.2 degrees (a user clicking features). */
	struct vec3 a[30], b[30];
	int np = 0;
	while (np < 30) {
		double u = uniform(), vv = 0.15 + 0.7 * uniform();
		struct vec3 d1 = glint_latlong_uv_to_dir(u, vv);
		struct vec3 d2 = m3_tmul(&truth, d1);
		float w1[3], w2[3];
		glint_probe_lookup(m[0], GLINT_PROBE_LATLONG, d1, w1);
		glint_probe_lookup(m[1], GLINT_PROBE_LATLONG, d2, w2);
		if (w1[0] < 1 || w2[0] < 1)
			continue;
		a[np] = jitter(d1);
		b[np] = jitter(d2);
		np++;
	}
	struct mat3 r;
	double rms;
	CHECK(glint_register_points(a, b, np, &r, &rms) == 0, "%s",
	      glint_error_msg());
	double err = glint_rotation_angle_deg(&r, &truth);
	printf("from 30 correspondences (0.2 deg jitter): %.3f deg from the "
	       "truth, residual %.3f deg RMS\n",
	       err, rms);
	CHECK(err < 0.5, "correspondences: %g degrees off", err);
	CHECK(glint_register_points(a, b, 1, &r, &rms) < 0,
	      "registered from one point");

	/* Automatic, from "about 90 degrees about Y". */
	struct mat3 guess = m3_rotation_xyz_deg(0, 90, 0), ra;
	double cost;
	CHECK(glint_register_auto(e[0], m[0], e[1], m[1], &guess, &ra, &cost) ==
		      0,
	      "%s", glint_error_msg());
	err = glint_rotation_angle_deg(&ra, &truth);
	printf("automatic: %.3f deg from the truth (cost %.4f)\n", err, cost);
	CHECK(err < 1, "automatic registration: %g degrees off", err);

	/* Blend weighted by mask x density: the whole sphere covered. */
	struct glint_image *w[2], *blend;
	for (int v = 0; v < 2; v++) {
		w[v] = glint_image_new(256, 128);
		for (int i = 0; i < 256 * 128 * 3; i++)
			w[v]->data[i] = m[v]->data[i] * dn[v]->data[i];
	}
	CHECK(glint_probe_blend(e[0], w[0], e[1], w[1], &ra, &blend) == 0, "%s",
	      glint_error_msg());
	long covered = 0, one = 0;
	double *rel = malloc(sizeof(double) * 256 * 128);
	long nr = 0;
	for (int y = 0; y < 128; y++)
		for (int x = 0; x < 256; x++) {
			struct vec3 d;
			float w2[3];
			glint_probe_pixel_dir(GLINT_PROBE_LATLONG, 256, 128,
					      x + 0.5, y + 0.5, &d);
			glint_probe_lookup(m[1], GLINT_PROBE_LATLONG,
					   m3_tmul(&ra, d), w2);
			int ok = glint_image_px(m[0], x, y)[0] > 0.5 ||
				 w2[0] > 0.5;
			covered += ok;
			one += glint_image_px(m[0], x, y)[0] > 0.5;
			const float *t = glint_image_px(env1, x, y),
				    *p = glint_image_px(blend, x, y);
			double lt = t[0] + t[1] + t[2], lp = p[0] + p[1] + p[2];
			if (ok && lt > 0)
				rel[nr++] = fabs(lp / lt - 1);
		}
	qsort(rel, (size_t)nr, sizeof(double), cmp_double);
	printf("blend: %.1f %% of the sphere reliable in a view (one view: "
	       "%.1f %%); median error %.4f\n",
	       100.0 * covered / (256 * 128), 100.0 * one / (256 * 128),
	       rel[nr / 2]);
	CHECK(covered > 0.995 * 256 * 128, "blend covers %.1f %%",
	      100.0 * covered / (256 * 128));
	CHECK(rel[nr / 2] < 0.03, "blend median error %g", rel[nr / 2]);
	free(rel);
	for (int v = 0; v < 2; v++) {
		glint_image_free(ph[v]);
		glint_image_free(e[v]);
		glint_image_free(m[v]);
		glint_image_free(dn[v]);
		glint_image_free(w[v]);
	}
	glint_image_free(blend);
	glint_image_free(env1);
	glint_image_free(env2);
	glint_image_free(big);
	return test_result();
}
