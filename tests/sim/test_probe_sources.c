/* SPDX-License-Identifier: MIT */
/*
 * Light sources the probe cannot resolve (capture/probe/probe_sources.h),
 * against ground truth: a chrome ball reflecting the Venice map, rendered
 * by the simulator's independent forward renderer (sim/probe_sim.c) and
 * blurred by the sim camera's lens and optical low-pass filter
 * (sim/sensor.h), with noise.  The sun, turned to six places on the ball
 * from near its centre to 0.95 of its radius, is found once, in its direction
 * (within 1 degree and 3 sigma) with its flux (within 3 % and 3 sigma);
 * maps that hold no compact source (smoothed Venice, the studio's
 * softboxes, a flat grey) give no false alarm over many noise draws, nor
 * a bright lamp just outside the ball's rim in the photo; the
 * map's total light is kept by taking a source out and putting it back;
 * the JSON reads back what was written.
 */
#include "test.h"

#include "capture/probe/probe_sources.h"
#include "core/error.h"
#include "sim/probe_sim.h"
#include "sim/sensor.h"

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <stdlib.h>
#include <string.h>

enum { W = 320, H = 240 };
static const double FPX = 640, RADIUS_PX = 96;
static int SPP = 12; /* as sim/scenes.c renders the rig's probe */

static struct glint_image *venice;

/* The map turned about +Y by `shift` texel columns. */
static struct glint_image *turned(const struct glint_image *m, int shift)
{
	struct glint_image *o = glint_image_new(m->width, m->height);
	int w = m->width;
	for (int y = 0; y < m->height; y++)
		for (int x = 0; x < w; x++)
			memcpy(glint_image_px(o, x, y),
			       glint_image_px(m, ((x + shift) % w + w) % w, y),
			       3 * sizeof(float));
	return o;
}

/* A box-filtered copy, f times smaller: no compact light survives. */
static struct glint_image *shrink(const struct glint_image *m, int f)
{
	struct glint_image *o = glint_image_new(m->width / f, m->height / f);
	for (int y = 0; y < o->height; y++)
		for (int x = 0; x < o->width; x++)
			for (int c = 0; c < 3; c++) {
				double s = 0;
				for (int j = 0; j < f; j++)
					for (int i = 0; i < f; i++)
						s += glint_image_px(
							m, f * x + i,
							f * y + j)[c];
				glint_image_px(o, x, y)[c] =
					(float)(s / (f * f));
			}
	return o;
}

/* The ball photographed: the forward render (spp x spp rays a pixel:
 * a sun of 0.7 deg needs 12 where a pixel spans 2 deg; a smooth map
 * needs 3), the camera's optics, and
 * noise of 1 % of the signal plus 0.1 % of the ball's mean (a merged
 * bracket's), whose variance *var gets. */
static struct glint_image *photo_of(const struct glint_image *map, int spp,
				    unsigned long seed,
				    struct glint_image **var)
{
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };
	double d = 1 / sin(atan(RADIUS_PX / FPX));
	struct glint_image *img = NULL;
	struct glint_sensor s;

	CHECK(glint_sim_mirror_ball(map, W, H, FPX, v3(0, 0, -d), 1, n, k, spp,
				    &img) == 0,
	      "%s", glint_error_msg());
	glint_sensor_default(&s);
	CHECK(glint_sensor_optics(&s, img) == 0, "%s", glint_error_msg());
	double mean = 0;
	for (size_t i = 0; i < (size_t)W * H * 3; i++)
		mean += img->data[i] / (W * H * 3.0);
	*var = glint_image_new(W, H);
	gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
	gsl_rng_set(rng, seed);
	for (size_t i = 0; i < (size_t)W * H * 3; i++) {
		double sd = 0.01 * img->data[i] + 0.001 * mean;
		img->data[i] += (float)gsl_ran_gaussian(rng, sd);
		(*var)->data[i] = (float)(sd * sd);
	}
	gsl_rng_free(rng);
	return img;
}

static void ball_opts(struct glint_unwrap_opts *o)
{
	glint_unwrap_default_opts(o);
	o->fpx = FPX;
	o->ball_cx = W / 2.0;
	o->ball_cy = H / 2.0;
	o->ball_r = RADIUS_PX;
}

static struct vec3 texel_dir(const struct glint_image *m, int x, int y)
{
	return glint_latlong_uv_to_dir((x + 0.5) / m->width,
				       (y + 0.5) / m->height);
}

/* The sun of map m: its direction (the brightest texel) and its flux,
 * the integral of L d(omega) within 3 degrees less the 4-8 degree ring's
 * mean radiance. */
static void sun_truth(const struct glint_image *m, struct vec3 *dir,
		      double flux[3])
{
	int w = m->width, h = m->height, bx = 0, by = 0;
	double best = -1, in[3] = { 0, 0, 0 }, ring[3] = { 0, 0, 0 };
	double om_in = 0, om_ring = 0;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			if (glint_image_px(m, x, y)[0] > best) {
				best = glint_image_px(m, x, y)[0];
				bx = x;
				by = y;
			}
	*dir = texel_dir(m, bx, by);
	for (int y = 0; y < h; y++) {
		double om =
			(2 * M_PI / w) * (M_PI / h) * sin((y + 0.5) * M_PI / h);
		for (int x = 0; x < w; x++) {
			double a = acos(fmin(1, v3_dot(texel_dir(m, x, y),
						       *dir))) *
				   180 / M_PI;
			const float *p = glint_image_px(m, x, y);
			for (int c = 0; c < 3; c++) {
				if (a <= 3)
					in[c] += p[c] * om;
				else if (a >= 4 && a <= 8)
					ring[c] += p[c] * om;
			}
			om_in += a <= 3 ? om / 3 : 0;
			om_ring += a >= 4 && a <= 8 ? om / 3 : 0;
		}
	}
	for (int c = 0; c < 3; c++)
		flux[c] = in[c] - ring[c] / om_ring * om_in;
}

static void test_sun(void)
{
	/* the sun (at azimuth 36 deg in the map) turned to 60, 90, 120 and
	 * 150 deg from the direction straight behind the ball, incidence
	 * 60 deg to 15 (near the ball's centre), then to 45 and 35 deg:
	 * incidence 67 and 72 deg, 0.92 and 0.95 of the ball's radius,
	 * where the 4-pixel aperture crosses the map's 80-degree grazing
	 * line (a lamp behind the sample).  There a pixel spans 3.5-4.7 deg
	 * (a quarter pixel of centroid error is 0.9-1.2 deg): the direction
	 * within a third of a pixel and 3 sigma; the flux within 3 % and
	 * 3 sigma, in the dim green of a sunset sun (15 % of its red,
	 * sigma 3-5 %) within 3 sigma and 10 %. */
	static const int shifts[] = { -68, -154, -239, -324, -25, 3 };
	struct glint_source_opts so;

	glint_source_default_opts(&so);
	for (int k = 0; k < 6; k++) {
		struct glint_image *map = turned(venice, shifts[k]), *var;
		struct glint_image *ph = photo_of(map, SPP, 11 + k, &var);
		struct glint_unwrap_opts o;
		struct glint_light_sources s;
		struct vec3 dir;
		double flux[3];

		ball_opts(&o);
		sun_truth(map, &dir, flux);
		CHECK(glint_probe_find_sources(ph, var, NULL, &o, &so, &s,
					       NULL) == 0,
		      "%s", glint_error_msg());
		CHECK(s.n == 1, "sun at azimuth %.0f: %d sources found",
		      atan2(dir.x, -dir.z) * 180 / M_PI, s.n);
		if (s.n >= 1) {
			const struct glint_light_source *l = &s.s[0];
			double a =
				acos(fmin(1, v3_dot(l->dir, dir))) * 180 / M_PI;
			printf("sun at azimuth %6.1f: found %.2f deg off "
			       "(sigma %.2f, %.2f deg a pixel), flux "
			       "r %.4f g %.4f of the truth (sigma %.4f, "
			       "%.4f)\n",
			       atan2(dir.x, -dir.z) * 180 / M_PI, a,
			       l->dir_sigma_deg, l->px_deg,
			       l->flux[0] / flux[0], l->flux[1] / flux[1],
			       l->flux_sigma[0] / flux[0],
			       l->flux_sigma[1] / flux[1]);
			int rim = k >= 4;
			CHECK(a < (rim ? l->px_deg / 3 : 1) &&
				      a < 3 * l->dir_sigma_deg,
			      "direction %.2f deg off (sigma %.2f)", a,
			      l->dir_sigma_deg);
			for (int c = 0; c < 2; c++) {
				double e = fabs(l->flux[c] - flux[c]);
				double tol = rim && c == 1 ? 0.10 : 0.03;
				CHECK(e < tol * flux[c] &&
					      e < 3 * l->flux_sigma[c],
				      "channel %d flux %g for %g (sigma %g)", c,
				      l->flux[c], flux[c], l->flux_sigma[c]);
			}
		}
		glint_image_free(map);
		glint_image_free(ph);
		glint_image_free(var);
	}
}

/* No compact source: the false alarms over 20 noise draws each of
 * three maps that have none. */
static void test_false_alarms(void)
{
	struct glint_image *maps[3] = { shrink(venice, 16), NULL,
					glint_image_new(64, 32) };
	const char *names[3] = { "Venice smoothed to 5.6 deg", "studio.exr",
				 "flat grey" };
	struct glint_image *studio = NULL;
	struct glint_source_opts so;
	int alarms = 0, photos = 0;

	glint_source_default_opts(&so);
	if (glint_image_read(GLINT_SHARED_DATA
			     "/probes/blender_studiolights/studio.exr",
			     &studio) == 0)
		maps[1] = studio;
	else
		glint_error_clear();
	for (size_t i = 0; i < (size_t)64 * 32 * 3; i++)
		maps[2]->data[i] = 1;
	for (int m = 0; m < 3; m++) {
		int found = 0;
		if (!maps[m]) {
			printf("%s: not here (../shared/data), skipped\n",
			       names[m]);
			continue;
		}
		for (int draw = 0; draw < 20; draw++) {
			struct glint_image *var,
				*ph = photo_of(maps[m], 3, 100 + draw, &var);
			struct glint_unwrap_opts o;
			struct glint_light_sources s;
			ball_opts(&o);
			CHECK(glint_probe_find_sources(ph, var, NULL, &o, &so,
						       &s, NULL) == 0,
			      "%s", glint_error_msg());
			found += s.n;
			photos++;
			glint_image_free(ph);
			glint_image_free(var);
		}
		printf("%s: %d sources in 20 photos\n", names[m], found);
		alarms += found;
	}
	printf("false alarms: %d in %d photos\n", alarms, photos);
	CHECK(alarms == 0, "%d false alarms in %d photos", alarms, photos);
	for (int m = 0; m < 3; m++)
		glint_image_free(maps[m]);
}

/* A lamp beside the ball, 1.5 to 4 px outside its rim in the photo (a
 * light of the lab seen past the probe, a million times the photo's
 * mean), bleeds into the rim's last pixels through the camera's blur (a
 * Gaussian of 0.9 px, the lens, OLPF and pixel together): never a source
 * of the ball's, now that a source's aperture reaches the rim. */
static void test_lamp_beside_ball(void)
{
	struct glint_image *map = shrink(venice, 16);
	struct glint_source_opts so;
	int found = 0, tried = 0;

	glint_source_default_opts(&so);
	for (int k = 0; k < 8; k++) {
		struct glint_image *var, *ph = photo_of(map, 3, 300 + k, &var);
		struct glint_unwrap_opts o;
		struct glint_light_sources s;
		double a = k * M_PI / 4 + 0.3, out = 1.5 + 2.5 * (k % 4) / 3;
		double lx = W / 2.0 + (RADIUS_PX + out) * cos(a);
		double ly = H / 2.0 + (RADIUS_PX + out) * sin(a);
		double mean = 0;
		for (size_t i = 0; i < (size_t)W * H * 3; i++)
			mean += ph->data[i] / (W * H * 3.0);
		for (int y = 0; y < H; y++)
			for (int x = 0; x < W; x++) {
				double d2 = (x + 0.5 - lx) * (x + 0.5 - lx) +
					    (y + 0.5 - ly) * (y + 0.5 - ly);
				float v = (float)(1e6 * mean *
						  exp(-d2 / (2 * 0.81)));
				for (int c = 0; c < 3; c++)
					glint_image_px(ph, x, y)[c] += v;
			}
		ball_opts(&o);
		CHECK(glint_probe_find_sources(ph, var, NULL, &o, &so, &s,
					       NULL) == 0,
		      "%s", glint_error_msg());
		if (s.n)
			printf("lamp %.1f px outside the rim at %.0f deg: "
			       "found as a source at %.1f, %.1f\n",
			       out, a * 180 / M_PI, s.s[0].photo_x,
			       s.s[0].photo_y);
		found += s.n;
		tried++;
		glint_image_free(ph);
		glint_image_free(var);
	}
	printf("lamps beside the ball: %d sources in %d photos\n", found,
	       tried);
	CHECK(found == 0, "%d lamps beside the ball taken as sources", found);
	glint_image_free(map);
}

/* Out of the photo, into the map: the map's total light unchanged
 * (within 1 %), the source now a point; the JSON reads back. */
static void test_round_trip(void)
{
	struct glint_image *map = turned(venice, 240), *var;
	struct glint_image *ph = photo_of(map, SPP, 5, &var);
	struct glint_image *cleaned = NULL, *plain = NULL, *sharp = NULL;
	struct glint_unwrap_opts o;
	struct glint_light_sources s, back;
	struct glint_source_opts so;
	double f0[3], f1[3];
	char path[] = "/tmp/glint-sources-XXXXXX";
	int fd = mkstemp(path);

	glint_source_default_opts(&so);
	ball_opts(&o);
	CHECK(glint_probe_find_sources(ph, var, NULL, &o, &so, &s, &cleaned) ==
		      0,
	      "%s", glint_error_msg());
	CHECK(glint_probe_unwrap(ph, &o, &plain, NULL, NULL) == 0, "%s",
	      glint_error_msg());
	CHECK(cleaned &&
		      glint_probe_unwrap(cleaned, &o, &sharp, NULL, NULL) == 0,
	      "%s", glint_error_msg());
	if (sharp && plain) {
		glint_probe_add_sources(sharp, &s);
		glint_latlong_flux(plain, f0);
		glint_latlong_flux(sharp, f1);
		printf("map's light with the sun as a point / as photographed: "
		       "%.4f %.4f %.4f\n",
		       f1[0] / f0[0], f1[1] / f0[1], f1[2] / f0[2]);
		for (int c = 0; c < 3; c++)
			CHECK(fabs(f1[c] / f0[c] - 1) < 0.01,
			      "channel %d: total light %g for %g", c, f1[c],
			      f0[c]);
	}
	/* The map written (glint_probe_unwrap_write()): at 4 r (384 texels
	 * round) the point's four texels would be 0.94 deg wide; it is at
	 * least 720 wide, its total light that of the map at 4 r. */
	char dir[] = "/tmp/glint-unwrap-XXXXXX", env_path[64];
	int ew = 0, eh = 0;
	struct glint_image *written = NULL;
	CHECK(mkdtemp(dir) != NULL, "mkdtemp");
	snprintf(env_path, sizeof(env_path), "%s/env.exr", dir);
	o.variance = var;
	CHECK(glint_probe_unwrap_write(ph, &o, env_path, &ew, &eh) == 0, "%s",
	      glint_error_msg());
	CHECK(ew == 720 && eh == 360, "a map with a source: %d x %d", ew, eh);
	CHECK(glint_image_read(env_path, &written) == 0, "%s",
	      glint_error_msg());
	if (written && sharp) {
		double fw[3];
		glint_latlong_flux(written, fw);
		for (int c = 0; c < 3; c++)
			CHECK(fabs(fw[c] / f1[c] - 1) < 0.01,
			      "channel %d: the written map's light %g for %g",
			      c, fw[c], f1[c]);
	}
	glint_image_free(written);
	static const char *const made[] = { "env.exr", "env-sources.json",
					    "env-mask.png", "env-density.exr",
					    "env-preview.png" };
	for (size_t i = 0; i < sizeof(made) / sizeof(made[0]); i++) {
		char f[96];
		snprintf(f, sizeof(f), "%s/%s", dir, made[i]);
		unlink(f);
	}
	rmdir(dir);
	o.variance = NULL;
	if (fd >= 0)
		close(fd);
	CHECK(glint_probe_sources_write(path, "photo.exr", &s) == 0, "%s",
	      glint_error_msg());
	CHECK(glint_probe_sources_read(path, &back) == 0, "%s",
	      glint_error_msg());
	CHECK(back.n == s.n && back.n >= 1, "read %d sources of %d", back.n,
	      s.n);
	if (back.n >= 1 && s.n >= 1) {
		CHECK(fabs(back.s[0].flux[0] / s.s[0].flux[0] - 1) < 1e-6 &&
			      v3_dot(back.s[0].dir, s.s[0].dir) > 1 - 1e-9 &&
			      back.s[0].saturated == s.s[0].saturated,
		      "the source read back differs");
	}
	/* the probe's resolution: 2 sqrt 2 / R radians a pixel at 90
	 * degrees from its axis, kept through the file */
	double want = 2 * sqrt(2.0) / RADIUS_PX * 180 / M_PI;
	CHECK(fabs(s.map_pixel_deg - want) < 1e-9 &&
		      fabs(back.map_pixel_deg - s.map_pixel_deg) < 1e-6,
	      "map_pixel_deg %g, read back %g, for %g", s.map_pixel_deg,
	      back.map_pixel_deg, want);
	/* a broken file names itself and the key */
	FILE *f = fopen(path, "w");
	if (f) {
		fputs("{\"total_flux\": [1, 1, 1], \"sources\": "
		      "[{\"direction\": [0, 2, 0]}]}\n",
		      f);
		fclose(f);
	}
	CHECK(glint_probe_sources_read(path, &back) < 0 &&
		      strstr(glint_error_msg(), "sources[0]") &&
		      strstr(glint_error_msg(), path),
	      "a bad direction: '%s'", glint_error_msg());
	glint_error_clear();
	unlink(path);
	glint_image_free(map);
	glint_image_free(ph);
	glint_image_free(var);
	glint_image_free(cleaned);
	glint_image_free(plain);
	glint_image_free(sharp);
}

int main(int argc, char **argv)
{
	if (argc > 1)
		SPP = atoi(argv[1]);
	if (glint_image_read(GLINT_DATA_DIR "/env/venice_sunset_1k.hdr",
			     &venice) < 0) {
		fprintf(stderr, "%s\n", glint_error_msg());
		return 1;
	}
	RUN(test_sun);
	RUN(test_false_alarms);
	RUN(test_lamp_beside_ball);
	RUN(test_round_trip);
	glint_image_free(venice);
	return test_result();
}
