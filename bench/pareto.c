/* SPDX-License-Identifier: MIT */
/*
 * Speed against accuracy: every fitting configuration on the same
 * simulated captures, charted error against time with the Pareto front.
 *
 * Captures: Table-1 materials under the Venice map, photographed at 512 px
 * by the reference renderer (cached in bench-out/), noise-free or through
 * the sensor model (one 12-bit exposure, shot + read noise, clipped pixels
 * dropped); lower resolutions are box-averaged from the 512 px photo with
 * the camera's focal length scaled to match.
 * Four captures per material: noise-free, a normal exposure (mean at 10 %
 * of the ADC range) and a dim one (1 %) through a pinhole, and a normal
 * one through a 100 mm lens at f/4 focused on the sphere's front.
 * Configurations vary one thing at a time from the default (three-pass,
 * 256 px, 8 + 8 fixed samples, full-size map, the lens modelled): the
 * method (three-pass, naive, variable projection, annealing + LM), the
 * image resolution (128 .. 512), the samples per hit (4 .. 16), the
 * env-map resolution (1024 or 256 wide), depth of field (the lens, or a
 * pinhole: the same on the pinhole captures).
 * Each fit runs in its own process (fork): wall time and that process's
 * peak memory (wait4) are its own.
 * Error: the worst parameter error in units of the fitting issue's
 * tolerances (albedo 0.01, roughness 5 % relative, ior 0.05): <= 1 meets
 * them all; and the fit's relative RMSE.
 *   bench/pareto [--quick]
 * Writes bench-out/pareto.csv, pareto.gp, pareto.png, pareto.svg.
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
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

struct config {
	const char *method; /* label, one curve per method */
	enum glint_fit_method m;
	enum glint_fit_optimizer opt;
	int px, samples, env_w;
	int dof; /* model the capture's lens (else a pinhole) */
};

static const struct config configs[] = {
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 256, 8, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 128, 8, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 512, 8, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 256, 4, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 256, 16, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 256, 8, 256, 1 },
	{ "naive", GLINT_FIT_NAIVE, GLINT_OPT_LM, 256, 8, 1024, 1 },
	{ "naive", GLINT_FIT_NAIVE, GLINT_OPT_LM, 128, 8, 1024, 1 },
	{ "varpro", GLINT_FIT_VARPRO, GLINT_OPT_LM, 256, 8, 1024, 1 },
	{ "varpro", GLINT_FIT_VARPRO, GLINT_OPT_LM, 128, 8, 1024, 1 },
	{ "varpro", GLINT_FIT_VARPRO, GLINT_OPT_LM, 512, 8, 1024, 1 },
	{ "anneal", GLINT_FIT_THREE_PASS, GLINT_OPT_ANNEAL, 256, 8, 1024, 1 },
	{ "three-pass", GLINT_FIT_THREE_PASS, GLINT_OPT_LM, 256, 8, 1024, 0 },
};
#define NC ((int)(sizeof(configs) / sizeof(configs[0])))

static const char *const materials[] = { "yellow-plastic", "copper",
					 "satin-paint" };
#define NM 3

/* The captures of each material: noise-free, one normal exposure (mean at
 * 10 % of the ADC range), a dim one (1 %), all through a pinhole; and a
 * normal exposure through the 100 mm lens at f/4 focused on the sphere's
 * front (its rim about 5 px out of focus at 256 px). */
struct capture {
	double noise; /* 0: noise-free, else the exposure level */
	double fnum;  /* 0: pinhole */
};
static const struct capture captures[] = {
	{ 0, 0 },
	{ 0.1, 0 },
	{ 0.01, 0 },
	{ 0.1, 4 },
};
#define NCAP 4

struct outcome {
	double seconds, perr, rel_rmse;
	int ok;
};

/* Fit one capture with one configuration, in this (child) process. */
static struct outcome run_one(const struct config *c, const char *mat,
			      const struct capture *cap)
{
	struct outcome out = { NAN, NAN, NAN, 0 };
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	char env[256];
	struct glint_scene sc;
	struct glint_renderer r;
	struct glint_image *weight = NULL;

	if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json", mat, &m,
				truth) < 0)
		return out;
	struct glint_image *big =
		bench_photo_512_lens(mat, m, truth, cap->fnum);
	if (!big)
		return out;
	struct glint_image *photo = fixture_shrink(big, 512 / c->px);
	glint_image_free(big);
	if (cap->noise > 0 && fixture_add_noise(photo, &weight, cap->noise) < 0)
		return out;
	if (c->env_w == 1024)
		snprintf(env, sizeof(env), "%s",
			 GLINT_DATA_DIR "/env/venice_sunset_1k.hdr");
	else
		snprintf(env, sizeof(env), "bench-out/venice-%d.exr", c->env_w);
	double t0 = glint_clock_monotonic();
	fixture_scene_lens(&sc, c->px, env, c->dof ? cap->fnum : 0);
	if (glint_renderer_init(&r, &sc, 0, NULL) < 0)
		return out;
	struct glint_fit_opts o;
	struct glint_fit_result res;
	glint_fit_default_opts(&o);
	o.method = c->m;
	o.optimizer = c->opt;
	/* annealing at 60 evaluations per parameter (glint's default is
	 * 150): 20x the LM fits' time already; the default set must run in
	 * 20 minutes */
	o.anneal_evals = 60;
	o.light_samples = o.lobe_samples = c->samples;
	if (glint_fit(&r, m, photo, weight, &o, &res) == 0) {
		out.seconds = glint_clock_monotonic() - t0;
		out.perr = fixture_tolerance_error(res.p, truth);
		out.rel_rmse = res.rel_rmse;
		out.ok = 1;
	}
	glint_renderer_release(&r);
	glint_image_free(photo);
	glint_image_free(weight);
	return out;
}

/* The map at a quarter of its width, box-averaged (once). */
static int small_env(int w)
{
	char path[256];
	struct stat st;
	snprintf(path, sizeof(path), "bench-out/venice-%d.exr", w);
	if (stat(path, &st) == 0)
		return 0;
	struct glint_image *src = NULL;
	if (glint_image_read(GLINT_DATA_DIR "/env/venice_sunset_1k.hdr", &src) <
	    0)
		return -1;
	struct glint_image *d = fixture_shrink(src, src->width / w);
	int ret = d ? glint_image_write(path, d, NULL) : -1;
	glint_image_free(src);
	glint_image_free(d);
	return ret;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/pareto [--quick]";
	bench_help(argc, argv, usage);
	int quick = argc > 1 && !strcmp(argv[1], "--quick");
	if (argc > 1 + quick)
		bench_refuse(argv[1 + quick], usage);
	int nm = quick ? 1 : NM;
	glint_log_set_mode(GLINT_LOG_QUIET);
	mkdir("bench-out", 0777);
	if (small_env(256) < 0) {
		fprintf(stderr, "bench/pareto: %s\n", glint_error_msg());
		return 1;
	}
	/* Reference photos first, in this process, so children only read. */
	for (int i = 0; i < nm; i++) {
		const struct glint_model *m;
		double t[GLINT_MAX_PARAMS];
		if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
					materials[i], &m, t) < 0)
			return 1;
		for (int k = 0; k < NCAP; k++)
			glint_image_free(bench_photo_512_lens(
				materials[i], m, t, captures[k].fnum));
	}
	FILE *csv = fopen("bench-out/pareto.csv", "w");
	fprintf(csv, "method,px,samples,env_w,dof,material,noise,f_number,"
		     "seconds,peak_mib,param_err,rel_rmse\n");
	/* Per configuration: medians over the captures. */
	double med_t[NC], med_e[NC], max_e[NC], peak[NC];
	printf("%-11s %4s %4s %5s %4s %9s %9s %10s %10s %8s   median error "
	       "per capture: clean / normal / dim / f4\n",
	       "method", "px", "spp", "env", "dof", "median s", "peak MiB",
	       "med error", "worst err", "rel RMSE");
	for (int c = 0; c < NC; c++) {
		double ts[NCAP * NM], es[NCAP * NM], rr[NCAP * NM], worst = 0,
								    pk = 0;
		double ek[NCAP][NM];
		int n = 0, nk[NCAP] = { 0 };
		for (int i = 0; i < nm; i++)
			for (int k = 0; k < NCAP; k++) {
				int fd[2];
				struct outcome o = { NAN, NAN, NAN, 0 };
				struct rusage ru;
				int st;
				if (pipe(fd) < 0)
					return 1;
				pid_t pid = fork();
				if (pid == 0) {
					close(fd[0]);
					o = run_one(&configs[c], materials[i],
						    &captures[k]);
					if (write(fd[1], &o, sizeof(o)) < 0)
						_exit(1);
					_exit(0);
				}
				close(fd[1]);
				if (read(fd[0], &o, sizeof(o)) != sizeof(o))
					o.ok = 0;
				close(fd[0]);
				wait4(pid, &st, 0, &ru);
				double mib = ru.ru_maxrss / 1024.0;
				fprintf(csv,
					"%s,%d,%d,%d,%d,%s,%g,%g,%.4f,%.1f,"
					"%.4f,%.5f\n",
					configs[c].method, configs[c].px,
					configs[c].samples, configs[c].env_w,
					configs[c].dof, materials[i],
					captures[k].noise, captures[k].fnum,
					o.seconds, mib, o.perr, o.rel_rmse);
				if (!o.ok)
					continue;
				ek[k][nk[k]++] = o.perr;
				ts[n] = o.seconds;
				es[n] = o.perr;
				rr[n] = o.rel_rmse;
				worst = fmax(worst, o.perr);
				pk = fmax(pk, mib);
				n++;
			}
		med_t[c] = n ? bench_median(ts, n) : NAN;
		med_e[c] = n ? bench_median(es, n) : NAN;
		max_e[c] = n ? worst : NAN;
		peak[c] = pk;
		printf("%-11s %4d %4d %5d %4s %9.2f %9.1f %10.2f %10.2f %8.4f "
		       " ",
		       configs[c].method, configs[c].px, configs[c].samples,
		       configs[c].env_w, configs[c].dof ? "on" : "off",
		       med_t[c], peak[c], med_e[c], max_e[c],
		       n ? bench_median(rr, n) : NAN);
		for (int k = 0; k < NCAP; k++)
			printf(" %6.2f",
			       nk[k] ? bench_median(ek[k], nk[k]) : NAN);
		printf("\n");
		fflush(stdout);
	}
	fclose(csv);
	/* The Pareto front of (median time, median error). */
	FILE *fr = fopen("bench-out/pareto-front.csv", "w");
	fprintf(fr, "seconds,param_err,label\n");
	printf("\nPareto front (no other configuration is both faster and "
	       "more accurate):\n");
	int order[NC];
	for (int c = 0; c < NC; c++)
		order[c] = c;
	for (int a = 0; a < NC; a++)
		for (int b = a + 1; b < NC; b++)
			if (med_t[order[b]] < med_t[order[a]]) {
				int t = order[a];
				order[a] = order[b];
				order[b] = t;
			}
	double best = INFINITY;
	for (int k = 0; k < NC; k++) {
		int c = order[k];
		if (!(med_e[c] < best))
			continue;
		best = med_e[c];
		printf("  %-11s %3d px, %2d samples, map %4d, DoF %s: %.2f s, "
		       "error %.2f\n",
		       configs[c].method, configs[c].px, configs[c].samples,
		       configs[c].env_w, configs[c].dof ? "on" : "off",
		       med_t[c], med_e[c]);
		fprintf(fr, "%.4f,%.4f,\"%s %dpx s%d e%d\"\n", med_t[c],
			med_e[c], configs[c].method, configs[c].px,
			configs[c].samples, configs[c].env_w);
	}
	fclose(fr);
	printf("error: worst parameter error in units of the tolerances "
	       "(albedo 0.01, roughness 5 %%, ior 0.05), median over %d "
	       "captures (%d materials x noise-free, normal and dim exposures "
	       "through a pinhole, a normal one through f/4)\n",
	       NCAP * nm, nm);
	FILE *gp = fopen("bench-out/pareto.gp", "w");
	fprintf(gp,
		"set datafile separator ','\n"
		"set logscale x\nset yrange [0:*]\nset grid\n"
		"set key outside right\n"
		"set xlabel 'median fit time (s)'\n"
		"set ylabel 'median worst parameter error (tolerance units)'\n"
		"set title 'glint: speed against accuracy (Pareto front "
		"marked)'\n"
		"set arrow from graph 0, first 1 to graph 1, first 1 nohead "
		"dt 2\n"
		"plot_it = \"plot ");
	const char *methods[] = { "three-pass", "naive", "varpro", "anneal" };
	const char *colours[] = { "#1f77b4", "#2ca02c", "#d62728", "#9467bd" };
	/* Points, not lines: a method's configurations differ in more than
	 * one setting, and a line between them would read as a trend. Each
	 * point is labelled with what differs from the default. */
	for (int k = 0; k < 4; k++)
		fprintf(gp,
			"'bench-out/pareto-%s.csv' using 1:2 with "
			"points pt 7 ps 1.3 lc rgb '%s' title '%s', "
			"'bench-out/pareto-%s.csv' using 1:2:3 with labels "
			"offset char 0.6,0.7 left font ',8' notitle, ",
			methods[k], colours[k], methods[k], methods[k]);
	fprintf(gp, "'bench-out/pareto-front.csv' skip 1 using 1:2 with "
		    "points pt 6 ps 3 lw 2 lc rgb 'black' title "
		    "'Pareto front'\"\n"
		    "set terminal pngcairo noenhanced size 1000,560\n"
		    "set output 'bench-out/pareto.png'\neval plot_it\n"
		    "set terminal svg noenhanced size 1000,560\n"
		    "set output 'bench-out/pareto.svg'\neval plot_it\n");
	fclose(gp);
	for (int k = 0; k < 4; k++) {
		char p[128];
		snprintf(p, sizeof(p), "bench-out/pareto-%s.csv", methods[k]);
		FILE *f = fopen(p, "w");
		/* one curve per method, sorted by time */
		for (int j = 0; j < NC; j++) {
			int c = order[j];
			if (strcmp(configs[c].method, methods[k]))
				continue;
			fprintf(f, "%.4f,%.4f,\"%d px", med_t[c], med_e[c],
				configs[c].px);
			if (configs[c].samples != 8)
				fprintf(f, " %d smp", configs[c].samples);
			if (configs[c].env_w != 1024)
				fprintf(f, " map %d", configs[c].env_w);
			if (!configs[c].dof)
				fprintf(f, " no DoF");
			fprintf(f, "\"\n");
		}
		fclose(f);
	}
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/pareto.gp") == 0)
		printf("chart: bench-out/pareto.png, bench-out/pareto.svg\n");
	return 0;
}
