/* SPDX-License-Identifier: MIT */
/*
 * Real photographs glint did not make: the UW photometric-stereo matte gray
 * sphere (../shared/data/spheres/uw_psm/gray/), 8-bit TGA, 512 x 340, each
 * lit by one distant point light of known direction (lights.txt).  Each
 * photo is fitted alone with Lambert, Oren-Nayar and Torrance-Sparrow and
 * the per-light answers are compared against their reported intervals;
 * then all the photos are fitted jointly (glint_fit_views()) and the
 * per-light answers compared with that.
 *
 *   bench/gray_sphere [--response srgb|gamma:G] [--max-pixels N] [LIGHT...]
 *
 * The set-up, stated:
 *   - response: the 8-bit codes are linearised through the sRGB curve
 *     (IEC 61966-2-1) unless --response gamma:G (code^G); 255 is clipped
 *     (weight 0), 0 is kept;
 *   - noise: each code is uncertain by its quantisation step (variance
 *     1/12 code^2) plus one code of read noise, carried through the
 *     response's slope into a per-pixel weight;
 *   - geometry: the sphere's circle from gray.mask.tga (centroid, radius
 *     from the area); an almost orthographic camera (focal length 20 000 px:
 *     the dataset gives none) with the sphere at the distance that makes its
 *     radius match; lights.txt directions in camera coordinates, x right,
 *     y up, z toward the camera;
 *   - light: a disc of 0.5 degrees radius in a 2048 x 1024 lat-long map
 *     whose irradiance at normal incidence is pi, so a Lambertian sphere of
 *     albedo a shows a n.l: the albedos are in the photo's units (the
 *     light's strength is not known).
 * Prints one row per light and model, then the spread of each parameter
 * across lights against the median reported standard error.
 */
#include "bench.h"
#include "sim/fixtures.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/image.h"
#include "core/log.h"
#include "fit/fit.h"
#include "fit/render/render.h"
#include "fit/scene/envmap.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DIR	GLINT_SHARED_DATA "/spheres/uw_psm"
#define NLIGHTS 12

static double response_gamma; /* 0: sRGB */

static double linear(double code)
{
	if (response_gamma > 0)
		return pow(code, response_gamma);
	return code <= 0.04045 ? code / 12.92
			       : pow((code + 0.055) / 1.055, 2.4);
}

/* d linear / d code, numerically. */
static double slope(double code)
{
	double h = 1e-4;
	return (linear(fmin(1, code + h)) - linear(fmax(0, code - h))) /
	       (fmin(1, code + h) - fmax(0, code - h));
}

static int read_lights(struct vec3 *l)
{
	FILE *f = fopen(DIR "/lights.txt", "r");
	int n = 0;

	if (!f)
		return glint_error_set(errno, "%s/lights.txt: cannot open",
				       DIR);
	if (fscanf(f, "%d", &n) != 1 || n != NLIGHTS)
		n = -1;
	for (int i = 0; i < NLIGHTS && n > 0; i++)
		if (fscanf(f, "%lf %lf %lf", &l[i].x, &l[i].y, &l[i].z) != 3)
			n = -1;
	fclose(f);
	return n < 0 ? glint_error_set(EINVAL, "lights.txt: expected 12 "
					       "directions")
		     : 0;
}

/* The mask's circle: centroid and the radius of a disc of its area. */
static int mask_circle(double *cx, double *cy, double *r)
{
	struct glint_image *m;
	int ret = glint_ldr_read_image(DIR "/gray/gray.mask.tga", &m);
	double n = 0, sx = 0, sy = 0;

	if (ret < 0)
		return ret;
	for (int y = 0; y < m->height; y++)
		for (int x = 0; x < m->width; x++)
			if (m->data[((size_t)y * m->width + x) * 3] > 0.5f) {
				n++;
				sx += x + 0.5;
				sy += y + 0.5;
			}
	glint_image_free(m);
	if (n < 100)
		return glint_error_set(EINVAL, "gray.mask.tga: no sphere");
	*cx = sx / n;
	*cy = sy / n;
	*r = sqrt(n / M_PI);
	return 0;
}

struct row {
	double p[GLINT_MAX_PARAMS], se[GLINT_MAX_PARAMS];
	double rel_rmse, bic;
};

/* One light's photo, weights and scene, traced. */
struct shot {
	struct glint_image *photo, *weight;
	struct glint_renderer r;
	int inited;
};

static void shot_free(struct shot *s)
{
	if (s->inited)
		glint_renderer_release(&s->r);
	glint_image_free(s->photo);
	glint_image_free(s->weight);
	memset(s, 0, sizeof(*s));
}

static int load_light(int li, struct vec3 ldir, double cx, double cy,
		      double rpx, struct shot *s)
{
	char path[512];
	struct glint_image *map;
	struct glint_envmap *env = NULL;
	struct glint_scene sc;
	int ret;

	memset(s, 0, sizeof(*s));
	snprintf(path, sizeof(path), DIR "/gray/gray.%d.tga", li);
	ret = glint_ldr_read_image(path, &s->photo);
	if (ret < 0)
		return ret;
	s->weight = glint_image_new(s->photo->width, s->photo->height);
	if (!s->weight)
		return -ENOMEM;
	for (size_t k = 0; k < (size_t)s->photo->width * s->photo->height * 3;
	     k++) {
		double c = s->photo->data[k];
		double sd = slope(c) * sqrt(1.0 / 12 + 1) / 255;
		s->photo->data[k] = (float)linear(c);
		s->weight->data[k] = c >= 1 ? 0 : (float)(1 / (sd * sd));
	}
	glint_scene_defaults(&sc);
	double fpx = 20000, pitch = 1e-5, R = 0.05;
	glint_pinhole_init(&sc.cam, s->photo->width, s->photo->height,
			   fpx * pitch, pitch, 0, 0, v3(0, 0, 0), v3(0, 0, -1),
			   v3(0, 1, 0));
	ret = glint_pinhole_sphere_from_circle(&sc.cam, cx, cy, rpx, R,
					       &sc.sphere_centre);
	sc.sphere_radius = R;
	sc.env_scale = 1;
	map = ret < 0 ? NULL : fixture_disc_map(ldir, 2048, 0.5, 0);
	if (!ret && !map)
		ret = -ENOMEM;
	if (!ret)
		ret = glint_envmap_new(map, sc.env_rotation, 1, "point light",
				       &env);
	if (!ret)
		ret = glint_renderer_init_env(&s->r, &sc, env, 0, NULL);
	s->inited = !ret;
	return ret;
}

/* Fit models[m] to the shots (one: alone; several: jointly). */
static int fit_shots(struct shot *const *shots, int n, int max_pixels,
		     const struct glint_model *model, struct row *row,
		     struct glint_fit_result *out)
{
	struct glint_fit_view v[NLIGHTS];
	struct glint_fit_opts o;
	struct glint_fit_result res;

	for (int k = 0; k < n; k++)
		v[k] = (struct glint_fit_view){ &shots[k]->r, shots[k]->photo,
						shots[k]->weight };
	glint_fit_default_opts(&o);
	o.max_pixels = max_pixels;
	int ret = glint_fit_views(v, n, model, &o, &res);
	if (ret < 0)
		return ret;
	memcpy(row->p, res.p, sizeof(res.p));
	memcpy(row->se, res.se, sizeof(res.se));
	row->rel_rmse = res.rel_rmse;
	double nv = 3.0 * res.pixels;
	row->bic = nv * log(2 * res.cost / nv) + model->nparams * log(nv);
	if (out)
		*out = res;
	return 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/*
 * One fit of each model to all the lights' photos at once (glint fit with
 * several photos): its values and intervals, each photo's relative RMSE,
 * and how the per-light fits sit against it: the chi^2 per degree of
 * freedom of their differences from the joint value in their own
 * standard errors, and how many of their intervals hold it.
 */
static int joint_fits(struct shot *const *shots, int n, int max_pixels,
		      const struct glint_model **models, int nmodels,
		      struct row (*rows)[3], const int *use)
{
	struct glint_fit_result *res = malloc(sizeof(*res));

	if (!res)
		return -ENOMEM;
	printf("\njoint fit of the %d lights' photos (one material, every "
	       "photo in its own scene):\n",
	       n);
	for (int m = 0; m < nmodels; m++) {
		struct row jr;
		double t0 = glint_clock_monotonic();
		int ret = fit_shots(shots, n, max_pixels, models[m], &jr, res);
		if (ret < 0) {
			free(res);
			return ret;
		}
		printf("  %-17s rel.RMSE %.4f, BIC %.1f, chi2/dof %.2f, "
		       "%.0f s; per photo:",
		       models[m]->name, jr.rel_rmse, jr.bic, res->unc.chi2_dof,
		       glint_clock_monotonic() - t0);
		for (int v = 0; v < res->nviews; v++)
			printf(" %.3f", res->view[v].rel_rmse);
		printf("\n");
		for (int k = 0; k < models[m]->nparams; k++) {
			if (k == 1 || k == 2 || k == 4 || k == 5)
				continue;
			double chi2 = 0;
			int cnt = 0, hold = 0;
			for (int i = 0; i < NLIGHTS; i++) {
				if (!use[i] || !(rows[i][m].se[k] > 0) ||
				    !isfinite(rows[i][m].se[k]))
					continue;
				double z = (rows[i][m].p[k] - jr.p[k]) /
					   rows[i][m].se[k];
				chi2 += z * z;
				cnt++;
				hold += fabs(z) <= 1.96;
			}
			printf("    %-18s %8.4f +- %.4f  [%.4f, %.4f]   per "
			       "light vs joint: chi2/dof %.2f, %d of %d "
			       "intervals hold it\n",
			       models[m]->params[k].name, jr.p[k], jr.se[k],
			       res->unc.lo[k], res->unc.hi[k],
			       cnt > 1 ? chi2 / (cnt - 1) : NAN, hold, cnt);
		}
		fflush(stdout);
	}
	free(res);
	return 0;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/gray_sphere [--response "
				    "srgb|gamma:G] [--max-pixels N] [LIGHT...]";
	bench_help(argc, argv, usage);
	const struct glint_model *models[] = { &glint_model_lambert,
					       &glint_model_oren_nayar,
					       &glint_model_torrance_sparrow };
	enum { NM = 3 };
	struct vec3 lights[NLIGHTS];
	static struct row rows[NLIGHTS][NM];
	int use[NLIGHTS], nuse = 0, max_pixels = 4096;
	double cx = 0, cy = 0, rpx = 0;

	for (int i = 0; i < NLIGHTS; i++)
		use[i] = 0;
	for (int a = 1; a < argc; a++) {
		if (!strcmp(argv[a], "--response") && a + 1 < argc) {
			a++;
			if (!strncmp(argv[a], "gamma:", 6))
				response_gamma = atof(argv[a] + 6);
		} else if (!strcmp(argv[a], "--max-pixels") && a + 1 < argc) {
			max_pixels = atoi(argv[++a]);
		} else {
			int k = bench_count(argv[a], 0, NLIGHTS - 1);
			if (k < 0)
				bench_refuse(argv[a], usage);
			use[k] = 1, nuse++;
		}
	}
	if (!nuse)
		for (int i = 0; i < NLIGHTS; i++)
			use[i] = 1, nuse++;
	glint_log_set_mode(GLINT_LOG_QUIET);
	if (read_lights(lights) < 0 || mask_circle(&cx, &cy, &rpx) < 0) {
		fprintf(stderr, "gray_sphere: %s\n", glint_error_msg());
		return 1;
	}
	printf("gray sphere: circle (%.1f, %.1f) r %.1f px; response %s\n", cx,
	       cy, rpx, response_gamma > 0 ? "gamma" : "sRGB");
	if (response_gamma > 0)
		printf("  gamma %.3f\n", response_gamma);
	printf("light  angle  model              rel.RMSE        BIC   "
	       "parameters (value +- standard error)\n");
	static struct shot shots[NLIGHTS];
	struct shot *used[NLIGHTS];
	int nused = 0;
	for (int i = 0; i < NLIGHTS; i++) {
		if (!use[i])
			continue;
		struct shot *sp = &shots[i];
		int ret = load_light(i, lights[i], cx, cy, rpx, sp);
		for (int m = 0; m < NM && ret == 0; m++)
			ret = fit_shots(&sp, 1, max_pixels, models[m],
					&rows[i][m], NULL);
		if (ret < 0) {
			fprintf(stderr, "gray_sphere: light %d: %s\n", i,
				glint_error_msg());
			return 1;
		}
		used[nused++] = sp;
		for (int m = 0; m < NM; m++) {
			printf("%5d  %5.1f  %-17s  %8.4f  %9.1f  ", i,
			       acos(lights[i].z) * 180 / M_PI, models[m]->name,
			       rows[i][m].rel_rmse, rows[i][m].bic);
			for (int k = 0; k < models[m]->nparams; k++)
				if (k != 1 && k != 2 && k != 4 && k != 5)
					printf(" %s %.4f+-%.4f",
					       models[m]->params[k].name,
					       rows[i][m].p[k],
					       rows[i][m].se[k]);
			printf("\n");
		}
		fflush(stdout);
	}
	if (nused > 1 &&
	    joint_fits(used, nused, max_pixels, models, NM, rows, use) < 0) {
		fprintf(stderr, "gray_sphere: joint fit: %s\n",
			glint_error_msg());
		return 1;
	}
	for (int i = 0; i < NLIGHTS; i++)
		shot_free(&shots[i]);
	/* Across lights: each parameter's spread against its errors. */
	printf("\nacross %d lights: parameter, mean, standard deviation, "
	       "median standard error, ratio; combined (inverse-variance) "
	       "+- error\n",
	       nuse);
	for (int m = 0; m < NM; m++)
		for (int k = 0; k < models[m]->nparams; k++) {
			if (k == 1 || k == 2 || k == 4 || k == 5)
				continue;
			double v[NLIGHTS], s[NLIGHTS], mean = 0, var = 0;
			int n = 0;
			for (int i = 0; i < NLIGHTS; i++)
				if (use[i]) {
					v[n] = rows[i][m].p[k];
					s[n++] = rows[i][m].se[k];
					mean += rows[i][m].p[k];
				}
			mean /= n;
			for (int j = 0; j < n; j++)
				var += (v[j] - mean) * (v[j] - mean);
			double sd = n > 1 ? sqrt(var / (n - 1)) : 0;
			/* The lights combined: inverse-variance mean, its
			 * error, and chi2/dof of their agreement (the error
			 * inflated by its root when above 1: Birge). */
			double sw = 0, swx = 0, chi2 = 0;
			for (int j = 0; j < n; j++)
				if (isfinite(s[j]) && s[j] > 0) {
					sw += 1 / (s[j] * s[j]);
					swx += v[j] / (s[j] * s[j]);
				}
			double cm = sw > 0 ? swx / sw : NAN;
			for (int j = 0; j < n; j++)
				if (isfinite(s[j]) && s[j] > 0)
					chi2 += (v[j] - cm) * (v[j] - cm) /
						(s[j] * s[j]);
			double cdof = n > 1 ? chi2 / (n - 1) : NAN;
			double cse = sw > 0 ? sqrt(1 / sw) * fmax(1, sqrt(cdof))
					    : NAN;
			qsort(s, n, sizeof(double), cmp_double);
			double med = s[n / 2];
			printf("  %-17s %-18s %8.4f %8.4f %8.4f %7.1f   %8.4f "
			       "+- %.4f (chi2/dof %.2f)\n",
			       models[m]->name, models[m]->params[k].name, mean,
			       sd, med, med > 0 ? sd / med : 0, cm, cse, cdof);
		}
	return 0;
}
