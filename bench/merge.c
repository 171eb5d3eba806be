/* SPDX-License-Identifier: MIT */
/*
 * Raw HDR merge benchmark: how long after a bracket's last frame its
 * merged image is ready, the streaming merge (each frame folded in as it
 * arrives, as glint capture and the rig run it) against the batch merge
 * (every frame kept, merged after the last).
 *
 * Per size, a bracket of the simulated camera's test card is captured once
 * (fake clock: the simulator draws a 12 MP frame's noise in seconds, far
 * slower than a sensor) and replayed on the real clock as a camera would
 * deliver it: frame i arrives at the sum of max(exposure, 1/30 s) of the
 * frames up to it.  Both modes run in turn in each round; medians.
 * "ready" is the merged, demosaiced radiance and variance in memory;
 * "on disk" adds writing the five files.  Held: the bytes each merge keeps
 * between frames (the stream: its sums, mask and one frame; the batch:
 * every frame).  Accuracy: each merge's z-scores against the card's known
 * radiance (mean ~0, spread ~1 is honest), and the stream's difference
 * from the batch in the batch's sigmas.
 *
 * usage: bench/merge [ROUNDS] [WxH...]   (default 3 rounds; 1014x760,
 *        2028x1520, 4056x3040); prints a table, writes
 *        bench-out/merge.csv and bench-out/merge.png (gnuplot).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd/backends.h"
#include "bench.h"

#include "capture/camera/bracket.h"
#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/session_merge.h"
#include "core/clock.h"
#include "core/error.h"
#include "sim/camera_sim.h"
#include "sim/sensor.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define MAXROUNDS 9
#define MAXSIZES  6
enum { M_STREAM, M_BATCH, NM };
static const char *const mode_name[NM] = { "streaming (shipped)",
					   "batch (frames kept)" };
static const char *const mode_key[NM] = { "streaming", "batch" };

static double now(void)
{
	return glint_clock_monotonic();
}

static void wait_until(double t)
{
	double d;
	while ((d = t - now()) > 0) {
		struct timespec ts = { (time_t)d,
				       (long)((d - (time_t)d) * 1e9) };
		nanosleep(&ts, NULL);
	}
}

static int capture(int w, int h, struct glint_bracket *b)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	char dev[96];

	/* Without the lens's blur and the low-pass filter: the z-scores
	 * compare the merge with the card's own radiance, which they blur. */
	snprintf(dev, sizeof(dev), "sim:width=%d,height=%d,seed=5,psf=0,olpf=0",
		 w, h);
	int ret = glint_camera_open("sim", dev, &clk, &cam);
	if (ret == 0) {
		glint_bracket_default_opts(&o);
		o.max_time_s = 1e6; /* the fake clock: no cap */
		ret = glint_bracket_capture(cam, &all, &o, &clk, b);
	}
	glint_camera_close(cam);
	return ret;
}

/* One replay of bracket b; *ready and *disk: seconds after the last
 * frame's arrival. */
static int replay(int mode, const struct glint_bracket *b,
		  const struct glint_noise_model *nm, double *ready,
		  double *disk, struct glint_raw_hdr *keep)
{
	static const char *const names[5] = { "hdr.exr", "variance.exr",
					      "weights.exr", "mask.png",
					      "hdr.png" };
	struct glint_hdr_stream *st = NULL;
	struct glint_raw_hdr raw;
	struct glint_image *r, *v, *m;
	double t = now() + 0.05, last = t;
	int ret = mode == M_STREAM ? glint_hdr_stream_new(nm, &st) : 0;

	for (int i = 0; i < b->n && ret == 0; i++) {
		last = t += fmax(b->frames[i].exposure_s, 1.0 / 30);
		wait_until(t);
		if (st)
			ret = glint_hdr_stream_add(st, &b->frames[i]);
	}
	if (ret == 0)
		ret = st ? glint_hdr_stream_finish(st, &raw, NULL)
			 : glint_hdr_merge_raw(b->frames, b->n, nm, &raw, NULL);
	glint_hdr_stream_free(st);
	if (ret == 0)
		ret = glint_hdr_demosaic(&raw, &r, &v, &m);
	if (ret < 0)
		return ret;
	*ready = now() - last;
	glint_image_free(r);
	glint_image_free(v);
	glint_image_free(m);
	if (keep) {
		*keep = raw;
		*disk = NAN;
		return 0;
	}
	int w, h;
	long valid;
	ret = glint_hdr_write(&raw, "bench-out/merge-tmp", names, &w, &h,
			      &valid, NULL);
	*disk = now() - last;
	for (int i = 0; i < 5; i++) {
		char p[128];
		snprintf(p, sizeof(p), "bench-out/merge-tmp/%s", names[i]);
		unlink(p);
	}
	rmdir("bench-out/merge-tmp");
	return ret;
}

/* z-scores against the test card's radiance: mean and spread. */
static void zstats(const struct glint_raw_hdr *h, double *mean, double *sd)
{
	struct glint_sensor s;
	struct glint_image *card = glint_sim_test_card(h->width, h->height, 6);
	double sz = 0, szz = 0;
	long n = 0;

	glint_sensor_default(&s);
	for (int y = 0; card && y < h->height; y++)
		for (int x = 0; x < h->width; x++) {
			size_t i = (size_t)y * h->width + x;
			if (!h->valid[i])
				continue;
			int c = (x & 1) + (y & 1); /* RGGB */
			double t = glint_image_px(card, x, y)[c] * s.k * s.gain;
			double z = (h->x[i] - t) / sqrt(h->var[i]);
			sz += z;
			szz += z * z;
			n++;
		}
	*mean = n ? sz / n : NAN;
	*sd = n ? sqrt(szz / n - *mean * *mean) : NAN;
	glint_image_free(card);
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/merge [ROUNDS] [WxH...]";
	bench_help(argc, argv, usage);
	int rounds = 3, nsz = 0, size[MAXSIZES][2];
	static const int dflt[3][2] = { { 1014, 760 },
					{ 2028, 1520 },
					{ 4056, 3040 } };
	struct glint_noise_model nm;

	glint_backends_register();
	glint_noise_default(&nm);
	for (int i = 1; i < argc; i++) {
		int w, h;
		if (sscanf(argv[i], "%dx%d", &w, &h) == 2 && w >= 8 && h >= 8 &&
		    w <= 8192 && h <= 8192 && nsz < MAXSIZES) {
			size[nsz][0] = w & ~1;
			size[nsz++][1] = h & ~1;
		} else if (bench_count(argv[i], 1, 1000) > 0) {
			rounds = fmin(bench_count(argv[i], 1, 1000), MAXROUNDS);
		} else {
			bench_refuse(argv[i], usage);
		}
	}
	if (!nsz)
		for (; nsz < 3; nsz++) {
			size[nsz][0] = dflt[nsz][0];
			size[nsz][1] = dflt[nsz][1];
		}
	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/merge.csv", "w");
	if (!csv) {
		perror("bench-out/merge.csv");
		return 1;
	}
	fprintf(csv, "size,megapixels,frames,mode,ready_s,on_disk_s,held_mb,"
		     "z_mean,z_sd,vs_batch_sigma\n");
	printf("raw merge after the last frame: %d rounds, modes "
	       "alternating\n\n",
	       rounds);
	printf("%-10s %5s %6s  %-20s %9s %9s %8s %7s %6s %10s\n", "size", "MP",
	       "frames", "mode", "ready s", "disk s", "held MB", "z mean",
	       "z sd", "vs batch");
	for (int k = 0; k < nsz; k++) {
		int w = size[k][0], h = size[k][1];
		struct glint_bracket b;
		double t0 = now();
		if (capture(w, h, &b) < 0) {
			fprintf(stderr, "bench/merge: %s\n", glint_error_msg());
			return 1;
		}
		fprintf(stderr, "%dx%d: %d frames simulated in %.0f s\n", w, h,
			b.n, now() - t0);
		double ready[NM][MAXROUNDS], disk[NM][MAXROUNDS];
		struct glint_raw_hdr res[NM];
		for (int r = 0; r <= rounds; r++)
			for (int m = 0; m < NM; m++) {
				/* Round 0 keeps the merges for accuracy. */
				double rd, dk;
				if (replay(m, &b, &nm, &rd, &dk,
					   r ? NULL : &res[m]) < 0) {
					fprintf(stderr, "bench/merge: %s\n",
						glint_error_msg());
					return 1;
				}
				if (r) {
					ready[m][r - 1] = rd;
					disk[m][r - 1] = dk;
				}
			}
		double sites = (double)w * h, diff = 0;
		long nd = 0;
		for (size_t i = 0; i < (size_t)sites; i++)
			if (res[M_BATCH].valid[i] && res[M_STREAM].valid[i]) {
				diff += fabs(res[M_STREAM].x[i] -
					     res[M_BATCH].x[i]) /
					sqrt(res[M_BATCH].var[i]);
				nd++;
			}
		double held[NM] = { sites * (4 + 4 + 4 + 2) / 1e6,
				    sites * 2 * b.n / 1e6 };
		for (int m = 0; m < NM; m++) {
			double zm, zs;
			zstats(&res[m], &zm, &zs);
			double vs = m == M_STREAM ? diff / nd : 0;
			double mr = bench_median(ready[m], rounds),
			       md = bench_median(disk[m], rounds);
			printf("%4dx%-5d %5.2f %6d  %-20s %9.3f %9.3f %8.0f "
			       "%+7.3f %6.3f %10.4f\n",
			       w, h, sites / 1e6, b.n, mode_name[m], mr, md,
			       held[m], zm, zs, vs);
			fprintf(csv,
				"%dx%d,%.3f,%d,%s,%.4f,%.4f,%.1f,%.4f,"
				"%.4f,%.5f\n",
				w, h, sites / 1e6, b.n, mode_key[m], mr, md,
				held[m], zm, zs, vs);
			glint_raw_hdr_release(&res[m]);
		}
		glint_bracket_release(&b);
	}
	fclose(csv);
	printf("\nready: merged and demosaiced after the last frame arrived; "
	       "disk: and its five files written;\nmedians of %d rounds; "
	       "vs batch: mean |stream - batch| / batch sigma; peak memory "
	       "%.0f MiB (the replayed frames)\n",
	       rounds, bench_peak_mib());
	FILE *gp = fopen("bench-out/merge.gp", "w");
	if (gp) {
		fprintf(gp,
			"set terminal pngcairo noenhanced size 900,420\n"
			"set output 'bench-out/merge.png'\n"
			"set datafile separator ','\nset key left top\n"
			"set logscale x\nset xlabel 'megapixels'\n"
			"set ylabel 'seconds after the last frame'\n"
			"set title 'glint raw HDR merge: ready after the "
			"bracket'\n"
			"set xrange [0.5:20]\n"
			"plot 'bench-out/merge.csv' skip 1 every 2::0 using "
			"2:5 with linespoints title 'streaming (shipped)', '' "
			"skip 1 every 2::1 using 2:5 with linespoints title "
			"'batch (frames kept)', 0.5 with lines dt 2 title "
			"'target 0.5 s'\n");
		fclose(gp);
		if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
		    system("gnuplot bench-out/merge.gp") == 0)
			printf("plot: bench-out/merge.png\n");
	}
	return 0;
}
