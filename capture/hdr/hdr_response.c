/* SPDX-License-Identifier: MIT */
#include "capture/hdr/hdr_response.h"

#include "core/error.h"
#include "core/parallel.h"

#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_vector.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

void glint_debevec_default_opts(struct glint_debevec_opts *o)
{
	o->samples = 70;
	o->lambda = 10;
	o->floor[0] = o->floor[1] = o->floor[2] = -1;
}

/* Weight: OpenCV's hat (z + 1 up to 127, 256 - z above) when floor is 0,
 * else the same shape over (floor, 255], 0 at or below. */
static double hat(int floor, int z)
{
	if (floor <= 0)
		return z < 128 ? z + 1.0 : 256.0 - z;
	if (z <= floor)
		return 0;
	int mid = (floor + 256) / 2;
	return z < mid ? z - floor : 256.0 - z;
}

void glint_ldr_floor(const struct glint_ldr_stack *s, int floor[3])
{
	int k = 0;
	size_t np = (size_t)s->width * s->height;
	for (int i = 1; i < s->n; i++)
		if (s->times[i] < s->times[k])
			k = i;
	/* The 5th percentile of each channel, from a histogram of codes: the
	 * value at index np / 20 of the sorted samples. */
	size_t hist[3][256] = { { 0 } };
	for (size_t p = 0; p < np; p++)
		for (int c = 0; c < 3; c++)
			hist[c][s->rgb[k][3 * p + c]]++;
	for (int c = 0; c < 3; c++) {
		size_t cum = 0;
		int z = 0;
		while (z < 255 && (cum += hist[c][z]) <= np / 20)
			z++;
		int f = z + 3;
		floor[c] = f > 127 ? 127 : f;
	}
}

int glint_ldr_check_order(const struct glint_ldr_stack *s,
			  const char *const *names)
{
	size_t np = (size_t)s->width * s->height;
	int floor[3];

	glint_ldr_floor(s, floor);
	for (int a = 0; a < s->n; a++) {
		int b = -1; /* the next longer exposure */
		for (int i = 0; i < s->n; i++)
			if (s->times[i] > s->times[a] &&
			    (b < 0 || s->times[i] < s->times[b]))
				b = i;
		for (int i = a + 1; i < s->n; i++)
			if (!memcmp(s->rgb[i], s->rgb[a], np * 3))
				return glint_error_set(
					EINVAL,
					"%s and %s are the same image (a "
					"duplicated frame?)",
					names ? names[a] : "a frame",
					names ? names[i] : "another");
		if (b < 0)
			continue;
		for (int c = 0; c < 3; c++) {
			long up = 0, down = 0;
			for (size_t p = 0; p < np; p++) {
				int za = s->rgb[a][3 * p + c];
				int zb = s->rgb[b][3 * p + c];
				if (za <= floor[c] || zb <= floor[c] ||
				    za == 255 || zb == 255)
					continue;
				up += zb > za;
				down += zb < za;
			}
			if (up + down >= 100 && up < down)
				return glint_error_set(
					EINVAL,
					"%s (%g s) is darker than %s (%g s) "
					"in %.0f %% of the pixels that "
					"differ: the frames are not in the "
					"order of their exposure times (or a "
					"time is wrong)",
					names ? names[b] : "a frame",
					s->times[b],
					names ? names[a] : "a shorter one",
					s->times[a],
					100.0 * down / (double)(up + down));
		}
	}
	return 0;
}

static int check_stack(const struct glint_ldr_stack *s, int need_distinct)
{
	if (s->n < 2)
		return glint_error_set(
			EINVAL,
			"response recovery: %d image(s): need at "
			"least 2 exposures",
			s->n);
	if (s->width < 2 || s->height < 2)
		return glint_error_set(EINVAL,
				       "response recovery: %dx%d "
				       "images",
				       s->width, s->height);
	int distinct = 0;
	for (int i = 0; i < s->n; i++) {
		if (!(s->times[i] > 0) || !isfinite(s->times[i]))
			return glint_error_set(
				EINVAL,
				"exposure %d: time %g s: expected "
				"a positive time",
				i, s->times[i]);
		if (i && s->times[i] != s->times[0])
			distinct = 1;
	}
	if (need_distinct && !distinct)
		return glint_error_set(EINVAL,
				       "response recovery: every exposure is "
				       "%g s: the times must differ",
				       s->times[0]);
	return 0;
}

int glint_response_debevec(const struct glint_ldr_stack *s,
			   const struct glint_debevec_opts *o,
			   double response[256][3])
{
	int ret = check_stack(s, 1);
	int floor[3];
	if (ret < 0)
		return ret;
	if (o->floor[0] < 0)
		glint_ldr_floor(s, floor);
	else
		memcpy(floor, o->floor, sizeof(floor));
	/* OpenCV's sampling grid (its "random = false"). */
	int xp = (int)sqrt((double)o->samples * s->width / s->height);
	if (xp < 1)
		xp = 1;
	int yp = o->samples / xp;
	if (yp < 1)
		yp = 1;
	int sx = s->width / xp, sy = s->height / yp;
	int np = xp * yp;
	/* Rows: data, g(128) = 0, smoothness, and a 1e-9 pull of each ln E
	 * to 0 (keeps samples that are black in every frame determined). */
	int rows = np * s->n + 1 + 254 + np, cols = 256 + np;
	gsl_matrix *a = gsl_matrix_alloc((size_t)rows, (size_t)cols);
	gsl_vector *b = gsl_vector_alloc((size_t)rows);
	gsl_vector *tau = gsl_vector_alloc((size_t)cols);
	gsl_vector *x = gsl_vector_alloc((size_t)cols);
	gsl_vector *res = gsl_vector_alloc((size_t)rows);
	if (!a || !b || !tau || !x || !res) {
		ret = glint_error_set(ENOMEM,
				      "response recovery: out of memory");
		goto out;
	}
	for (int c = 0; c < 3; c++) {
		gsl_matrix_set_zero(a);
		gsl_vector_set_zero(b);
		int eq = 0;
		for (int i = 0; i < xp; i++)
			for (int j = 0; j < yp; j++) {
				int px = sx / 2 + i * sx, py = sy + j * sy;
				if (py >= s->height)
					py = s->height - 1;
				int k = i * yp + j;
				for (int im = 0; im < s->n; im++, eq++) {
					int z = s->rgb[im]
						      [3 * ((size_t)py *
								    s->width +
							    px) +
						       c];
					double w = hat(floor[c], z);
					gsl_matrix_set(a, (size_t)eq, (size_t)z,
						       w);
					gsl_matrix_set(a, (size_t)eq,
						       (size_t)(256 + k), -w);
					gsl_vector_set(b, (size_t)eq,
						       w * log(s->times[im]));
				}
			}
		gsl_matrix_set(a, (size_t)eq++, 128, 1); /* g(128) = 0 */
		for (int z = 1; z < 255; z++, eq++) {
			double w = o->lambda * fmax(hat(floor[c], z), 1);
			gsl_matrix_set(a, (size_t)eq, (size_t)z - 1, w);
			gsl_matrix_set(a, (size_t)eq, (size_t)z, -2 * w);
			gsl_matrix_set(a, (size_t)eq, (size_t)z + 1, w);
		}
		for (int k = 0; k < np; k++, eq++)
			gsl_matrix_set(a, (size_t)eq, (size_t)(256 + k), 1e-9);
		if (gsl_linalg_QR_decomp(a, tau) ||
		    gsl_linalg_QR_lssolve(a, tau, b, x, res)) {
			ret = glint_error_set(EDOM,
					      "response recovery: the least "
					      "squares problem is singular "
					      "(too few distinct code "
					      "values?)");
			goto out;
		}
		double g128 = gsl_vector_get(x, 128);
		for (int z = 0; z < 256; z++)
			response[z][c] =
				exp(gsl_vector_get(x, (size_t)z) - g128);
	}
out:
	gsl_matrix_free(a);
	gsl_vector_free(b);
	gsl_vector_free(tau);
	gsl_vector_free(x);
	gsl_vector_free(res);
	return ret;
}

static double robertson_w(int z)
{
	double d = (z - 127.5) / 127.5;
	return exp(-4 * d * d);
}

int glint_response_robertson(const struct glint_ldr_stack *s, int max_iter,
			     double threshold, double response[256][3],
			     int *iterations)
{
	int ret = check_stack(s, 1);
	if (ret < 0)
		return ret;
	size_t np = (size_t)s->width * s->height;
	float *e = malloc(np * sizeof(float));
	double count[256][3], w[256];
	if (!e)
		return glint_error_set(ENOMEM, "Robertson: out of memory");
	memset(count, 0, sizeof(count));
	for (int z = 0; z < 256; z++) {
		w[z] = robertson_w(z);
		for (int c = 0; c < 3; c++)
			response[z][c] = z / 128.0; /* linear start */
	}
	for (int i = 0; i < s->n; i++)
		for (size_t p = 0; p < np; p++)
			for (int c = 0; c < 3; c++)
				count[s->rgb[i][3 * p + c]][c] += 1;
	*iterations = 0;
	for (int it = 0; it < max_iter; it++) {
		double next[256][3], diff = 0;
		memset(next, 0, sizeof(next));
		for (int c = 0; c < 3; c++) {
			/* Irradiance per pixel under the current response. */
			for (size_t p = 0; p < np; p++) {
				double num = 0, den = 0;
				for (int i = 0; i < s->n; i++) {
					int z = s->rgb[i][3 * p + c];
					double t = s->times[i];
					num += w[z] * t * response[z][c];
					den += w[z] * t * t;
				}
				e[p] = (float)(den > 0 ? num / den : 0);
			}
			/* Response: the mean exposure giving each code. */
			for (int i = 0; i < s->n; i++)
				for (size_t p = 0; p < np; p++)
					next[s->rgb[i][3 * p + c]][c] +=
						s->times[i] * e[p];
			for (int z = 0; z < 256; z++)
				next[z][c] = count[z][c] > 0
						     ? next[z][c] / count[z][c]
						     : NAN;
			/* Codes never seen: interpolate neighbours. */
			for (int z = 0; z < 256; z++)
				if (isnan(next[z][c])) {
					int lo = z - 1, hi = z + 1;
					while (lo >= 0 && isnan(next[lo][c]))
						lo--;
					while (hi < 256 && isnan(next[hi][c]))
						hi++;
					next[z][c] =
						lo >= 0 && hi < 256
							? next[lo][c] +
								  (next[hi][c] -
								   next[lo]
								       [c]) *
									  (z -
									   lo) /
									  (hi -
									   lo)
						: lo >= 0  ? next[lo][c]
						: hi < 256 ? next[hi][c]
							   : z / 128.0;
				}
			double mid = next[128][c];
			for (int z = 0; z < 256; z++) {
				next[z][c] /= mid;
				diff += fabs(next[z][c] - response[z][c]);
				response[z][c] = next[z][c];
			}
		}
		*iterations = it + 1;
		if (diff / 3 < threshold)
			break;
	}
	free(e);
	return 0;
}

struct merge_job {
	const struct glint_ldr_stack *s;
	const double (*response)[3];
	const double (*w)[3];
	/* per frame i, code z, channel c: w(z) (ln I(z) - ln t_i), the
	 * frame's term of the weighted sum, made once */
	const double (*term)[256][3];
	struct glint_image *img, *m;
	atomic_long bad; /* pixel-channels without information */
};

/* A pixel-channel no frame informs: a bound from the extreme code. */
static float merge_bound(const struct merge_job *job, size_t p, int c)
{
	const struct glint_ldr_stack *s = job->s;
	int zmin = 255, zmax = 0;

	for (int i = 0; i < s->n; i++) {
		int z = s->rgb[i][3 * p + c];
		zmin = z < zmin ? z : zmin;
		zmax = z > zmax ? z : zmax;
	}
	double t = s->times[0];
	for (int i = 1; i < s->n; i++)
		t = zmin >= 255 ? fmin(t, s->times[i]) : fmax(t, s->times[i]);
	/* Clipped everywhere: a lower bound; black everywhere: an upper
	 * one. */
	return (float)(job->response[zmin >= 255 ? 255 : zmax][c] / t);
}

/* One pixel: per channel the weighted mean of ln E; returns how many
 * channels had no information. */
static int merge_pixel(const struct merge_job *job, size_t p)
{
	const struct glint_ldr_stack *s = job->s;
	double num[3] = { 0, 0, 0 }, den[3] = { 0, 0, 0 };
	int bad = 0;

	for (int i = 0; i < s->n; i++) {
		const uint8_t *z = s->rgb[i] + 3 * p;
		for (int c = 0; c < 3; c++) {
			num[c] += job->term[i][z[c]][c];
			den[c] += job->w[z[c]][c];
		}
	}
	for (int c = 0; c < 3; c++) {
		int ok = den[c] > 0;
		job->img->data[3 * p + c] = ok ? (float)exp(num[c] / den[c])
					       : merge_bound(job, p, c);
		if (job->m)
			job->m->data[3 * p + c] = (float)ok;
		bad += !ok;
	}
	return bad;
}

static void merge_rows(void *ctx, int y0, int y1, int thread)
{
	struct merge_job *job = ctx;
	size_t w = (size_t)job->s->width;
	long bad = 0;

	for (size_t p = (size_t)y0 * w; p < (size_t)y1 * w; p++)
		bad += merge_pixel(job, p);
	(void)thread;
	atomic_fetch_add(&job->bad, bad);
}

int glint_ldr_merge(const struct glint_ldr_stack *s,
		    const double response[256][3], const int *floor_in,
		    struct glint_image **out, struct glint_image **valid)
{
	double lnr[256][3], w[256][3];
	int ret = check_stack(s, 0), floor[3];

	*out = NULL;
	if (valid)
		*valid = NULL;
	if (ret < 0 && s->n >= 1)
		ret = 0; /* one exposure merges (to itself) */
	if (ret < 0)
		return ret;
	if (floor_in)
		memcpy(floor, floor_in, sizeof(floor));
	else
		glint_ldr_floor(s, floor);
	for (int z = 0; z < 256; z++) {
		for (int c = 0; c < 3; c++) {
			/* 0 at 255 and at or below the floor (at 0 when there
			 * is none): no clipped or black sample contributes. */
			w[z][c] = z >= 255 || z <= floor[c] ? 0
							    : hat(floor[c], z);
			if (!(response[z][c] > 0) || !isfinite(response[z][c]))
				return glint_error_set(EINVAL,
						       "response: code %d "
						       "channel %d is %g: "
						       "expected positive",
						       z, c, response[z][c]);
			lnr[z][c] = log(response[z][c]);
		}
	}
	struct glint_image *img = glint_image_new(s->width, s->height);
	struct glint_image *m =
		valid ? glint_image_new(s->width, s->height) : NULL;
	if (!img || (valid && !m)) {
		glint_image_free(img);
		glint_image_free(m);
		return glint_error_set(ENOMEM, "merge: out of memory");
	}
	size_t np = (size_t)s->width * s->height;
	long bad = 0;
	if (s->n > 256) {
		glint_image_free(img);
		glint_image_free(m);
		return glint_error_set(EINVAL,
				       "merge: %d exposures (at most "
				       "256)",
				       s->n);
	}
	double(*term)[256][3] = malloc((size_t)s->n * sizeof(*term));
	if (!term) {
		glint_image_free(img);
		glint_image_free(m);
		return glint_error_set(ENOMEM, "merge: out of memory");
	}
	for (int i = 0; i < s->n; i++) {
		double lnt = log(s->times[i]);
		for (int z = 0; z < 256; z++)
			for (int c = 0; c < 3; c++)
				term[i][z][c] =
					w[z][c] * lnr[z][c] - w[z][c] * lnt;
	}
	struct merge_job job = { s,
				 response,
				 (const double(*)[3])w,
				 (const double(*)[256][3])term,
				 img,
				 m,
				 0 };
	glint_parallel_for(s->height, 8, 0, merge_rows, &job);
	free(term);
	bad = atomic_load(&job.bad);
	if (bad == (long)(np * 3)) {
		glint_image_free(img);
		glint_image_free(m);
		return glint_error_set(ERANGE,
				       "merge: every sample is clipped or "
				       "black in every exposure");
	}
	*out = img;
	if (valid)
		*valid = m;
	return 0;
}
