/* SPDX-License-Identifier: MIT */
/*
 * Where the fitter's objective differs from a photo: the shade cache's
 * image of a material (the fitter's own estimate, its default samples)
 * against a reference photo, pixel by pixel over the sphere's interior
 * as the fit takes it.
 *
 *   bench/residual MAP MATERIAL PHOTO.exr [ROUGHNESS...]
 *
 * PHOTO is fixture_scene's 256 px view of MATERIAL under MAP (a map file
 * or class:NAME, as bench/accuracy takes them), as bench/accuracy's
 * ACCURACY_DUMP or ACCURACY_CACHE writes it.  For the
 * truth's roughness and each ROUGHNESS given (the truth's other
 * parameters), prints the sum of squared differences over the interior,
 * split between the highlight (photo above 4x the interior's median) and
 * the rest, the highlight's total against the photo's, and the five
 * pixels that differ most.  RESIDUAL_NO_FOOTPRINT=1, RESIDUAL_SAMPLES=N
 * and RESIDUAL_SPP=N change the fast path as bench/accuracy's options
 * (RESIDUAL_LIGHT_SAMPLES=N the light samples alone: 0 leaves the lobe
 * samples' estimate by itself);
 * RESIDUAL_SEED=N the fast path's sample seed (RESIDUAL_LOBE_SUMS=1 prints
 * each lobe's red integral summed over the interior: over seeds and
 * sample counts, whether the estimate itself is biased); RESIDUAL_NO_HOT=1 no
 * hot texels (the whole map sampled); RESIDUAL_AT=P1,P2,... one more row at
 * every parameter given (a fit's answer against the truth), each row also split
 * by the view's angle to the normal (all three channels).
 * RESIDUAL_OTHER=PHOTO2.exr (the same scene rendered with another seed)
 * prints the photo's own Monte Carlo noise on the same terms: half the
 * squared differences of the two photos over the interior.
 */
#define _DEFAULT_SOURCE
#include "bench.h"
#include "sim/fixtures.h"

#include "core/error.h"
#include "fit/brdf/model.h"
#include "fit/fit.h"
#include "fit/fit_data.h"
#include "fit/render/render.h"
#include "fit/render/shade_cache.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct px {
	int x, y;
	double photo, fast;
};

static int by_diff(const void *a, const void *b)
{
	const struct px *p = a, *q = b;
	double dp = fabs(p->fast - p->photo), dq = fabs(q->fast - q->photo);
	return (dq > dp) - (dq < dp);
}

int main(int argc, char **argv)
{
	static const char usage[] =
		"bench/residual MAP MATERIAL PHOTO.exr [ROUGHNESS...]";
	bench_help(argc, argv, usage);
	for (int i = 1; i < argc; i++)
		if (argv[i][0] == '-' && argv[i][1] && !isdigit(argv[i][1]))
			bench_refuse(argv[i], usage);
	if (argc < 4) {
		fprintf(stderr, "usage: %s\n", usage);
		return 2;
	}
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	struct glint_image *photo = NULL;
	if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json", argv[2],
				&m, truth) < 0 ||
	    glint_image_read(argv[3], &photo) < 0) {
		fprintf(stderr, "residual: %s\n", glint_error_msg());
		return 1;
	}
	struct glint_scene sc;
	struct glint_renderer r;
	struct glint_envmap *env = NULL;
	fixture_scene(&sc, 256, argv[1]);
	if (getenv("RESIDUAL_SPP"))
		sc.spp = atoi(getenv("RESIDUAL_SPP"));
	if (fixture_load_map(argv[1], &sc, &env) < 0 ||
	    glint_renderer_init_env(&r, &sc, env, 0, NULL) < 0) {
		fprintf(stderr, "residual: %s\n", glint_error_msg());
		return 1;
	}
	/* The interior as the fit takes it (fit_data_interior()). */
	const struct glint_gbuffer *gb = &r.gb;
	if (photo->width != gb->width || photo->height != gb->height) {
		fprintf(stderr,
			"residual: %s is %dx%d, not the scene's %dx%d\n",
			argv[3], photo->width, photo->height, gb->width,
			gb->height);
		return 1;
	}
	int npix = gb->width * gb->height, n = 0;
	int32_t *pix = malloc((size_t)npix * sizeof(*pix));
	for (int i = 0; i < npix; i++)
		if (fit_data_interior(gb, i % gb->width, i / gb->width))
			pix[n++] = i;
	/* The fit's own samples (its defaults, before it raises them). */
	struct glint_fit_opts fo;
	glint_fit_default_opts(&fo);
	glint_fit_resolve_samples(&fo, gb->spp);
	struct glint_shade_cache_opts co = {
		.light_samples = fo.light_samples,
		.lobe_samples = fo.lobe_samples,
		.static_samples = fo.static_samples,
		.no_footprint = getenv("RESIDUAL_NO_FOOTPRINT") != NULL,
	};
	if (getenv("RESIDUAL_SAMPLES"))
		co.light_samples = co.lobe_samples =
			atoi(getenv("RESIDUAL_SAMPLES"));
	co.no_hot = getenv("RESIDUAL_NO_HOT") != NULL;
	if (getenv("RESIDUAL_SEED"))
		co.seed = (uint32_t)atoi(getenv("RESIDUAL_SEED"));
	if (getenv("RESIDUAL_LIGHT_SAMPLES"))
		co.light_samples = atoi(getenv("RESIDUAL_LIGHT_SAMPLES"));
	struct glint_shade_cache *c = NULL;
	if (glint_shade_cache_new(gb, pix, n, r.env, m, &co, &c) < 0) {
		fprintf(stderr, "residual: %s\n", glint_error_msg());
		return 1;
	}
	double *lobes =
		malloc((size_t)n * m->bxdf->nlobes * 3 * sizeof(double));
	struct px *px = malloc((size_t)n * sizeof(*px));
	double *vals = malloc((size_t)n * sizeof(double));
	int nr = argc - 3;
	if (nr > 1 && m->lobes->roughness_param < 0) {
		fprintf(stderr, "residual: %s has no roughness\n", m->name);
		return 1;
	}
	const char *other_path = getenv("RESIDUAL_OTHER");
	if (other_path) {
		struct glint_image *other = NULL;
		if (glint_image_read(other_path, &other) < 0 ||
		    other->width != photo->width ||
		    other->height != photo->height) {
			fprintf(stderr, "residual: %s: %s\n", other_path,
				other ? "not the photo's size"
				      : glint_error_msg());
			glint_image_free(other);
			return 1;
		}
		double ssd = 0;
		for (int i = 0; i < n; i++) {
			int x = pix[i] % gb->width, y = pix[i] / gb->width;
			double d = glint_image_px(photo, x, y)[0] -
				   glint_image_px(other, x, y)[0];
			ssd += d * d;
		}
		printf("the photo's own noise: red channel, SSD %.4g "
		       "(half that of the two photos)\n",
		       ssd / 2);
		glint_image_free(other);
	}
	/* RESIDUAL_AT: one more row at every parameter given. */
	double at[GLINT_MAX_PARAMS];
	const char *at_s = getenv("RESIDUAL_AT");
	if (at_s) {
		char *end = (char *)at_s;
		for (int k = 0; k < m->nparams; k++) {
			char *from = end;
			at[k] = strtod(from, &end);
			if (end == from ||
			    *end != (k + 1 < m->nparams ? ',' : '\0')) {
				fprintf(stderr,
					"residual: RESIDUAL_AT needs %d values "
					"separated by commas\n",
					m->nparams);
				return 1;
			}
			end += k + 1 < m->nparams;
		}
		nr++;
	}
	for (int k = 0; k < nr; k++) {
		double p[GLINT_MAX_PARAMS];
		memcpy(p, truth, sizeof(p));
		if (at_s && k == nr - 1)
			memcpy(p, at, sizeof(p));
		else if (k)
			p[m->lobes->roughness_param] = atof(argv[3 + k]);
		glint_shade_cache_lobes(c, p, lobes);
		if (getenv("RESIDUAL_LOBE_SUMS")) {
			for (int j = 0; j < m->bxdf->nlobes; j++) {
				double sj = 0;
				for (int i = 0; i < n; i++)
					sj += lobes[((size_t)i *
							     m->bxdf->nlobes +
						     j) *
						    3];
				printf("lobe %d sum %.6f\n", j, sj);
			}
		}
		for (int i = 0; i < n; i++) {
			px[i].x = pix[i] % gb->width;
			px[i].y = pix[i] / gb->width;
			const float *ph =
				glint_image_px(photo, px[i].x, px[i].y);
			double f = 0;
			for (int j = 0; j < m->bxdf->nlobes; j++)
				f += p[m->lobes->param[j]] *
				     lobes[((size_t)i * m->bxdf->nlobes + j) *
					   3];
			px[i].fast = f;
			px[i].photo = ph[0];
			vals[i] = ph[0];
		}
		double med = bench_median(vals, n);
		double ssd_hi = 0, ssd_lo = 0, sum_f = 0, sum_p = 0;
		int nhi = 0;
		for (int i = 0; i < n; i++) {
			double d = px[i].fast - px[i].photo;
			if (px[i].photo > 4 * med) {
				ssd_hi += d * d;
				sum_f += px[i].fast;
				sum_p += px[i].photo;
				nhi++;
			} else {
				ssd_lo += d * d;
			}
		}
		printf("roughness %.5f: red channel, SSD highlight %.4g "
		       "(%d px, total fast/photo %.4f) rest %.4g\n",
		       p[m->lobes->roughness_param], ssd_hi, nhi, sum_f / sum_p,
		       ssd_lo);
		/* All three channels by the view's angle to the normal:
		 * Fresnel shows at grazing, the specular-ior ridge there. */
		double band[4] = { 0, 0, 0, 0 };
		for (int i = 0; i < n; i++) {
			const struct glint_hit *h =
				glint_gbuffer_pixel(gb, (size_t)pix[i]);
			double cs = -(h->n[0] * h->d[0] + h->n[1] * h->d[1] +
				      h->n[2] * h->d[2]);
			int b = cs > 0.75   ? 0
				: cs > 0.5  ? 1
				: cs > 0.25 ? 2
					    : 3;
			const float *ph = glint_image_px(
				photo, pix[i] % gb->width, pix[i] / gb->width);
			for (int ch = 0; ch < 3; ch++) {
				double f = 0;
				for (int j = 0; j < m->bxdf->nlobes; j++)
					f += p[m->lobes->param[j] + ch] *
					     lobes[((size_t)i *
							    m->bxdf->nlobes +
						    j) * 3 +
						   ch];
				band[b] += (f - ph[ch]) * (f - ph[ch]);
			}
		}
		printf("  RGB SSD by cos(view, normal) > 0.75, 0.5, 0.25, "
		       "below: %.4g %.4g %.4g %.4g\n",
		       band[0], band[1], band[2], band[3]);
		qsort(px, (size_t)n, sizeof(*px), by_diff);
		for (int i = 0; i < 5; i++)
			printf("  (%3d, %3d) photo %.4f fast %.4f\n", px[i].x,
			       px[i].y, px[i].photo, px[i].fast);
	}
	free(vals);
	free(px);
	free(lobes);
	free(pix);
	glint_shade_cache_free(c);
	glint_image_free(photo);
	glint_renderer_release(&r);
	return 0;
}
