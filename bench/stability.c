/* SPDX-License-Identifier: MIT */
/*
 * Stability: fits from random starts inside the bounds, at three noise
 * levels (noise-free; one sensor exposure with the mean at 10 % of the ADC
 * range; a dim one at 1 %, about 3x the relative noise).  Every method on
 * the materials at Table 1's edges (roughness 0.005 and 0.22, a diffuse
 * channel of 0, ior 1.15 and 3.23, a dark and a very bright specular);
 * the default method on every opaque Table-1 material.  128 px photos
 * (box-averaged from the cached 512 px reference photos), fast.
 *
 * Outcome of a fit, against the truth and the fit from the paper's start:
 *   converged     every parameter within the tolerances of that fit
 *                 (albedo 0.01, roughness 5 %, ior 0.05);
 *   hit a bound   otherwise, with a parameter on a bound the truth is not;
 *   stalled       otherwise, when LM ran out of iterations;
 *   wrong minimum otherwise (it stopped, converged, somewhere else).
 *   bench/stability [STARTS] [ANNEAL_STARTS]   (default 6 and 1:
 *   annealing is 20x slower; it runs at the normal noise level only)
 * Writes bench-out/stability.csv, stability.gp and stability.png.
 */
#define _DEFAULT_SOURCE
#include "bench.h"
#include "sim/fixtures.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"
#include "fit/fit.h"
#include "sim/reference.h"
#include "sim/sensor.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* Every opaque Table-1 material; the first six are the edges. */
static const char *const materials[] = {
	"green-acrylic",  "teflon",	      "satin-paint",	  "nylon",
	"silver",	  "copper",	      "semi-gloss-paint", "matte-paint",
	"yellow-plastic", "aluminium-bronze", "nickel",
};
#define NM    11
#define NEDGE 6
static const double noise_levels[] = { 0, 0.1, 0.01 };
#define NNOISE 3

struct method {
	const char *name;
	enum glint_fit_method m;
	enum glint_fit_optimizer opt;
};
static const struct method methods[] = {
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM },
	{ "naive", GLINT_FIT_NAIVE, GLINT_OPT_LM },
	{ "varpro", GLINT_FIT_VARPRO, GLINT_OPT_LM },
	{ "anneal", GLINT_FIT_THREE_PASS, GLINT_OPT_ANNEAL },
};
#define NMETH 4

enum { CONVERGED, BOUND, STALLED, WRONG, NOUT };
static const char *const outcome_names[NOUT] = { "converged", "hit a bound",
						 "stalled", "wrong minimum" };

static struct glint_image *
photo_128(const char *mat, const struct glint_model *m, const double *truth)
{
	struct glint_image *big = bench_photo_512(mat, m, truth);
	struct glint_image *img = big ? fixture_shrink(big, 4) : NULL;
	glint_image_free(big);
	return img;
}

static int within(const double *p, const double *q)
{
	return fixture_tolerance_error(p, q) <= 1;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/stability [STARTS] [ANNEAL_STARTS]";
	bench_help(argc, argv, usage);
	int starts = argc > 1 ? bench_count(argv[1], 1, 1000) : 6;
	int anneal_starts = argc > 2 ? bench_count(argv[2], 0, 1000) : 1;
	if (starts < 0 || anneal_starts < 0 || argc > 3)
		bench_refuse(argv[starts < 0	      ? 1
				  : anneal_starts < 0 ? 2
						      : 3],
			     usage);
	int count[NMETH][NOUT] = { { 0 } };
	/* The default method on every material, per noise level. */
	int dconv[NNOISE] = { 0 }, dfits[NNOISE] = { 0 };
	double secs[NMETH] = { 0 };
	int fits[NMETH] = { 0 };
	uint64_t rs = 2026;

	glint_log_set_mode(GLINT_LOG_QUIET);
	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/stability.csv", "w");
	fprintf(csv, "method,material,noise_level,start,outcome,seconds,"
		     "max_dev_tol\n");
	for (int mi = 0; mi < NM; mi++) {
		const struct glint_model *m;
		double truth[GLINT_MAX_PARAMS];
		struct glint_scene sc;
		struct glint_renderer r;
		if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
					materials[mi], &m, truth) < 0)
			return 1;
		struct glint_image *clean = photo_128(materials[mi], m, truth);
		fixture_scene(&sc, 128, NULL);
		if (!clean || glint_renderer_init(&r, &sc, 0, NULL) < 0) {
			fprintf(stderr, "bench/stability: %s\n",
				glint_error_msg());
			return 1;
		}
		for (int nl = 0; nl < NNOISE; nl++) {
			struct glint_image *photo =
				glint_image_new(clean->width, clean->height);
			struct glint_image *weight = NULL;
			memcpy(photo->data, clean->data,
			       (size_t)clean->width * clean->height * 3 *
				       sizeof(float));
			if (noise_levels[nl] > 0 &&
			    fixture_add_noise(photo, &weight,
					      noise_levels[nl]) < 0)
				return 1;
			/* The reference: the default fit from the paper's
			 * start. */
			struct glint_fit_opts o;
			struct glint_fit_result ref;
			glint_fit_default_opts(&o);
			if (glint_fit(&r, m, photo, weight, &o, &ref) < 0)
				return 1;
			for (int s = 0; s < starts; s++) {
				double start[GLINT_MAX_PARAMS];
				for (int k = 0; k < m->nparams; k++) {
					rs = rs * 6364136223846793005ull +
					     1442695040888963407ull;
					double u = (double)(rs >> 11) /
						   9007199254740992.0;
					start[k] = m->params[k].lo +
						   u * (m->params[k].hi -
							m->params[k].lo);
				}
				for (int me = 0; me < NMETH; me++) {
					struct glint_fit_result res;
					if ((mi >= NEDGE && me) ||
					    (methods[me].opt ==
						     GLINT_OPT_ANNEAL &&
					     (s >= anneal_starts ||
					      noise_levels[nl] != 0.1)))
						continue;
					glint_fit_default_opts(&o);
					o.method = methods[me].m;
					o.optimizer = methods[me].opt;
					o.start = start;
					o.seed = (uint64_t)s + 1;
					double t0 = glint_clock_monotonic();
					if (glint_fit(&r, m, photo, weight, &o,
						      &res) < 0)
						return 1;
					double dt =
						glint_clock_monotonic() - t0;
					int out = WRONG;
					if (within(res.p, ref.p))
						out = CONVERGED;
					else {
						int bound = 0, stall = 0;
						for (int k = 0; k < m->nparams;
						     k++) {
							const struct glint_param *
								pi = &m->params
									      [k];
							int tb =
								truth[k] <=
									pi->lo ||
								truth[k] >=
									pi->hi;
							bound |= res.at_bound
									 [k] &&
								 !tb;
						}
						for (int q = 0; q < res.npasses;
						     q++)
							stall |=
								res.passes[q]
									.iterations >=
								o.max_iter;
						out = bound   ? BOUND
						      : stall ? STALLED
							      : WRONG;
					}
					if (mi < NEDGE)
						count[me][out]++;
					if (!me) {
						dfits[nl]++;
						dconv[nl] += out == CONVERGED;
					}
					if (mi < NEDGE) {
						secs[me] += dt;
						fits[me]++;
					}
					fprintf(csv,
						"%s,%s,%g,%d,%s,%.3f,%.3f\n",
						methods[me].name, materials[mi],
						noise_levels[nl], s,
						outcome_names[out], dt,
						fixture_tolerance_error(res.p,
									ref.p));
					fflush(csv);
				}
			}
			glint_image_free(photo);
			glint_image_free(weight);
		}
		fprintf(stderr, "bench/stability: %s done\n", materials[mi]);
		glint_image_free(clean);
		glint_renderer_release(&r);
	}
	fclose(csv);
	printf("%d materials at Table 1's edges x 3 noise levels x %d random "
	       "starts (annealing %d), 128 px photos\n",
	       NEDGE, starts, anneal_starts);
	printf("%-11s %10s %12s %9s %14s %9s\n", "method", "converged",
	       "hit a bound", "stalled", "wrong minimum", "s / fit");
	FILE *dat = fopen("bench-out/stability.dat", "w");
	for (int me = 0; me < NMETH; me++) {
		double n = fits[me];
		if (!fits[me])
			continue;
		printf("%-11s %9.1f%% %11.1f%% %8.1f%% %13.1f%% %9.2f\n",
		       methods[me].name, 100 * count[me][CONVERGED] / n,
		       100 * count[me][BOUND] / n, 100 * count[me][STALLED] / n,
		       100 * count[me][WRONG] / n, secs[me] / n);
		fprintf(dat, "%s %.1f %.1f %.1f %.1f\n", methods[me].name,
			100 * count[me][CONVERGED] / n,
			100 * count[me][BOUND] / n,
			100 * count[me][STALLED] / n,
			100 * count[me][WRONG] / n);
	}
	fclose(dat);
	printf("\ndefault method (%s) on all %d opaque Table-1 materials:\n",
	       methods[0].name, NM);
	for (int nl = 0; nl < NNOISE; nl++)
		printf("  noise level %-5g %4d / %4d converged (%.1f%%)\n",
		       noise_levels[nl], dconv[nl], dfits[nl],
		       dfits[nl] ? 100.0 * dconv[nl] / dfits[nl] : 0.0);
	printf("converged: within albedo 0.01, roughness 5 %%, ior 0.05 of "
	       "the fit from the paper's start; per-fit outcomes in "
	       "bench-out/stability.csv\n");
	FILE *gp = fopen("bench-out/stability.gp", "w");
	fprintf(gp,
		"set terminal pngcairo noenhanced size 900,480\n"
		"set output 'bench-out/stability.png'\n"
		"set style data histograms\nset style histogram rowstacked\n"
		"set style fill solid border -1\nset boxwidth 0.6\n"
		"set ylabel 'fits from random starts (%%)'\nset yrange "
		"[0:100]\n"
		"set key outside right\n"
		"set title 'glint: outcome of fits from random starts'\n"
		"plot 'bench-out/stability.dat' using 2:xtic(1) title "
		"'converged', '' using 3 title 'hit a bound', '' using 4 "
		"title 'stalled', '' using 5 title 'wrong minimum'\n");
	fclose(gp);
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/stability.gp") == 0)
		printf("chart: bench-out/stability.png\n");
	return 0;
}
