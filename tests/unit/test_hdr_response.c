/* SPDX-License-Identifier: MIT */
/*
 * Response-curve recovery and the 8-bit merge on the real Memorial Church
 * stack (Debevec & Malik's own photographs, ../shared/data/exposures),
 * against OpenCV's regression data for the same stack and a published
 * merged radiance map.  The numbers printed here are docs/benchmarks.md's.
 */
#include "test.h"

#include "capture/hdr/hdr_response.h"
#include "core/error.h"
#include "core/formats.h"

#define N 16

static uint8_t *img[N];
static double times[N];
static int w, h;

static int load_stack(void)
{
	char rel[128];
	for (int i = 0; i < N; i++) {
		snprintf(rel, sizeof(rel),
			 "exposures/memorial/memorial%04d.png", 61 + i);
		const char *p = shared_file(rel);
		if (!p)
			return 77;
		int wi, hi;
		if (glint_png_read_rgb8(p, &wi, &hi, &img[i]) < 0) {
			fprintf(stderr, "%s\n", glint_error_msg());
			return 1;
		}
		if (i && (wi != w || hi != h))
			return 1;
		w = wi;
		h = hi;
		times[i] = 32.0 / (1 << i); /* 32 s ... 1/1024 s */
	}
	return 0;
}

/* OpenCV's CSV: 256 rows of 3 numbers (',' or ';' separated). */
static int load_csv(const char *rel, double r[256][3])
{
	const char *p = shared_file(rel);
	if (!p)
		return 77;
	FILE *f = fopen(p, "r");
	if (!f)
		return 1;
	for (int z = 0; z < 256; z++)
		if (fscanf(f, " %lf%*[,;] %lf%*[,;] %lf", &r[z][0], &r[z][1],
			   &r[z][2]) != 3) {
			fclose(f);
			return 1;
		}
	fclose(f);
	return 0;
}

/* Largest and median |ln(a / b)| over codes [lo, hi] after scaling both
 * to 1 at code 128; channel c of a against channel cb of b. */
static void curve_diff(double a[256][3], int c, double b[256][3], int cb,
		       int lo, int hi, double *worst, double *median)
{
	double d[256];
	int n = 0;
	for (int z = lo; z <= hi; z++)
		d[n++] = fabs(log(a[z][c] / a[128][c]) -
			      log(b[z][cb] / b[128][cb]));
	*worst = 0;
	for (int i = 0; i < n; i++)
		*worst = fmax(*worst, d[i]);
	/* median by partial sort */
	for (int i = 0; i <= n / 2; i++)
		for (int j = i + 1; j < n; j++)
			if (d[j] < d[i]) {
				double t = d[i];
				d[i] = d[j];
				d[j] = t;
			}
	*median = d[n / 2];
}

static double resp[256][3], cv[256][3];

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void test_debevec(void)
{
	struct glint_ldr_stack s = { N, w, h, (const uint8_t *const *)img,
				     times };
	struct glint_debevec_opts o;
	double worst, med;

	if (load_csv("exposures/opencv_reference/calibrate_debevec.csv", cv)) {
		printf("skip: OpenCV reference curves absent\n");
		return;
	}
	glint_debevec_default_opts(&o);
	/* Like for like: OpenCV's hat has no black floor.  OpenCV reads
	 * BGR: its column 0 is blue. */
	o.floor[0] = o.floor[1] = o.floor[2] = 0;
	CHECK(glint_response_debevec(&s, &o, resp) == 0, "%s",
	      glint_error_msg());
	for (int c = 0; c < 3; c++) {
		curve_diff(resp, c, cv, 2 - c, 16, 239, &worst, &med);
		printf("Debevec (floor 0) vs OpenCV's expected output, %c, "
		       "codes "
		       "16..239: worst |d ln| %.3f, median %.3f\n",
		       "RGB"[c], worst, med);
		CHECK(med < 0.15, "%c: median |d ln| %g against OpenCV",
		      "RGB"[c], med);
	}
	/* glint's default: codes at the black floor carry no weight. */
	int fl[3];
	glint_ldr_floor(&s, fl);
	glint_debevec_default_opts(&o);
	CHECK(glint_response_debevec(&s, &o, resp) == 0, "%s",
	      glint_error_msg());
	for (int c = 0; c < 3; c++) {
		curve_diff(resp, c, cv, 2 - c, 32, 239, &worst, &med);
		printf("Debevec (black floor %d) vs OpenCV, %c, codes 32..239: "
		       "worst |d ln| %.3f, median %.3f\n",
		       fl[c], "RGB"[c], worst, med);
	}
}

static void test_robertson_and_merge(void)
{
	struct glint_ldr_stack s = { N, w, h, (const uint8_t *const *)img,
				     times };
	double rob[256][3], worst, med;
	int iters;

	CHECK(glint_response_robertson(&s, 30, 0.01, rob, &iters) == 0, "%s",
	      glint_error_msg());
	for (int c = 0; c < 3; c++) {
		curve_diff(rob, c, resp, c, 16, 239, &worst, &med);
		printf("Robertson (%d iterations) vs Debevec, %c, codes "
		       "16..239: "
		       "worst |d ln| %.3f, median %.3f\n",
		       iters, "RGB"[c], worst, med);
	}

	const char *ref =
		shared_file("exposures/memorial/memorial_threejs.hdr");
	struct glint_image *pub = NULL, *ours = NULL, *valid = NULL;
	if (!ref || glint_image_read(ref, &pub) < 0) {
		printf("skip: published map absent\n");
		return;
	}
	for (int k = 0; k < 2; k++) {
		CHECK(glint_ldr_merge(&s, k ? rob : resp, NULL, &ours,
				      &valid) == 0,
		      "%s", glint_error_msg());
		if (!ours)
			return;
		CHECK(pub->width == ours->width && pub->height == ours->height,
		      "published %dx%d, ours %dx%d", pub->width, pub->height,
		      ours->width, ours->height);
		/* Up to scale: the median log ratio; then errors and the
		 * correlation of log radiance. */
		size_t n = (size_t)w * h * 3, m = 0;
		double *lr = malloc(n * sizeof(double));
		double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
		for (size_t i = 0; i < n; i++) {
			double a = ours->data[i], b = pub->data[i];
			if (!(a > 0) || !(b > 0) || !valid->data[i])
				continue;
			lr[m++] = log(a / b);
			double la = log(a), lb = log(b);
			sa += la;
			sb += lb;
			saa += la * la;
			sbb += lb * lb;
			sab += la * lb;
		}
		double *srt = malloc(m * sizeof(double));
		memcpy(srt, lr, m * sizeof(double));
		qsort(srt, m, sizeof(double), cmp_double);
		double scale = srt[m / 2];
		size_t within10 = 0;
		double sum_abs = 0;
		for (size_t i = 0; i < m; i++) {
			double e = fabs(exp(lr[i] - scale) - 1);
			within10 += e < 0.10;
			sum_abs += e;
		}
		double corr = (m * sab - sa * sb) /
			      sqrt((m * saa - sa * sa) * (m * sbb - sb * sb));
		printf("%s merge vs memorial_threejs.hdr (up to scale %.4g): "
		       "log correlation %.4f, mean |relative error| %.3f, "
		       "%.1f %% of samples within 10 %%\n",
		       k ? "Robertson" : "Debevec", exp(scale), corr,
		       sum_abs / m, 100.0 * within10 / m);
		CHECK(corr > 0.995, "log correlation %g", corr);
		CHECK(100.0 * within10 / m > (k ? 85 : 60),
		      "%.1f %% within 10 %%", 100.0 * within10 / m);
		free(lr);
		free(srt);
		glint_image_free(ours);
		glint_image_free(valid);
	}
	glint_image_free(pub);
}

static void test_bad_stacks(void)
{
	double t1[2] = { 0.01, 0.01 };
	struct glint_ldr_stack s = { 2, w, h, (const uint8_t *const *)img, t1 };
	struct glint_debevec_opts o;
	glint_debevec_default_opts(&o);
	CHECK(glint_response_debevec(&s, &o, resp) < 0,
	      "equal exposure times accepted");
	CHECK_MSG(glint_error_msg(), "must differ");
	s.n = 1;
	CHECK(glint_response_debevec(&s, &o, resp) < 0,
	      "one exposure accepted");
	CHECK_MSG(glint_error_msg(), "at least 2");
	double t2[2] = { 0.01, -1 };
	s.n = 2;
	s.times = t2;
	CHECK(glint_response_debevec(&s, &o, resp) < 0,
	      "negative time accepted");
	CHECK_MSG(glint_error_msg(), "-1");
}

int main(void)
{
	int r = load_stack();
	if (r == 77) {
		printf("skip: ../shared/data/exposures/memorial absent\n");
		return 77;
	}
	if (r)
		return 1;
	RUN(test_debevec);
	RUN(test_robertson_and_merge);
	RUN(test_bad_stacks);
	for (int i = 0; i < N; i++)
		free(img[i]);
	return test_result();
}
