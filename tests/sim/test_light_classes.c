/* SPDX-License-Identifier: MIT */
/*
 * The procedural lighting classes (sim/light_class.h): each map is finite
 * and non-negative; each small source's irradiance is what the class
 * states, at widths where it spans many texels or less than one; the
 * overcast sky is CIE's (zenith 3x the horizon); the window-lit room
 * takes most of its light from a few bright areas near the horizon;
 * names and widths outside the choices are refused, named.
 */
#include "test.h"

#include "core/error.h"
#include "sim/light_class.h"

#include <errno.h>
#include <sys/wait.h>

static double texel_omega(const struct glint_image *img, int j)
{
	return (2 * M_PI / img->width) * (M_PI / img->height) *
	       sin((j + 0.5) * M_PI / img->height);
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Irradiance at normal incidence from the cap of radius cap_deg about d,
 * less the background: the median of the ring from cap_deg to
 * cap_deg + 1.5 degrees, over the cap. */
static void cap_irradiance(const struct glint_image *img, struct vec3 d,
			   double cap_deg, double e[3])
{
	double cap = cos(cap_deg * M_PI / 180),
	       ring = cos((cap_deg + 1.5) * M_PI / 180);
	static double vals[3][1 << 16];
	int nring = 0;
	double sum[3] = { 0 }, cos_omega = 0;

	for (int j = 0; j < img->height; j++)
		for (int i = 0; i < img->width; i++) {
			struct vec3 t = glint_latlong_uv_to_dir(
				(i + 0.5) / img->width,
				(j + 0.5) / img->height);
			double c = v3_dot(t, d);
			const float *px = glint_image_px(img, i, j);
			if (c >= cap) {
				double w = texel_omega(img, j) * c;
				cos_omega += w;
				for (int ch = 0; ch < 3; ch++)
					sum[ch] += px[ch] * w;
			} else if (c >= ring && nring < (1 << 16)) {
				for (int ch = 0; ch < 3; ch++)
					vals[ch][nring] = px[ch];
				nring++;
			}
		}
	for (int ch = 0; ch < 3; ch++) {
		qsort(vals[ch], (size_t)nring, sizeof(double), cmp_double);
		double bg = nring ? vals[ch][nring / 2] : 0;
		e[ch] = sum[ch] - bg * cos_omega;
	}
}

static void test_maps_are_sane(void)
{
	for (const char *const *n = glint_sim_light_classes; *n; n++) {
		struct glint_image *img = NULL, *again = NULL;
		int ret = glint_sim_light_class(*n, 256, &img);
		CHECK(ret == 0 && img, "%s: %s", *n, glint_error_msg());
		if (!img)
			continue;
		CHECK(img->width == 256 && img->height == 128, "%s: %dx%d", *n,
		      img->width, img->height);
		int bad = 0;
		double flux = 0;
		for (size_t k = 0; k < (size_t)img->width * img->height * 3;
		     k++) {
			bad += !isfinite(img->data[k]) || img->data[k] < 0;
			flux += img->data[k];
		}
		CHECK(bad == 0, "%s: %d values negative or not finite", *n,
		      bad);
		CHECK(flux > 0, "%s: a black map", *n);
		glint_sim_light_class(*n, 256, &again);
		CHECK(again && !memcmp(img->data, again->data,
				       sizeof(float) * 3 * 256 * 128),
		      "%s: the same name and width give another map", *n);
		glint_image_free(img);
		glint_image_free(again);
	}
}

static void test_small_sources_keep_their_irradiance(void)
{
	static const int widths[] = { 256, 1024, 2048 };
	int total = 0;

	for (const char *const *n = glint_sim_light_classes; *n; n++) {
		struct vec3 dir[8];
		double e[8][3];
		int ns = glint_sim_light_class_sources(*n, dir, e, 8);
		CHECK(ns >= 0 && ns <= 8, "%s: %d sources", *n, ns);
		for (int wi = 0; wi < 3 && ns > 0; wi++) {
			struct glint_image *img = NULL;
			if (glint_sim_light_class(*n, widths[wi], &img) < 0)
				continue;
			/* Every source is at most 3 degrees across; the
			 * cap holds it and its edge texels. */
			double cap = 1.7 + 2 * 180.0 / img->height;
			for (int s = 0; s < ns; s++) {
				double got[3];
				cap_irradiance(img, dir[s], cap, got);
				for (int ch = 0; ch < 3; ch++)
					CHECK(fabs(got[ch] / e[s][ch] - 1) <
						      0.01,
					      "%s at %d px, source %d, "
					      "channel %d: irradiance %.5g, "
					      "stated %.5g",
					      *n, widths[wi], s, ch, got[ch],
					      e[s][ch]);
				total++;
			}
			glint_image_free(img);
		}
	}
	/* The sun, the lamp, six night lamps; at three widths. */
	CHECK(total == 3 * 8, "%d sources checked", total);
}

static void test_overcast_is_cie(void)
{
	struct glint_image *img = NULL;
	glint_sim_light_class("overcast", 1024, &img);
	CHECK(img != NULL, "%s", glint_error_msg());
	if (!img)
		return;
	/* The first row is 0.09 degrees from the zenith; the row just above
	 * the horizon 0.09 degrees up. */
	double zen = glint_image_px(img, 0, 0)[1];
	double hor = glint_image_px(img, 0, img->height / 2 - 1)[1];
	CHECK_NEAR(zen / hor, 3, 0.02, "zenith over horizon");
	glint_image_free(img);
}

/* Of the window-lit room's flux (luminance x solid angle), the share
 * from elevations -10 to 40 degrees, and from its brightest 5 % of
 * solid angle. */
static void test_window_room_is_lit_from_the_horizon(void)
{
	struct glint_image *img = NULL;
	glint_sim_light_class("window-room", 512, &img);
	CHECK(img != NULL, "%s", glint_error_msg());
	if (!img)
		return;
	size_t n = (size_t)img->width * img->height;
	double *lum = malloc(n * sizeof(double)), total = 0, band = 0,
	       omega = 0;
	for (int j = 0; j < img->height; j++) {
		double el = 90 - (j + 0.5) * 180.0 / img->height;
		for (int i = 0; i < img->width; i++) {
			const float *p = glint_image_px(img, i, j);
			double f = rgb_luminance(p[0], p[1], p[2]) *
				   texel_omega(img, j);
			lum[(size_t)j * img->width + i] =
				rgb_luminance(p[0], p[1], p[2]);
			total += f;
			omega += texel_omega(img, j);
			if (el > -10 && el < 40)
				band += f;
		}
	}
	CHECK(band / total > 0.6, "share from near the horizon %.3f",
	      band / total);
	CHECK_NEAR(omega, 4 * M_PI, 1e-3, "the map's solid angle");
	/* The brightest texels by luminance, summed in solid angle until 5 %
	 * of the sphere: an upper bound on their radiance's threshold. */
	qsort(lum, n, sizeof(double), cmp_double);
	double thresh = lum[(size_t)(0.95 * (double)n)], bright = 0;
	for (int j = 0; j < img->height; j++)
		for (int i = 0; i < img->width; i++) {
			const float *p = glint_image_px(img, i, j);
			double l = rgb_luminance(p[0], p[1], p[2]);
			if (l >= thresh)
				bright += l * texel_omega(img, j);
		}
	CHECK(bright / total > 0.5, "share of the brightest texels %.3f",
	      bright / total);
	free(lum);
	glint_image_free(img);
}

static void test_refusals(void)
{
	struct glint_image *img = (struct glint_image *)1;
	CHECK(glint_sim_light_class("disco", 256, &img) == -EINVAL && !img,
	      "an unknown class");
	CHECK_MSG(glint_error_msg(), "'disco'");
	CHECK_MSG(glint_error_msg(), "window-room");
	CHECK(glint_sim_light_class("overcast", 257, &img) == -EINVAL && !img,
	      "an odd width");
	CHECK_MSG(glint_error_msg(), "257");
	CHECK(glint_sim_light_class("overcast", 32, &img) == -EINVAL,
	      "a width under 64");
}

/* glint demo --light: an unknown class is a usage error naming the
 * choices, before anything is written. */
static void test_demo_option(const char *glint)
{
	char cmd[2048], out[512];
	snprintf(out, sizeof(out), "%s/demo", test_tmpdir());
	snprintf(cmd, sizeof(cmd),
		 "'%s' demo -q --light disco --out '%s' 2>'%s/err'", glint, out,
		 test_tmpdir());
	int st = system(cmd);
	CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 2, "status %d", st);
	char path[600], msg[1024] = "";
	snprintf(path, sizeof(path), "%s/err", test_tmpdir());
	FILE *f = fopen(path, "r");
	if (f) {
		size_t n = fread(msg, 1, sizeof(msg) - 1, f);
		msg[n] = '\0';
		fclose(f);
	}
	CHECK_MSG(msg, "disco");
	CHECK_MSG(msg, "night-lamps");
	snprintf(path, sizeof(path), "%s/photo.exr", out);
	CHECK(access(path, F_OK) != 0, "nothing written: %s", path);
}

int main(int argc, char **argv)
{
	RUN(test_maps_are_sane);
	RUN(test_small_sources_keep_their_irradiance);
	RUN(test_overcast_is_cie);
	RUN(test_window_room_is_lit_from_the_horizon);
	RUN(test_refusals);
	/* The command, where this machine runs it (a cross build's tests
	 * run under an emulator the shell may not know). */
	char probe_cmd[1024];
	if (argc > 1) {
		snprintf(probe_cmd, sizeof(probe_cmd),
			 "'%s' --help >/dev/null 2>&1", argv[1]);
		if (system(probe_cmd) == 0)
			RUN_ARG(test_demo_option, argv[1]);
		else
			fprintf(stderr,
				"skip test_demo_option: %s does not run "
				"here\n",
				argv[1]);
	}
	return test_result();
}
