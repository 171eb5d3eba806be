/* SPDX-License-Identifier: MIT */
/*
 * The whole rig at a real sensor's size: `glint rig --once` on the
 * simulated rig (sim camera and board) with the camera at each given size,
 * run as its own process so that its peak resident memory is its own
 * (wait4's ru_maxrss), with the time of each stage from its JSON log and
 * the bytes it left on disk.
 *
 * Stages: set-up (start to "ready": the simulated camera renders its two
 * views, which a real camera does not), the probe (bracket, merge, ball
 * detection, unwrap), the sample (bracket, merge, sphere detection,
 * scene.json), the fit job (trace, fit, final render, outputs).  Each is
 * also given per megapixel, to show which grows faster than the pixels.
 *
 * usage: bench/rig_size [WxH[/K] ...]
 *   default 1014x760 2028x1520/2 4056x3040/4: K is the sim camera's
 *   scene_scale (views rendered at 1/K and interpolated: the reference
 *   render of a 12 MP view alone would take most of an hour).  Prints a
 *   table; writes bench-out/rig_size.csv and bench-out/rig_size.png
 *   (gnuplot, where installed).  Runs take minutes each at 12 MP.
 */
#define _GNU_SOURCE
#include "bench.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <jansson.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

struct row {
	int w, h, k, status;
	double mpx, wall, peak_mib, views_mib, fit_peak_mib;
	double setup, probe, sample, fit_job, fit_s, render_s;
	double disk_mb;
	int frames;
};

static double wall_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_REALTIME, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* "2026-11-25T06:31:50.366Z" to seconds since the epoch. */
static double iso_time(const char *s)
{
	struct tm tm;
	memset(&tm, 0, sizeof(tm));
	const char *rest = strptime(s, "%Y-%m-%dT%H:%M:%S", &tm);
	if (!rest)
		return NAN;
	return (double)timegm(&tm) + (*rest == '.' ? atof(rest) : 0);
}

static long long disk_bytes;
static int add_size(const char *path, const struct stat *st, int type,
		    struct FTW *f)
{
	(void)path, (void)f;
	if (type == FTW_F)
		disk_bytes += st->st_size;
	return 0;
}

static int remove_one(const char *path, const struct stat *st, int type,
		      struct FTW *f)
{
	(void)st, (void)type, (void)f;
	return remove(path);
}

static int write_config(const char *path, const char *out, const struct row *r)
{
	json_error_t e;
	json_t *rig = json_load_file(GLINT_DATA_DIR "/rig-sim.json", 0, &e);
	if (!rig) {
		fprintf(stderr, "rig_size: %s: %s\n", e.source, e.text);
		return -1;
	}
	char dev[160];
	snprintf(dev, sizeof(dev),
		 "sim:width=%d,height=%d,scene=rig,timescale=0.1,"
		 "scene_scale=%d",
		 r->w, r->h, r->k);
	json_object_set_new(rig, "output", json_string(out));
	json_object_set_new(json_object_get(rig, "camera"), "device",
			    json_string(dev));
	json_object_set_new(json_object_get(rig, "optics"), "focal_px",
			    json_integer(2 * r->w));
	json_object_set_new(json_object_get(rig, "board"), "scenario",
			    json_string(GLINT_DATA_DIR "/sim-press.json"));
	/* The simulator spends about 8 s on each 12 MP frame (shot and read
	 * noise drawn per site on one thread, the DNG written), which a real
	 * sensor delivers in 0.1 s: the bracket's 60 s cap would stop it short.
	 */
	json_t *br = json_object_get(rig, "bracket");
	if (!br)
		json_object_set_new(rig, "bracket", br = json_object());
	json_object_set_new(br, "max_time_s", json_real(900));
	int ret = json_dump_file(rig, path, JSON_INDENT(1));
	json_decref(rig);
	return ret;
}

/* Stage times from the run's JSON log lines. */
static void read_log(const char *path, double t_start, struct row *r)
{
	FILE *f = fopen(path, "r");
	char line[4096];
	double t_ready = NAN, t[8], t_fit0 = NAN, t_fit1 = NAN;
	for (int i = 0; i < 8; i++)
		t[i] = NAN;
	while (f && fgets(line, sizeof(line), f)) {
		json_t *j = json_loads(line, 0, NULL);
		const char *msg = json_string_value(json_object_get(j, "msg"));
		const char *ts = json_string_value(json_object_get(j, "time"));
		int step, n;
		if (msg && ts) {
			double tt = iso_time(ts) - t_start;
			if (!strncmp(msg, "ready:", 6) && isnan(t_ready))
				t_ready = tt;
			else if (sscanf(msg, "step %d/7", &step) == 1 &&
				 step >= 1 && step <= 7)
				t[step] = tt;
			else if (strstr(msg, ": fitting "))
				t_fit0 = tt;
			else if (strstr(msg, ": done") && strstr(msg, "job ")) {
				const char *pk = strstr(msg, "peak memory ");
				t_fit1 = tt;
				if (pk)
					r->fit_peak_mib = atof(pk + 12);
			} else if (sscanf(msg, "%d frames, ", &n) == 1)
				r->frames += n;
		}
		json_decref(j);
	}
	if (f)
		fclose(f);
	r->setup = t_ready;
	r->probe = t[4] - t[3];
	r->sample = t[6] - t[5];
	r->fit_job = t_fit1 - t_fit0;
}

static void read_result(const char *path, struct row *r)
{
	json_t *d = json_load_file(path, 0, NULL);
	json_t *fit = json_object_get(d, "fit");
	r->fit_s = json_number_value(json_object_get(fit, "seconds"));
	r->render_s = json_number_value(
		json_object_get(json_object_get(fit, "render"), "seconds"));
	json_decref(d);
}

static int run(const char *glint, struct row *r)
{
	char dir[] = "/tmp/glint-rig-size-XXXXXX";
	char cfg[PATH_MAX], out[PATH_MAX], log[PATH_MAX], res[PATH_MAX];
	if (!mkdtemp(dir)) {
		perror("rig_size: mkdtemp");
		return -1;
	}
	snprintf(cfg, sizeof(cfg), "%s/rig.json", dir);
	snprintf(out, sizeof(out), "%s/out", dir);
	snprintf(log, sizeof(log), "%s/log.jsonl", dir);
	snprintf(res, sizeof(res), "%s/result.json", dir);
	if (mkdir(out, 0755) < 0 || write_config(cfg, out, r) < 0) {
		fprintf(stderr, "rig_size: cannot set up %s\n", dir);
		return -1;
	}
	double t0 = wall_now();
	pid_t pid = fork();
	if (pid == 0) {
		int o = open(res, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		int e = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		if (o < 0 || e < 0 || dup2(o, 1) < 0 || dup2(e, 2) < 0)
			_exit(126);
		execl(glint, "glint", "rig", "--config", cfg, "--once",
		      "--json", (char *)NULL);
		_exit(127);
	}
	int st = 0;
	struct rusage ru;
	if (pid < 0 || wait4(pid, &st, 0, &ru) < 0) {
		perror("rig_size: running glint");
		return -1;
	}
	r->wall = wall_now() - t0;
	r->status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
	r->peak_mib = ru.ru_maxrss / 1024.0;
	read_log(log, t0, r);
	read_result(res, r);
	disk_bytes = 0;
	nftw(out, add_size, 16, FTW_PHYS);
	r->disk_mb = disk_bytes / 1e6;
	if (r->status) {
		/* Kept, with the jobs' own record of what failed. */
		fprintf(stderr,
			"rig_size: %dx%d: glint exit %d; kept %s (its log "
			"log.jsonl; glint jobs --root %s)\n",
			r->w, r->h, r->status, dir, out);
		return 0;
	}
	nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS);
	return 0;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/rig_size [WxH[/K] ...]";
	bench_help(argc, argv, usage);
	const char *def[] = { "1014x760", "2028x1520/2", "4056x3040/4" };
	int n = argc > 1 ? argc - 1 : 3;
	struct row rows[16];
	int failed = 0;
	char self[PATH_MAX], glint[PATH_MAX + 16];

	if (n > 16)
		n = 16;
	ssize_t len = readlink("/proc/self/exe", self, sizeof(self) - 1);
	if (len < 0) {
		perror("rig_size: /proc/self/exe");
		return 1;
	}
	self[len] = 0;
	snprintf(glint, sizeof(glint), "%s/../cmd/glint", dirname(self));
	if (access(glint, X_OK) < 0) {
		fprintf(stderr, "rig_size: no glint at %s (build it first)\n",
			glint);
		return 1;
	}
	for (int i = 1; i < argc; i++) {
		int w, h, k = 1;
		if (sscanf(argv[i], "%dx%d/%d", &w, &h, &k) < 2 || w < 64 ||
		    h < 48 || w > 8192 || h > 8192 || k < 1 || k > 64) {
			fprintf(stderr,
				"%s: expected WxH or WxH/K "
				"(64x48 .. 8192x8192, K 1..64)\n",
				argv[i]);
			bench_refuse(argv[i], usage);
		}
	}
	printf("glint rig --once on the simulated rig, one process per size "
	       "(peak RSS from wait4; of it the fit process's, from the "
	       "job's log)\n\n");
	printf("%-14s %6s %8s %7s %9s %7s %7s %7s %8s %6s %8s %8s %7s %6s\n",
	       "size", "MP", "peak MiB", "fit MiB", "views MiB", "set-up",
	       "probe", "sample", "fit job", "fit", "render", "disk MB",
	       "frames", "exit");
	for (int i = 0; i < n; i++) {
		struct row *r = &rows[i];
		memset(r, 0, sizeof(*r));
		r->k = 1;
		const char *a = argc > 1 ? argv[i + 1] : def[i];
		/* checked above: the arguments before any run */
		sscanf(a, "%dx%d/%d", &r->w, &r->h, &r->k);
		r->mpx = r->w * (double)r->h / 1e6;
		/* The sim camera's two views, float RGB: not the pipeline's. */
		r->views_mib = 2.0 * r->w * r->h * 12 / (1 << 20);
		if (run(glint, r) < 0)
			return 1;
		failed |= r->status != 0;
		printf("%-14s %6.2f %8.0f %7.0f %9.0f %7.1f %7.1f %7.1f %8.1f "
		       "%6.1f %8.1f %8.1f %7d %6d\n",
		       a, r->mpx, r->peak_mib, r->fit_peak_mib, r->views_mib,
		       r->setup, r->probe, r->sample, r->fit_job, r->fit_s,
		       r->render_s, r->disk_mb, r->frames, r->status);
		fflush(stdout);
	}
	printf("\nper megapixel (s/MP; a stage linear in the pixels keeps "
	       "its figure):\n");
	printf("%-14s %7s %7s %8s %8s\n", "size", "probe", "sample", "fit job",
	       "MiB/MP");
	for (int i = 0; i < n; i++) {
		const struct row *r = &rows[i];
		printf("%-14s %7.2f %7.2f %8.2f %8.0f\n",
		       argc > 1 ? argv[i + 1] : def[i], r->probe / r->mpx,
		       r->sample / r->mpx, r->fit_job / r->mpx,
		       (r->peak_mib - r->views_mib) / r->mpx);
	}

	mkdir("bench-out", 0755);
	FILE *csv = fopen("bench-out/rig_size.csv", "w");
	if (!csv) {
		perror("rig_size: bench-out/rig_size.csv");
		return 1;
	}
	fprintf(csv,
		"mpx,peak_mib,fit_peak_mib,views_mib,setup_s,probe_s,sample_s,"
		"fit_job_s,fit_s,render_s,disk_mb,frames,exit\n");
	for (int i = 0; i < n; i++) {
		const struct row *r = &rows[i];
		fprintf(csv,
			"%.3f,%.1f,%.1f,%.1f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,"
			"%.1f,%d,%d\n",
			r->mpx, r->peak_mib, r->fit_peak_mib, r->views_mib,
			r->setup, r->probe, r->sample, r->fit_job, r->fit_s,
			r->render_s, r->disk_mb, r->frames, r->status);
	}
	fclose(csv);
	FILE *gp = fopen("bench-out/rig_size.gp", "w");
	if (gp) {
		fprintf(gp,
			"set terminal png size 900,420\n"
			"set output 'bench-out/rig_size.png'\n"
			"set datafile separator ','\n"
			"set multiplot layout 1,2\n"
			"set xlabel 'megapixels'\nset ylabel 'seconds'\n"
			"set key top left\n"
			"plot 'bench-out/rig_size.csv' skip 1 using 1:6 w lp "
			"t 'probe', '' skip 1 using 1:7 w lp t 'sample', "
			"'' skip 1 using 1:8 w lp t 'fit job'\n"
			"set ylabel 'MiB'\n"
			"plot 'bench-out/rig_size.csv' skip 1 using 1:2 w lp "
			"t 'peak RSS', '' skip 1 using 1:($2-$4) w lp "
			"t 'without the sim views', '' skip 1 using 1:3 w lp "
			"t 'the fit process', 1024 t '1 GiB'\n"
			"unset multiplot\n");
		fclose(gp);
		if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
		    system("gnuplot bench-out/rig_size.gp") == 0)
			printf("plot: bench-out/rig_size.png\n");
	}
	return failed;
}
