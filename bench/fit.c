/* SPDX-License-Identifier: MIT */
/*
 * Fit benchmark: time and accuracy of every method on the same input, in
 * one run.  The input: a 512x512 photo of a 10 cm sphere (180 px in
 * radius) of a Table-1 material under the 1024x512 Venice-sunset map,
 * rendered by the independent reference renderer (cached in bench-out/).
 * Fast-path methods run `rounds` times interleaved (medians reported); the
 * paper-faithful path (a full trace and render per evaluation) runs once.
 * Then the transparent spheres (Table 1's quartz, 256x256, reference photo
 * with 64 random-branching paths per pixel): annealing + LM polish (the
 * default) against LM alone, and what a change of transmission costs (a
 * re-sum of cached paths) against a change of ior (a re-trace).
 *   bench/fit [ROUNDS] [--no-faithful] [--no-dielectric] [--material NAME]
 *             [--default-only]
 * --default-only: the default row alone, with where its time went (the
 * passes, the uncertainty stage, the rest).
 */
#define _POSIX_C_SOURCE 200809L
#include "bench.h"
#include "sim/fixtures.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"
#include "fit/render/dielectric_paths.h"
#include "fit/fit.h"
#include "sim/reference.h"

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

struct variant {
	const char *name;
	enum glint_fit_method method;
	int coarse, faithful;
	int samples, pixels; /* 0: the defaults (8 + 8, 4096) */
	int no_footprint;    /* the previous path (shade_cache.h) */
};

static const struct variant variants[] = {
	{ "three-pass, coarse-to-fine (default)", GLINT_FIT_THREE_PASS, 1, 0, 0,
	  0, 0 },
	{ "default without footprint integral", GLINT_FIT_THREE_PASS, 1, 0, 0,
	  0, 1 },
	{ "three-pass, full resolution", GLINT_FIT_THREE_PASS, 0, 0, 0, 0, 0 },
	{ "naive single pass, coarse-to-fine", GLINT_FIT_NAIVE, 1, 0, 0, 0, 0 },
	{ "variable projection, coarse-to-fine", GLINT_FIT_VARPRO, 1, 0, 0, 0,
	  0 },
	{ "three-pass, 4 + 4 samples", GLINT_FIT_THREE_PASS, 1, 0, 4, 0, 0 },
	{ "three-pass, 16 + 16 samples", GLINT_FIT_THREE_PASS, 1, 0, 16, 0, 0 },
	{ "three-pass, 2048 pixels", GLINT_FIT_THREE_PASS, 1, 0, 0, 2048, 0 },
	{ "three-pass, 2048 pixels, 4 + 4 samples", GLINT_FIT_THREE_PASS, 1, 0,
	  4, 2048, 0 },
	{ "three-pass, paper-faithful (re-render)", GLINT_FIT_THREE_PASS, 0, 1,
	  0, 0, 0 },
};
#define NV ((int)(sizeof(variants) / sizeof(variants[0])))

/* Worst errors against the truth: albedo (abs), roughness (rel), ior. */
static void errors(const double *p, const double *t, double e[3])
{
	e[0] = 0;
	for (int k = 0; k < 6; k++)
		e[0] = fmax(e[0], fabs(p[k] - t[k]));
	e[1] = fabs(p[6] / t[6] - 1);
	e[2] = fabs(p[7] - t[7]);
}

/* Where one fit's time went: its passes (the sample sets' polish is part
 * of the uncertainty stage), the uncertainty, the set-up and the rest. */
static void print_breakdown(const struct glint_fit_result *res, double wall)
{
	double passes = 0;
	printf("  %-28s %7s %6s %6s %8s\n", "pass", "pixels", "iters", "evals",
	       "s");
	for (int i = 0; i < res->npasses; i++) {
		const struct glint_fit_pass *p = &res->passes[i];
		printf("  %-28s %7d %6d %6d %8.3f\n", p->name, p->pixels,
		       p->iterations, p->evaluations, p->seconds);
		if (!strstr(p->name, "sample sets"))
			passes += p->seconds;
	}
	printf("  %-28s %30.3f\n", "uncertainty (with the sets)",
	       res->unc_seconds);
	printf("  %-28s %30.3f\n", "set-up (data, first cache)",
	       res->setup_seconds);
	printf("  %-28s %30.3f\n", "the rest (scans, statistics)",
	       wall - passes - res->unc_seconds - res->setup_seconds);
	printf("  %-28s %30.3f\n", "wall", wall);
	printf("  relative RMSE %.9g, weighted cost %.9g (all pixels %.9g)\n",
	       res->rel_rmse, res->cost, res->wcost);
}

/* The quartz spheres: annealing vs LM, re-sum vs re-trace. */
static int dielectric_rows(int rounds)
{
	static const char *const mats[] = { "blue-quartz", "purple-quartz" };
	printf("\ntransparent spheres (Table 1) under venice_sunset_1k, "
	       "256x256 photo, radius 90 px\n");
	printf("%-15s %-26s %9s %7s %9s %7s\n", "material", "optimizer",
	       "median s", "evals", "transm.", "ior");
	FILE *csv = fopen("bench-out/fit-dielectric.csv", "w");
	fprintf(csv, "material,optimizer,median_s,evaluations,"
		     "transmission_err,ior_err\n");
	for (int mi = 0; mi < 2; mi++) {
		struct glint_scene sc;
		struct glint_renderer r;
		const struct glint_model *m;
		double truth[GLINT_MAX_PARAMS];
		char path[512];
		fixture_scene(&sc, 256, NULL);
		if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
					mats[mi], &m, truth) < 0 ||
		    glint_renderer_init(&r, &sc, 0, NULL) < 0)
			return -1;
		snprintf(path, sizeof(path), "bench-out/photo-%s-256.exr",
			 mats[mi]);
		struct glint_image *photo = NULL;
		if (glint_image_read(path, &photo) < 0) {
			struct glint_reference_opts ro;
			glint_reference_default_opts(&ro);
			ro.spp = 64;
			photo = glint_image_new(256, 256);
			if (glint_reference_render(&sc, r.env, m, truth, &ro,
						   photo) < 0 ||
			    glint_image_write(path, photo, NULL) < 0)
				return -1;
		}
		for (int a = 0; a < 2; a++) {
			double t[16];
			struct glint_fit_result res;
			int evals = 0;
			for (int k = 0; k < rounds; k++) {
				struct glint_fit_opts o;
				glint_fit_default_opts(&o);
				o.optimizer = a ? GLINT_OPT_LM : GLINT_OPT_AUTO;
				double t0 = glint_clock_monotonic();
				if (glint_fit(&r, m, photo, NULL, &o, &res) < 0)
					return -1;
				t[k] = glint_clock_monotonic() - t0;
			}
			for (int i = 0; i < res.npasses; i++)
				evals += res.passes[i].evaluations;
			double et = 0;
			for (int c = 0; c < 3; c++)
				et = fmax(et, fabs(res.p[c] - truth[c]));
			double med = bench_median(t, rounds);
			const char *name = a ? "LM from the paper's start"
					     : "annealing + LM polish";
			printf("%-15s %-26s %9.2f %7d %9.4f %7.4f\n", mats[mi],
			       name, med, evals, et, fabs(res.p[3] - truth[3]));
			fprintf(csv, "%s,\"%s\",%.4f,%d,%.5f,%.5f\n", mats[mi],
				name, med, evals, et,
				fabs(res.p[3] - truth[3]));
		}
		/* What each kind of change costs, on the fit's own pixels. */
		if (mi == 0) {
			int n = 0;
			int32_t *pix =
				malloc((size_t)256 * 256 * sizeof(int32_t));
			for (int i = 0; i < 256 * 256; i++)
				if (r.gb.hits[(size_t)i * r.gb.spp].geom >= 0)
					pix[n++] = i;
			struct glint_dielectric_cache c;
			double *rgb = malloc((size_t)n * 3 * sizeof(double));
			double tt[16], ts[16];
			for (int k = 0; k < rounds; k++) {
				double t0 = glint_clock_monotonic();
				glint_dielectric_trace(r.tracer, &r.gb, pix, n,
						       r.env, sc.sphere_centre,
						       sc.sphere_radius,
						       truth[3], NULL, 0, &c);
				tt[k] = glint_clock_monotonic() - t0;
				t0 = glint_clock_monotonic();
				glint_dielectric_shade(&c, truth, rgb);
				ts[k] = glint_clock_monotonic() - t0;
				if (k + 1 < rounds)
					glint_dielectric_cache_free(&c);
			}
			printf("  %d sphere pixels x %d samples: a new ior "
			       "re-traces %lld paths in %.1f ms; a new "
			       "transmission re-sums them in %.2f ms (%.0fx "
			       "cheaper)\n",
			       n, r.gb.spp, (long long)c.npaths,
			       1e3 * bench_median(tt, rounds),
			       1e3 * bench_median(ts, rounds),
			       bench_median(tt, rounds) /
				       bench_median(ts, rounds));
			glint_dielectric_cache_free(&c);
			free(rgb);
			free(pix);
		}
		glint_image_free(photo);
		glint_renderer_release(&r);
	}
	fclose(csv);
	printf("errors: largest |transmission - truth| and |ior - truth|; "
	       "medians of %d rounds\n",
	       rounds);
	return 0;
}

int main(int argc, char **argv)
{
	static const char usage[] =
		"bench/fit [ROUNDS] [--no-faithful] [--no-dielectric] "
		"[--material NAME] [--default-only]";
	bench_help(argc, argv, usage);
	int rounds = 3, faithful = 1, dielectric = 1, default_only = 0;
	const char *material = "yellow-plastic";
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	char photo_path[512];

	/* The dielectric rows read the G-buffer's hits: keep them all. */
	setenv("GLINT_GBUFFER_MB", "1e9", 1);
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--no-faithful"))
			faithful = 0;
		else if (!strcmp(argv[i], "--no-dielectric"))
			dielectric = 0;
		else if (!strcmp(argv[i], "--default-only"))
			default_only = 1;
		else if (!strcmp(argv[i], "--material") && i + 1 < argc)
			material = argv[++i];
		else if ((rounds = bench_count(argv[i], 1, 1000)) < 0)
			bench_refuse(argv[i], usage);
	}
	glint_log_set_mode(GLINT_LOG_QUIET);
	fixture_scene(&sc, 512, NULL);
	sc.light_samples = 16;
	sc.brdf_samples = 16;
	if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json", material,
				&m, truth) < 0 ||
	    glint_renderer_init(&r, &sc, 0, NULL) < 0) {
		fprintf(stderr, "bench/fit: %s\n", glint_error_msg());
		return 1;
	}
	mkdir("bench-out", 0777);
	snprintf(photo_path, sizeof(photo_path), "bench-out/photo-%s-512.exr",
		 material);
	struct glint_image *photo = NULL;
	if (glint_image_read(photo_path, &photo) < 0) {
		struct glint_reference_opts ro;
		glint_reference_default_opts(&ro);
		ro.spp = 4;
		photo = glint_image_new(512, 512);
		fprintf(stderr,
			"bench/fit: rendering the reference photo "
			"(once; cached in %s)\n",
			photo_path);
		if (glint_reference_render(&sc, r.env, m, truth, &ro, photo) <
			    0 ||
		    glint_image_write(photo_path, photo, NULL) < 0) {
			fprintf(stderr, "bench/fit: %s\n", glint_error_msg());
			return 1;
		}
	}
	double t[NV][16], e[NV][3] = { { 0 } };
	int iters[NV] = { 0 }, evals[NV] = { 0 };
	if (rounds > 16)
		rounds = 16;
	fprintf(stderr, "bench/fit: %s, %d rounds\n", material, rounds);
	for (int k = 0; k < rounds; k++)
		for (int v = 0; v < NV; v++) {
			struct glint_fit_opts o;
			struct glint_fit_result res;
			if (variants[v].faithful && (k > 0 || !faithful))
				continue;
			if (default_only && v > 0)
				continue;
			glint_fit_default_opts(&o);
			o.method = variants[v].method;
			o.coarse_to_fine = variants[v].coarse;
			o.faithful = variants[v].faithful;
			if (variants[v].samples)
				o.light_samples = o.lobe_samples =
					variants[v].samples;
			if (variants[v].pixels)
				o.max_pixels = variants[v].pixels;
			o.no_footprint = variants[v].no_footprint;
			if (o.faithful)
				o.max_iter = 30;
			double t0 = glint_clock_monotonic();
			if (glint_fit(&r, m, photo, NULL, &o, &res) < 0) {
				fprintf(stderr, "bench/fit: %s: %s\n",
					variants[v].name, glint_error_msg());
				return 1;
			}
			t[v][k] = glint_clock_monotonic() - t0;
			if (default_only)
				print_breakdown(&res, t[v][k]);
			errors(res.p, truth, e[v]);
			iters[v] = 0;
			evals[v] = 0;
			for (int i = 0; i < res.npasses; i++) {
				iters[v] += res.passes[i].iterations;
				evals[v] += res.passes[i].evaluations;
			}
		}
	FILE *csv = fopen("bench-out/fit.csv", "w");
	fprintf(csv, "variant,median_s,albedo_err,roughness_rel_err,ior_err\n");
	double med[NV];
	printf("\n%s under venice_sunset_1k (1024x512), 512x512 photo, sphere "
	       "radius 180 px\n",
	       material);
	printf("%-40s %9s %7s %8s %9s %9s %7s %6s\n", "method", "median s",
	       "vs 1st", "speedup", "albedo", "rough.", "ior", "iters");
	for (int v = 0; v < NV; v++) {
		int n = variants[v].faithful ? (faithful ? 1 : 0) : rounds;
		if (default_only && v > 0)
			n = 0;
		if (!n) {
			med[v] = NAN;
			continue;
		}
		med[v] = bench_median(t[v], n);
	}
	for (int v = 0; v < NV; v++) {
		if (isnan(med[v]))
			continue;
		char speedup[16] = "-"; /* without the faithful run */
		if (!isnan(med[NV - 1]))
			snprintf(speedup, sizeof(speedup), "%.1f",
				 med[NV - 1] / med[v]);
		printf("%-40s %9.2f %7.2f %8s %9.4f %8.1f%% %7.4f %6d\n",
		       variants[v].name, med[v], med[v] / med[0], speedup,
		       e[v][0], 100 * e[v][1], e[v][2], iters[v]);
		fprintf(csv, "\"%s\",%.4f,%.5f,%.5f,%.5f\n", variants[v].name,
			med[v], e[v][0], e[v][1], e[v][2]);
	}
	fclose(csv);
	printf("\nerrors: largest |albedo - truth|, |roughness / truth - 1|, "
	       "|ior - truth|;\nspeedup = paper-faithful time / this time; "
	       "medians of %d rounds (faithful: 1 run)\n",
	       rounds);
	if (dielectric && !default_only && dielectric_rows(rounds) < 0) {
		fprintf(stderr, "bench/fit: dielectric: %s\n",
			glint_error_msg());
		return 1;
	}
	printf("peak memory: %.1f MiB\n", bench_peak_mib());
	FILE *gp = fopen("bench-out/fit.gp", "w");
	fprintf(gp,
		"set terminal pngcairo noenhanced size 1000,520\n"
		"set output 'bench-out/fit.png'\n"
		"set datafile separator ','\nset logscale x\n"
		"set xlabel 'median fit time (s, log scale)'\n"
		"set ylabel 'roughness error (%%)'\nset yrange [0:*]\n"
		"set xrange [0.5:%s]\n"
		"set title 'glint fit: speed against accuracy (%s)'\n"
		"set rmargin at screen 0.64\n",
		isnan(med[NV - 1]) ? "*" : "2000", material);
	/* Points numbered as the table's rows, the names beside the plot
	 * (their labels on the points overlapped). */
	for (int v = 0, k = 0; v < NV; v++)
		if (!isnan(med[v])) {
			k++;
			fprintf(gp,
				"set label %d '%d  %s' at screen 0.66, "
				"screen %.3f font ',9'\n",
				k, k, variants[v].name, 0.86 - 0.045 * (k - 1));
		}
	fprintf(gp, "plot 'bench-out/fit.csv' skip 1 using 2:($4*100) with "
		    "points pt 7 ps 1.5 notitle, '' skip 1 using "
		    "2:($4*100):(sprintf('%%d', $0 + 1)) with labels offset "
		    "0.9,0.6 font ',9' notitle\n");
	fclose(gp);
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/fit.gp") == 0)
		printf("plot: bench-out/fit.png\n");
	glint_image_free(photo);
	glint_renderer_release(&r);
	return 0;
}
