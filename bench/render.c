/* SPDX-License-Identifier: MIT */
/*
 * Render benchmark.  On the demo scene (512x512, one sphere, 4 samples per
 * pixel = 1 Mi primary rays) it measures, interleaved round by round so
 * that machine noise hits every variant alike:
 *   - Embree's raw throughput on the same rays: rtcIntersect16 and
 *     rtcIntersect1, user-geometry sphere and RTC_GEOMETRY_TYPE_SPHERE_POINT;
 *   - glint's primary pass (ray generation, packets, exact hit re-solve,
 *     G-buffer), one thread and all threads;
 *   - shading (MIS, 32 + 32 samples per hit);
 *   - the simulator's reference renderer on the same scene (its own
 *     rays, 4 a pixel, 32 + 32 samples a lobe and hit: the ground truth
 *     tests and benchmarks fit, and most of their time).
 * Prints medians and ratios, writes bench-out/render.csv and, with gnuplot,
 * bench-out/render.png.
 *   bench/render [ROUNDS]
 */
#define _POSIX_C_SOURCE 200809L
#include "bench.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "fit/render/render.h"
#include "sim/reference.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

enum {
	RAW16_USER,
	RAW1_USER,
	RAW16_POINT,
	RAW1_POINT,
	PRIMARY_1T,
	PRIMARY_MT,
	SHADE_MT,
	REFERENCE_MT,
	NVARIANTS
};

static const char *names[NVARIANTS] = {
	"embree rtcIntersect16, user sphere",
	"embree rtcIntersect1,  user sphere",
	"embree rtcIntersect16, SPHERE_POINT",
	"embree rtcIntersect1,  SPHERE_POINT",
	"glint primary pass, 1 thread",
	"glint primary pass, all threads",
	"glint shading (32+32 MIS), all threads",
	"sim/ reference render (32+32), all threads",
};

static struct glint_tracer *make_tracer(const struct glint_scene *s,
					enum glint_sphere_kind kind)
{
	struct glint_tracer *t;
	if (glint_tracer_new(&t) < 0 ||
	    glint_tracer_add_sphere(t, s->sphere_centre, s->sphere_radius,
				    kind) < 0 ||
	    glint_tracer_commit(t) < 0) {
		fprintf(stderr, "bench: %s\n", glint_error_msg());
		exit(1);
	}
	return t;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/render [ROUNDS]";
	bench_help(argc, argv, usage);
	int rounds = argc > 1 ? bench_count(argv[1], 1, 100) : 7;
	if (rounds < 0 || argc > 2)
		bench_refuse(argv[rounds < 0 ? 1 : 2], usage);
	struct glint_scene sc;
	struct glint_renderer r;
	double p[GLINT_MAX_PARAMS];
	const struct glint_model *model;

	if (rounds < 1)
		rounds = 1;
	glint_log_set_mode(GLINT_LOG_QUIET);
	/* It reads the G-buffer's hits: keep them all (dense). */
	setenv("GLINT_GBUFFER_MB", "1e9", 1);
	if (glint_scene_load(GLINT_DATA_DIR "/demo-scene.json", &sc) < 0 ||
	    glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
				"yellow-plastic", &model, p) < 0 ||
	    glint_renderer_init(&r, &sc, 0, NULL) < 0) {
		fprintf(stderr, "bench: %s\n", glint_error_msg());
		return 1;
	}
	/* The G-buffer's rays, as origin/direction sextuples. */
	size_t n = (size_t)sc.cam.width * sc.cam.height * sc.spp, hits = 0;
	float *rays = malloc(n * 6 * sizeof(float));
	int32_t *geom = malloc(n * sizeof(int32_t));
	for (size_t i = 0; i < n; i++) {
		for (int c = 0; c < 3; c++) {
			rays[6 * i + c] = (float)(c == 0   ? sc.cam.pos.x
						  : c == 1 ? sc.cam.pos.y
							   : sc.cam.pos.z);
			rays[6 * i + 3 + c] = r.gb.hits[i].d[c];
		}
		hits += r.gb.hits[i].geom >= 0;
	}
	struct glint_tracer *user = make_tracer(&sc, GLINT_SPHERE_USER);
	struct glint_tracer *point = make_tracer(&sc, GLINT_SPHERE_POINT);
	struct glint_image *img = glint_image_new(sc.cam.width, sc.cam.height);
	struct glint_reference_opts ro;
	glint_reference_default_opts(&ro);
	ro.spp = sc.spp;
	ro.samples = 32;
	double *t[NVARIANTS];
	for (int v = 0; v < NVARIANTS; v++)
		t[v] = calloc((size_t)rounds, sizeof(double));

	fprintf(stderr, "bench/render: %d rounds of %zu rays (%d threads)\n",
		rounds, n, glint_cpu_count());
	for (int k = 0; k < rounds; k++) {
		for (int v = 0; v < NVARIANTS; v++) {
			struct glint_gbuffer gb;
			struct glint_shade_opts so = { .light_samples = 32,
						       .brdf_samples = 32,
						       .background = 1 };
			double t0 = glint_clock_monotonic();
			switch (v) {
			case RAW16_USER:
			case RAW1_USER:
				glint_tracer_intersect_raw(user, rays, (int)n,
							   geom,
							   v == RAW16_USER);
				break;
			case RAW16_POINT:
			case RAW1_POINT:
				glint_tracer_intersect_raw(point, rays, (int)n,
							   geom,
							   v == RAW16_POINT);
				break;
			case PRIMARY_1T:
			case PRIMARY_MT:
				glint_tracer_primary(user, &sc.cam, sc.spp,
						     v == PRIMARY_1T ? 1 : 0,
						     NULL, &gb);
				glint_gbuffer_free(&gb);
				break;
			case SHADE_MT:
				glint_render_shade(&r.gb, r.tracer, r.env,
						   model, p, &so, img, NULL);
				break;
			case REFERENCE_MT:
				if (glint_reference_render(&sc, r.env, model, p,
							   &ro, img) < 0) {
					fprintf(stderr, "bench: %s\n",
						glint_error_msg());
					return 1;
				}
				break;
			}
			t[v][k] = glint_clock_monotonic() - t0;
		}
	}

	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/render.csv", "w");
	double med[NVARIANTS];
	fprintf(csv, "variant,median_s,mrays_per_s\n");
	printf("\n%-42s %10s %12s %8s\n", "variant", "median ms", "Mrays/s",
	       "ratio");
	for (int v = 0; v < NVARIANTS; v++)
		med[v] = bench_median(t[v], rounds);
	for (int v = 0; v < NVARIANTS; v++) {
		/* Shading counts shaded samples (hits x 64 a lobe), not
		 * rays; the reference renderer samples both of the
		 * material's lobes. */
		double units = v == SHADE_MT	   ? (double)hits * 64
			       : v == REFERENCE_MT ? (double)hits * 128
						   : (double)n;
		double rate = units / med[v] / 1e6;
		fprintf(csv, "\"%s\",%.6f,%.3f\n", names[v], med[v], rate);
		if (v >= SHADE_MT)
			printf("%-42s %10.1f %12.2f %8s  (M shaded "
			       "samples/s)\n",
			       names[v], 1e3 * med[v], rate, "");
		else
			printf("%-42s %10.1f %12.2f %8.2f\n", names[v],
			       1e3 * med[v], rate, med[RAW16_USER] / med[v]);
	}
	fclose(csv);
	printf("\nratio = throughput / raw rtcIntersect16 on the user sphere "
	       "(same rays)\n");
	printf("glint primary pass (1 thread) vs raw Embree: %.2f; "
	       "SPHERE_POINT vs user geometry (packets): %.2f\n",
	       med[RAW16_USER] / med[PRIMARY_1T],
	       med[RAW16_USER] / med[RAW16_POINT]);
	printf("peak memory: %.1f MiB\n", bench_peak_mib());

	FILE *gp = fopen("bench-out/render.gp", "w");
	fprintf(gp,
		"set terminal pngcairo noenhanced size 1000,520\n"
		"set output 'bench-out/render.png'\n"
		"set datafile separator ','\nset style fill solid\n"
		"set boxwidth 0.6\nset ylabel 'Mrays/s (median of %d)'\n"
		"set yrange [0:*]\nset bmargin 9\nset lmargin 18\n"
		"set xtics rotate by 25 right font ',9'\n"
		"set title 'glint render benchmark (%zu rays)'\n"
		"plot 'bench-out/render.csv' every ::1::6 using 0:3:"
		"xtic(1) with boxes notitle\n",
		rounds, n);
	fclose(gp);
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/render.gp") == 0)
		printf("plot: bench-out/render.png\n");
	else
		printf("plot: install gnuplot to draw bench-out/render.png\n");

	for (int v = 0; v < NVARIANTS; v++)
		free(t[v]);
	free(rays);
	free(geom);
	glint_image_free(img);
	glint_tracer_free(user);
	glint_tracer_free(point);
	glint_renderer_release(&r);
	return 0;
}
