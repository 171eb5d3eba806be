/* SPDX-License-Identifier: MIT */
/*
 * The linear merge folded in frame by frame (capture/hdr/hdr_linear.h): per
 * site the sums of weights and of weighted values, and a bit per frame
 * that was unclipped there; one frame held back so that its weight can
 * come from the frame after it.
 */
#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/hdr_linear_priv.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct glint_hdr_stream {
	struct glint_noise_model noise;
	int n;			  /* frames added */
	int failed;		  /* an add failed: no result */
	struct glint_frame first; /* frame 0's metadata (no pixels) */
	struct merge_frame k[GLINT_HDR_STREAM_MAX]; /* per frame, no pixels */
	int shortest;				    /* index of least t g */
	size_t sites;
	float *sw, *swx;	     /* sums of weights, of weight x value */
	uint32_t *mask;		     /* bit i: frame i unclipped at the site */
	uint16_t *held;		     /* the frame held back (index n - 1) */
	struct glint_hdr_report rep; /* the motion check's counts so far */
};

int glint_hdr_stream_new(const struct glint_noise_model *noise,
			 struct glint_hdr_stream **out)
{
	struct glint_hdr_stream *s = calloc(1, sizeof(*s));

	*out = NULL;
	if (!s)
		return glint_error_set(ENOMEM, "HDR merge: out of memory");
	s->noise = *noise;
	*out = s;
	return 0;
}

static void release(struct glint_hdr_stream *s)
{
	free(s->sw);
	free(s->swx);
	free(s->mask);
	free(s->held);
	s->sw = s->swx = NULL;
	s->mask = NULL;
	s->held = NULL;
}

void glint_hdr_stream_free(struct glint_hdr_stream *s)
{
	if (!s)
		return;
	release(s);
	free(s);
}

/* Folding the held frame in, rows [begin, end) on one thread. */
struct fold_job {
	struct glint_hdr_stream *s;
	const struct merge_frame *held, *next; /* next: NULL at the end */
	uint32_t bit;
	int pair; /* the motion check's pair index, -1: none */
	struct glint_hdr_report *part;
	int width;
};

/* Site i of the held frame into the sums. */
static inline void fold_site(const struct fold_job *j, size_t i,
			     struct glint_hdr_report *rep)
{
	const struct merge_frame *h = j->held, *nx = j->next;
	struct glint_hdr_stream *s = j->s;
	double w0 = s->sw[i], wx0 = s->swx[i];
	/* The estimate without the held frame's noise: the frames folded
	 * before it and the next one. */
	double sw = w0, swx = wx0;
	if (nx && nx->data[i] < nx->sat) {
		double d = nx->data[i] - nx->black;
		double x = w0 > 0 ? wx0 / w0 : d / nx->tg;
		double v = glint_merge_var_x(nx, x * nx->tg);
		sw += 1 / v;
		swx += d / nx->tg / v;
	}
	double dn = h->data[i], d = dn - h->black;
	double xref = sw > 0 ? swx / sw : d / h->tg;
	if (dn < h->sat) {
		double v = glint_merge_var_x(h, xref * h->tg);
		s->sw[i] = (float)(w0 + 1 / v);
		s->swx[i] = (float)(wx0 + d / h->tg / v);
		s->mask[i] |= j->bit;
	}
	double z;
	if (j->pair >= 0 && glint_merge_pair_z(h, nx, i, xref, &z)) {
		rep->compared[j->pair]++;
		if (fabs(z) > 5)
			rep->disagree[j->pair] += 1;
	}
}

static void fold_rows(void *ctx, int begin, int end, int thread)
{
	const struct fold_job *j = ctx;

	for (size_t i = (size_t)begin * j->width; i < (size_t)end * j->width;
	     i++)
		fold_site(j, i, &j->part[thread]);
}

static int fold_held(struct glint_hdr_stream *s, const struct merge_frame *next)
{
	int nthreads = glint_cpu_count();
	int idx = s->n - 2; /* the held frame's index */
	struct merge_frame held = s->k[idx];
	struct glint_hdr_report *part = calloc((size_t)nthreads, sizeof(*part));

	if (!part)
		return glint_error_set(ENOMEM, "HDR merge: out of memory");
	held.data = s->held;
	struct fold_job job = { s,
				&held,
				next,
				1u << idx,
				idx < 32 ? idx : -1,
				part,
				s->first.width * s->first.channels };
	glint_parallel_for(s->first.height, 8, nthreads, fold_rows, &job);
	for (int t = 0; job.pair >= 0 && t < nthreads; t++) {
		s->rep.compared[idx] += part[t].compared[idx];
		s->rep.disagree[idx] += part[t].disagree[idx];
	}
	free(part);
	return 0;
}

static int start(struct glint_hdr_stream *s, const struct glint_frame *f)
{
	size_t ns = (size_t)f->width * f->channels * f->height;

	s->sites = ns;
	s->sw = calloc(ns, sizeof(float));
	s->swx = calloc(ns, sizeof(float));
	s->mask = calloc(ns, sizeof(uint32_t));
	s->held = malloc(ns * sizeof(uint16_t));
	if (!s->sw || !s->swx || !s->mask || !s->held) {
		release(s);
		return glint_error_set(ENOMEM, "HDR merge: out of memory");
	}
	s->first = *f;
	s->first.data = NULL;
	return 0;
}

int glint_hdr_stream_add(struct glint_hdr_stream *s,
			 const struct glint_frame *f)
{
	int ret;

	if (s->failed)
		return glint_error_set(EINVAL,
				       "HDR merge: an earlier frame "
				       "failed; nothing more is merged");
	if (s->n >= GLINT_HDR_STREAM_MAX)
		ret = glint_error_set(EINVAL,
				      "HDR merge: frame %d: at most %d frames "
				      "a bracket",
				      s->n, GLINT_HDR_STREAM_MAX);
	else
		ret = glint_hdr_check_frame(f, s->n, s->n ? &s->first : NULL);
	if (ret == 0 && s->n == 0)
		ret = start(s, f);
	if (ret < 0) {
		s->failed = 1;
		return ret;
	}
	struct merge_frame *k = &s->k[s->n];
	glint_merge_frame_init(k, f, &s->noise);
	if (k->tg < s->k[s->shortest].tg)
		s->shortest = s->n;
	s->n++;
	if (s->n > 1) {
		k->data = f->data;
		ret = fold_held(s, k);
		k->data = NULL;
		if (ret < 0) {
			s->failed = 1;
			return ret;
		}
	}
	memcpy(s->held, f->data, s->sites * sizeof(uint16_t));
	return 0;
}

/* The last frame folded in and the merged value and variance per site,
 * in place of the sums: one pass. */
struct finish_job {
	struct fold_job fold; /* the last frame, no next */
	uint8_t *valid;
};

static void finish_rows(void *ctx, int begin, int end, int thread)
{
	const struct finish_job *j = ctx;
	struct glint_hdr_stream *s = j->fold.s;
	struct glint_hdr_report *rep = &j->fold.part[thread];
	const struct merge_frame *k0 = &s->k[s->shortest];
	size_t w = (size_t)j->fold.width;

	for (size_t i = (size_t)begin * w; i < (size_t)end * w; i++) {
		fold_site(&j->fold, i, rep);
		uint32_t m = s->mask[i];
		if (!m) {
			/* Clipped in every frame: a lower bound, no weight. */
			s->swx[i] = (float)((k0->top - k0->black) / k0->tg);
			s->sw[i] = 0;
			j->valid[i] = 0;
			rep->invalid_sites++;
			continue;
		}
		double xhat = (double)s->swx[i] / s->sw[i], si = 0;
		for (; m; m &= m - 1) {
			const struct merge_frame *k = &s->k[__builtin_ctz(m)];
			si += 1 / glint_merge_var_x(k, xhat * k->tg);
		}
		double var = 1 / si;
		s->swx[i] = (float)xhat;
		s->sw[i] = (float)var;
		j->valid[i] = 1;
		if (xhat < 3 * sqrt(var))
			rep->dark_sites++;
	}
}

int glint_hdr_stream_finish(struct glint_hdr_stream *s,
			    struct glint_raw_hdr *out,
			    struct glint_hdr_report *rep)
{
	struct glint_hdr_report local;
	int nthreads = glint_cpu_count();

	memset(out, 0, sizeof(*out));
	if (!rep)
		rep = &local;
	memset(rep, 0, sizeof(*rep));
	if (s->failed)
		return glint_error_set(EINVAL, "HDR merge: a frame failed; "
					       "nothing merged");
	if (s->n < 1)
		return glint_error_set(EINVAL, "HDR merge: no frames");
	uint8_t *valid = malloc(s->sites);
	struct glint_hdr_report *part = calloc((size_t)nthreads, sizeof(*part));
	if (!valid || !part) {
		free(valid);
		free(part);
		s->failed = 1;
		return glint_error_set(ENOMEM, "HDR merge: out of memory");
	}
	int last = s->n - 1;
	struct merge_frame held = s->k[last];
	held.data = s->held;
	struct finish_job job = { { s, &held, NULL, 1u << last, -1, part,
				    s->first.width * s->first.channels },
				  valid };
	glint_parallel_for(s->first.height, 8, nthreads, finish_rows, &job);
	*rep = s->rep;
	rep->frames = s->n;
	rep->sites = (long)s->sites;
	rep->pairs = s->n - 1 < 32 ? s->n - 1 : 32;
	for (int i = 0; i < rep->pairs; i++) {
		rep->pair_tg[i][0] = s->k[i].tg;
		rep->pair_tg[i][1] = s->k[i + 1].tg;
	}
	for (int t = 0; t < nthreads; t++) {
		rep->invalid_sites += part[t].invalid_sites;
		rep->dark_sites += part[t].dark_sites;
	}
	free(part);
	out->width = s->first.width;
	out->height = s->first.height;
	snprintf(out->format, sizeof(out->format), "%s", s->first.format);
	out->x = s->swx;
	out->var = s->sw;
	out->valid = valid;
	s->swx = s->sw = NULL;
	release(s);
	s->failed = 1; /* finished: nothing more to add */
	return glint_hdr_report_finish(rep, out, s->k[s->shortest].tg);
}
