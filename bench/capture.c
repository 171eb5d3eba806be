/* SPDX-License-Identifier: MIT */
/*
 * Capture benchmark: the wall time of an exposure bracket against its
 * physical floor, on the simulated camera with real timing (real clock,
 * frame period max(exposure, 1/30 s), exposure landing 2 frames late).
 *
 * floor = sum over the bracket's frames of max(exposure, fastest frame
 * period): what a camera needs to deliver exactly those frames back to
 * back.  Modes, interleaved in each round of one run:
 *   metered by its frames  glint capture as shipped: the bracket starts at
 *                          10 ms and its own frames are the meter
 *   metered apart          the previous way: metering frames first, each
 *                          waiting out the latency, then the bracket
 *   from a known start     the bracket from the exposure metering apart
 *                          found (what a rig that remembers it would do)
 *   sequential             one glint_camera_capture() per exposure of the
 *                          metered-apart bracket, ascending (its cheapest
 *                          order): every change waits out the latency
 *
 * usage: bench/capture [RUNS] [--device DEV]   (default 3 runs,
 *        sim:width=128,height=96); prints a table, writes
 *        bench-out/capture.csv and bench-out/capture.png (gnuplot).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd/backends.h"
#include "bench.h"

#include "capture/camera/bracket.h"
#include "core/error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAXRUNS 15
enum { M_SHIPPED, M_APART, M_KNOWN, M_SEQUENTIAL, NM };
static const char *const mode_name[NM] = { "metered by its frames",
					   "metered apart first",
					   "from a known start", "sequential" };

static double floor_of(const struct glint_bracket *b, double period)
{
	double s = 0;
	for (int i = 0; i < b->n; i++)
		s += fmax(b->frames[i].exposure_s, period);
	return s;
}

static int run_bracket(const char *dev, double start_s, int apart, double *wall,
		       double *flr, int *n, double *e0,
		       struct glint_bracket *keep)
{
	struct glint_camera *cam;
	struct glint_camera_info in;
	struct glint_bracket b;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	int ret = glint_camera_open("sim", dev, NULL, &cam);
	if (ret < 0)
		return ret;
	glint_camera_describe(cam, &in);
	glint_bracket_default_opts(&o);
	o.start_s = start_s;
	o.meter_apart = apart;
	double t0 = glint_clock_real.now(NULL);
	ret = glint_bracket_capture(cam, &all, &o, &glint_clock_real, &b);
	*wall = glint_clock_real.now(NULL) - t0;
	glint_camera_close(cam);
	if (ret < 0)
		return ret;
	*flr = floor_of(&b, in.frame_period_min_s);
	*n = b.n;
	if (e0)
		*e0 = b.metered_start_s;
	if (!b.covered_low || !b.covered_high)
		fprintf(stderr, "warning: bracket did not cover the range\n");
	if (keep)
		*keep = b;
	else
		glint_bracket_release(&b);
	return 0;
}

static int run_sequential(const char *dev, const struct glint_bracket *plan,
			  double *wall, double *flr)
{
	struct glint_camera *cam;
	struct glint_camera_info in;
	int ret = glint_camera_open("sim", dev, NULL, &cam);
	if (ret < 0)
		return ret;
	glint_camera_describe(cam, &in);
	double t0 = glint_clock_real.now(NULL);
	for (int i = 0; i < plan->n && ret == 0; i++) {
		struct glint_frame f;
		ret = glint_camera_capture(cam, plan->frames[i].exposure_s,
					   plan->frames[i].gain, 8, &f, NULL);
		if (ret == 0)
			glint_frame_release(&f);
	}
	*wall = glint_clock_real.now(NULL) - t0;
	*flr = floor_of(plan, in.frame_period_min_s);
	glint_camera_close(cam);
	return ret;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/capture [RUNS] [--device DEV]";
	bench_help(argc, argv, usage);
	glint_backends_register();
	const char *dev = "sim:width=128,height=96";
	int runs = 3;
	double wall[NM][MAXRUNS], flr[NM][MAXRUNS], ratio[NM][MAXRUNS];
	int frames[NM] = { 0 };

	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--device") && i + 1 < argc)
			dev = argv[++i];
		else if (bench_count(argv[i], 1, 1000) > 0)
			runs = fmin(bench_count(argv[i], 1, 1000), MAXRUNS);
		else
			bench_refuse(argv[i], usage);
	}
	printf("capture benchmark: %s, real clock, %d runs per mode\n", dev,
	       runs);
	for (int r = 0; r < runs; r++) {
		struct glint_bracket plan;
		double e0;
		int n;
		if (run_bracket(dev, 0, 1, &wall[M_APART][r], &flr[M_APART][r],
				&frames[M_APART], &e0, &plan) < 0 ||
		    run_bracket(dev, 0, 0, &wall[M_SHIPPED][r],
				&flr[M_SHIPPED][r], &frames[M_SHIPPED], NULL,
				NULL) < 0 ||
		    run_bracket(dev, e0, 0, &wall[M_KNOWN][r], &flr[M_KNOWN][r],
				&frames[M_KNOWN], NULL, NULL) < 0 ||
		    run_sequential(dev, &plan, &wall[M_SEQUENTIAL][r],
				   &flr[M_SEQUENTIAL][r]) < 0) {
			fprintf(stderr, "bench/capture: %s\n",
				glint_error_msg());
			return 1;
		}
		n = plan.n;
		frames[M_SEQUENTIAL] = n;
		glint_bracket_release(&plan);
		for (int m = 0; m < NM; m++)
			ratio[m][r] = wall[m][r] / flr[m][r];
		printf("run %d: metered start %.4g s:", r + 1, e0);
		for (int m = 0; m < NM; m++)
			printf("  %s %.2f s / floor %.2f s", mode_name[m],
			       wall[m][r], flr[m][r]);
		printf("\n");
	}
	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/capture.csv", "w");
	if (!csv) {
		perror("bench-out/capture.csv");
		return 1;
	}
	fprintf(csv, "mode,median_wall_s,median_floor_s,median_ratio\n");
	printf("\n%-24s %7s %12s %12s %14s %12s\n", "mode", "frames",
	       "median wall", "median floor", "wall / floor", "vs shipped");
	double med_ratio[NM], med_wall[NM];
	for (int m = 0; m < NM; m++) {
		med_wall[m] = bench_median(wall[m], runs);
		double mf = bench_median(flr[m], runs);
		med_ratio[m] = bench_median(ratio[m], runs);
		fprintf(csv, "\"%s\",%.4f,%.4f,%.4f\n", mode_name[m],
			med_wall[m], mf, med_ratio[m]);
	}
	for (int m = 0; m < NM; m++)
		printf("%-24s %7d %10.2f s %10.2f s %14.3f %12.2f\n",
		       mode_name[m], frames[m], med_wall[m],
		       bench_median(flr[m], runs), med_ratio[m],
		       med_wall[m] / med_wall[M_SHIPPED]);
	fclose(csv);
	printf("\nfloor = sum of max(exposure, 1/30 s) over the bracket's "
	       "frames; medians of %d runs\npeak memory: %.1f MiB\n",
	       runs, bench_peak_mib());
	FILE *gp = fopen("bench-out/capture.gp", "w");
	if (gp) {
		fprintf(gp,
			"set terminal pngcairo noenhanced size 1000,420\n"
			"set output 'bench-out/capture.png'\n"
			"set datafile separator ','\nset style fill solid 0.6\n"
			"set boxwidth 0.6\nset yrange [0:*]\n"
			"set ylabel 'wall time / physical floor'\n"
			"set title 'glint capture: bracket time against the "
			"physical floor (%s)'\n"
			"plot 'bench-out/capture.csv' skip 1 using 0:4:xtic(1) "
			"with boxes notitle, 1.05 with lines dt 2 title "
			"'target 1.05'\n",
			dev);
		fclose(gp);
		if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
		    system("gnuplot bench-out/capture.gp") == 0)
			printf("plot: bench-out/capture.png\n");
	}
	return 0;
}
