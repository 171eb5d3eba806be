/* SPDX-License-Identifier: MIT */
#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/hdr_linear_priv.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void glint_noise_default(struct glint_noise_model *m)
{
	/* sim/sensor.c: 12-bit ADC spanning a 10 ke- full well, 2.5 e-. */
	m->dn_per_electron = 4095.0 / 10000.0;
	m->read_noise_e = 2.5;
	m->saturation_dn = 0;
}

void glint_raw_hdr_release(struct glint_raw_hdr *h)
{
	free(h->x);
	free(h->var);
	free(h->valid);
	memset(h, 0, sizeof(*h));
}

int glint_hdr_check_frame(const struct glint_frame *f, int i,
			  const struct glint_frame *f0)
{
	if (!f->linear || !(f->channels == 1 ||
			    (f->channels == 3 && !strcmp(f->format, "RGB16"))))
		return glint_error_set(
			EINVAL,
			"HDR merge: frame %d is %s, %d channel(s)%s: "
			"the linear merge takes raw Bayer, mono or "
			"linear RGB16 frames (camera-encoded ones need "
			"a response curve)",
			i, f->format, f->channels,
			f->linear ? "" : ", camera-encoded");
	if (f0 && (f->width != f0->width || f->height != f0->height ||
		   strcmp(f->format, f0->format) != 0 ||
		   f->bit_depth != f0->bit_depth))
		return glint_error_set(
			EINVAL,
			"HDR merge: frame %d is %dx%d %s %d-bit, "
			"frame 0 %dx%d %s %d-bit: a bracket's "
			"frames must match",
			i, f->width, f->height, f->format, f->bit_depth,
			f0->width, f0->height, f0->format, f0->bit_depth);
	if (!(f->exposure_s > 0) || !isfinite(f->exposure_s) ||
	    !(f->gain > 0) || !isfinite(f->gain))
		return glint_error_set(EINVAL,
				       "HDR merge: frame %d has exposure "
				       "%g s, gain %g: expected positive "
				       "finite values",
				       i, f->exposure_s, f->gain);
	if (f->bit_depth < 1 || f->bit_depth > 16 || !(f->black_level >= 0) ||
	    !(f->white_level >= 0) ||
	    f->white_level > (1 << f->bit_depth) - 1 ||
	    f->black_level >= glint_frame_white_dn(f))
		return glint_error_set(EINVAL,
				       "HDR merge: frame %d: black level "
				       "%g, white level %g for %d bits",
				       i, f->black_level,
				       glint_frame_white_dn(f), f->bit_depth);
	if (!f->data)
		return glint_error_set(EINVAL,
				       "HDR merge: frame %d has no pixels", i);
	return 0;
}

static int check_frames(const struct glint_frame *f, int n)
{
	if (n < 1)
		return glint_error_set(EINVAL, "HDR merge: no frames");
	for (int i = 0; i < n; i++) {
		int ret = glint_hdr_check_frame(&f[i], i, i ? &f[0] : NULL);
		if (ret < 0)
			return ret;
	}
	return 0;
}

static int by_exposure(const void *a, const void *b)
{
	const struct glint_frame *x = *(const struct glint_frame *const *)a;
	const struct glint_frame *y = *(const struct glint_frame *const *)b;
	double ex = x->exposure_s * x->gain, ey = y->exposure_s * y->gain;
	return (ex > ey) - (ex < ey);
}

void glint_merge_frame_init(struct merge_frame *k, const struct glint_frame *f,
			    const struct glint_noise_model *m)
{
	double top = glint_frame_white_dn(f);
	k->data = f->data;
	k->black = f->black_level;
	k->top = top;
	k->sat = m->saturation_dn > 0 ? m->saturation_dn
				      : glint_frame_clip_dn(f);
	k->tg = f->exposure_s * f->gain;
	k->gc = f->gain * m->dn_per_electron;
	k->floor_var =
		k->gc * k->gc * m->read_noise_e * m->read_noise_e + 1.0 / 12;
	k->inv_tg2 = 1 / (k->tg * k->tg);
}

int glint_merge_pair_z(const struct merge_frame *a, const struct merge_frame *b,
		       size_t s, double xhat, double *z)
{
	double da = a->data[s] - a->black, db = b->data[s] - b->black;
	double ra = a->top - a->black, rb = b->top - b->black;
	if (da < 0.02 * ra || da > 0.9 * ra || db < 0.02 * rb || db > 0.9 * rb)
		return 0;
	double v = glint_merge_var_x(a, xhat * a->tg) +
		   glint_merge_var_x(b, xhat * b->tg);
	*z = (da / a->tg - db / b->tg) / sqrt(v);
	return 1;
}

/*
 * One site's merged value and its variance: the inverse-variance weighted
 * mean of the unclipped frames' dn / (time x gain), the variances first
 * from each sample's own value, then from the merged estimate (unbiased
 * weights).  0 when every frame is clipped there.
 */
static int merge_site(const struct merge_frame *f, int n, size_t s,
		      double *xhat, double *var)
{
	double sw = 0, swx = 0;

	*xhat = 0;
	for (int pass = 0; pass < 2; pass++) {
		sw = swx = 0;
		for (int i = 0; i < n; i++) {
			const struct merge_frame *k = &f[i];
			double dn = k->data[s];
			if (dn >= k->sat)
				continue;
			double d = dn - k->black;
			double v =
				glint_merge_var_x(k, pass ? *xhat * k->tg : d);
			sw += 1 / v;
			swx += d / k->tg / v;
		}
		if (!(sw > 0))
			return 0;
		*xhat = swx / sw;
	}
	*var = 1 / sw;
	return 1;
}

/* Motion check at one site on frames adjacent in exposure: their values
 * per unit exposure must agree within 5 sigma. */
static void motion_check(const struct merge_frame *f, int n, size_t s,
			 double xhat, struct glint_hdr_report *rep)
{
	for (int i = 0; i + 1 < n && i < 32; i++) {
		double z;
		if (!glint_merge_pair_z(&f[i], &f[i + 1], s, xhat, &z))
			continue;
		rep->compared[i]++;
		if (fabs(z) > 5)
			rep->disagree[i] += 1;
	}
}

/* The merge's rows [begin, end) on one thread, its counts into its own
 * report. */
struct merge_job {
	const struct merge_frame *f;
	int n, width;
	struct glint_raw_hdr *out;
	struct glint_hdr_report *part; /* one per thread */
};

static void merge_rows(void *ctx, int begin, int end, int thread)
{
	const struct merge_job *j = ctx;
	const struct merge_frame *f0 = &j->f[0];
	struct glint_hdr_report *rep = &j->part[thread];
	struct glint_raw_hdr *out = j->out;

	for (size_t s = (size_t)begin * j->width; s < (size_t)end * j->width;
	     s++) {
		double xhat, var;
		if (!merge_site(j->f, j->n, s, &xhat, &var)) {
			/* Clipped in every frame: a lower bound, no weight. */
			out->x[s] = (float)((f0->top - f0->black) / f0->tg);
			out->var[s] = 0;
			out->valid[s] = 0;
			rep->invalid_sites++;
			continue;
		}
		out->x[s] = (float)xhat;
		out->var[s] = (float)var;
		out->valid[s] = 1;
		if (xhat < 3 * sqrt(var))
			rep->dark_sites++;
		motion_check(j->f, j->n, s, xhat, rep);
	}
}

static int by_value(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

int glint_noise_from_bracket(const struct glint_frame *frames, int n,
			     struct glint_noise_model *m, long *used)
{
	const struct glint_frame **f = malloc((size_t)n * sizeof(*f));
	int ret = check_frames(frames, n);

	*used = 0;
	if (!f || ret < 0) {
		free(f);
		return ret < 0 ? ret : glint_error_set(ENOMEM, "out of memory");
	}
	for (int i = 0; i < n; i++)
		f[i] = &frames[i];
	qsort(f, (size_t)n, sizeof(*f), by_exposure);
	size_t ns =
		(size_t)frames[0].width * frames[0].height * frames[0].channels;
	/* At most about 4 M samples over all pairs. */
	size_t step = ns * (size_t)(n > 1 ? n - 1 : 1) / 4000000 + 1;
	/* Linear RGB frames (a converter's output) keep one list per
	 * channel: its colour matrix gives the channels different noise. */
	int nc = frames[0].channels;
	if (nc > 1 && step % (size_t)nc)
		step += (size_t)nc - step % (size_t)nc;
	size_t cap = (ns / step + 1) * (size_t)(n > 1 ? n - 1 : 1),
	       k[3] = { 0 };
	float *q = malloc(cap * (size_t)nc * sizeof(float));
	if (!q) {
		free(f);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int i = 0; i + 1 < n; i++) {
		const struct glint_frame *a = f[i], *b = f[i + 1];
		double ra = glint_frame_white_dn(a) - a->black_level,
		       rb = glint_frame_white_dn(b) - b->black_level;
		double r =
			(b->exposure_s * b->gain) / (a->exposure_s * a->gain);
		for (size_t s0 = 0; s0 < ns; s0 += step)
			for (int c = 0; c < nc; c++) {
				size_t s = s0 + (size_t)c;
				double da = a->data[s] - a->black_level,
				       db = b->data[s] - b->black_level;
				if (da < 0.05 * ra || da > 0.8 * ra ||
				    db < 0.05 * rb || db > 0.8 * rb)
					continue;
				double diff = db - r * da;
				q[cap * (size_t)c + k[c]++] =
					(float)(diff * diff /
						(b->gain * db +
						 r * r * a->gain * da));
			}
	}
	free(f);
	/* diff^2 / its variance per unit c is chi-square with one degree of
	 * freedom: its median is 0.45494 c.  Of several channels, the
	 * noisiest (its variance is not understated). */
	double best = 0;
	long total = 0;
	for (int c = 0; c < nc; c++) {
		if (k[c] < 1000)
			continue;
		float *qc = q + cap * (size_t)c;
		qsort(qc, k[c], sizeof(*qc), by_value);
		double est = qc[k[c] / 2] / 0.454936;
		best = est > best ? est : best;
		total += (long)k[c];
	}
	if (best > 0) {
		m->dn_per_electron = best;
		*used = total;
	}
	free(q);
	return 0;
}

int glint_hdr_merge_raw(const struct glint_frame *frames, int n,
			const struct glint_noise_model *noise,
			struct glint_raw_hdr *out, struct glint_hdr_report *rep)
{
	const struct glint_frame **f;
	struct merge_frame *mf;
	struct glint_hdr_report local, *part;
	int nthreads = glint_cpu_count();
	int ret = check_frames(frames, n);

	memset(out, 0, sizeof(*out));
	if (!rep)
		rep = &local;
	memset(rep, 0, sizeof(*rep));
	if (ret < 0)
		return ret;
	size_t ns =
		(size_t)frames[0].width * frames[0].channels * frames[0].height;
	f = malloc((size_t)n * sizeof(*f));
	mf = malloc((size_t)n * sizeof(*mf));
	part = calloc((size_t)nthreads, sizeof(*part));
	out->x = malloc(ns * sizeof(float));
	out->var = malloc(ns * sizeof(float));
	out->valid = malloc(ns);
	if (!f || !mf || !part || !out->x || !out->var || !out->valid) {
		free(f);
		free(mf);
		free(part);
		glint_raw_hdr_release(out);
		return glint_error_set(ENOMEM, "HDR merge: out of memory");
	}
	for (int i = 0; i < n; i++)
		f[i] = &frames[i];
	qsort(f, (size_t)n, sizeof(*f), by_exposure);
	out->width = frames[0].width;
	out->height = frames[0].height;
	snprintf(out->format, sizeof(out->format), "%s", frames[0].format);

	for (int i = 0; i < n; i++)
		glint_merge_frame_init(&mf[i], f[i], noise);
	rep->frames = n;
	rep->sites = (long)ns;
	rep->pairs = n - 1 < 32 ? n - 1 : 32;
	for (int i = 0; i < rep->pairs; i++) {
		rep->pair_tg[i][0] = mf[i].tg;
		rep->pair_tg[i][1] = mf[i + 1].tg;
	}
	/* Rows to every thread; each counts into its own report (sums of
	 * whole numbers: the same totals in any order). */
	struct merge_job job = { mf, n, frames[0].width * frames[0].channels,
				 out, part };
	glint_parallel_for(frames[0].height, 8, nthreads, merge_rows, &job);
	for (int t = 0; t < nthreads; t++) {
		rep->invalid_sites += part[t].invalid_sites;
		rep->dark_sites += part[t].dark_sites;
		for (int i = 0; i < rep->pairs; i++) {
			rep->compared[i] += part[t].compared[i];
			rep->disagree[i] += part[t].disagree[i];
		}
	}
	double shortest_tg = mf[0].tg;
	free(f);
	free(mf);
	free(part);
	return glint_hdr_report_finish(rep, out, shortest_tg);
}

int glint_hdr_report_finish(struct glint_hdr_report *rep,
			    struct glint_raw_hdr *out, double shortest_tg)
{
	for (int i = 0; i < rep->pairs; i++) {
		if (rep->compared[i])
			rep->disagree[i] /= (double)rep->compared[i];
		if (rep->compared[i] > 100 && rep->disagree[i] > 0.01)
			rep->moved = 1;
	}
	if (rep->invalid_sites == rep->sites) {
		glint_raw_hdr_release(out);
		return glint_error_set(ERANGE,
				       "HDR merge: every frame is clipped "
				       "everywhere (shortest exposure x gain "
				       "%g s): nothing to merge",
				       shortest_tg);
	}
	if (rep->dark_sites + rep->invalid_sites == rep->sites) {
		glint_raw_hdr_release(out);
		return glint_error_set(ERANGE,
				       "HDR merge: every frame is black (no "
				       "site 3 sigma above the read noise): "
				       "nothing to merge");
	}
	int ret = glint_hdr_report_check_moved(rep, "HDR merge");
	if (ret < 0)
		glint_raw_hdr_release(out);
	return ret;
}

int glint_hdr_report_check_moved(const struct glint_hdr_report *rep,
				 const char *what)
{
	int worst = -1;

	if (!rep->moved)
		return 0;
	for (int i = 0; i < rep->pairs; i++)
		if (rep->compared[i] > 100 &&
		    (worst < 0 || rep->disagree[i] > rep->disagree[worst]))
			worst = i;
	if (worst < 0)
		return 0;
	return glint_error_set(
		EINVAL,
		"%s: the frames at %.4g s and %.4g s (exposure x gain) "
		"disagree beyond their noise on %.1f %% of the %ld sites both "
		"expose well (a still bracket: under 1 %%): frames of another "
		"scene among the bracket, or the rig or the scene moved; "
		"refused, nothing merged",
		what, rep->pair_tg[worst][0], rep->pair_tg[worst][1],
		100 * rep->disagree[worst], rep->compared[worst]);
}

/* Colour (0 R, 1 G, 2 B) of the 2x2 cell's sites, -1 each for mono. */
static void cfa_cell(const char *format, int colour[4])
{
	for (int i = 0; i < 4; i++) {
		char c = format[i];
		colour[i] = !strncmp(format, "MONO", 4) ? -1
			    : c == 'R'			? 0
			    : c == 'G'			? 1
							: 2;
	}
}

/* Per cell position (y & 1) * 2 + (x & 1) and output channel, the sites
 * whose mean it is: the site itself for its own colour (and for mono), else
 * the sites of that colour in its 3x3 neighbourhood, row by row. */
struct demosaic_job {
	const struct glint_raw_hdr *raw;
	int ntap[4][3];
	signed char dx[4][3][9], dy[4][3][9];
	struct glint_image *r, *v, *m;
};

static void demosaic_taps(struct demosaic_job *j, const int colour[4])
{
	for (int cell = 0; cell < 4; cell++) {
		int own = colour[cell], cy = cell >> 1, cx = cell & 1;
		for (int c = 0; c < 3; c++) {
			int radius = own == c || own < 0 ? 0 : 1, n = 0;
			for (int dy = -radius; dy <= radius; dy++)
				for (int dx = -radius; dx <= radius; dx++) {
					int cc = colour[((cy + dy) & 1) * 2 +
							((cx + dx) & 1)];
					if (cc >= 0 && cc != c)
						continue;
					j->dx[cell][c][n] = (signed char)dx;
					j->dy[cell][c][n++] = (signed char)dy;
				}
			j->ntap[cell][c] = n;
		}
	}
}

static void demosaic_rows(void *ctx, int begin, int end, int thread)
{
	const struct demosaic_job *j = ctx;
	const struct glint_raw_hdr *raw = j->raw;
	int w = raw->width, h = raw->height;
	(void)thread;

	for (int y = begin; y < end; y++)
		for (int x = 0; x < w; x++) {
			float *pr = glint_image_px(j->r, x, y),
			      *pv = glint_image_px(j->v, x, y),
			      *pm = glint_image_px(j->m, x, y);
			int ok = 1, cell = (y & 1) * 2 + (x & 1);
			int inside = x > 0 && y > 0 && x < w - 1 && y < h - 1;
			size_t site = (size_t)y * w + x;
			for (int c = 0; c < 3; c++) {
				const signed char *tx = j->dx[cell][c],
						  *ty = j->dy[cell][c];
				double sx = 0, sv = 0;
				int k = 0;
				for (int t = 0; t < j->ntap[cell][c]; t++) {
					int xx = x + tx[t], yy = y + ty[t];
					if (!inside && (xx < 0 || yy < 0 ||
							xx >= w || yy >= h))
						continue;
					size_t s = (size_t)yy * w + xx;
					if (!raw->valid[s])
						continue;
					sx += raw->x[s];
					sv += raw->var[s];
					k++;
				}
				if (k == 0) {
					ok = 0;
					/* Best available: the site itself. */
					pr[c] = raw->x[site];
					pv[c] = 0;
					continue;
				}
				pr[c] = (float)(sx / k);
				pv[c] = (float)(sv / ((double)k * k));
			}
			if (!ok)
				pv[0] = pv[1] = pv[2] = 0;
			pm[0] = pm[1] = pm[2] = (float)ok;
		}
}

/* Three samples per pixel (a linear RGB frame): nothing to interpolate;
 * a pixel is valid where all three are. */
static void rgb_rows(void *ctx, int begin, int end, int thread)
{
	const struct demosaic_job *j = ctx;
	const struct glint_raw_hdr *raw = j->raw;
	(void)thread;

	for (size_t p = (size_t)begin * raw->width;
	     p < (size_t)end * raw->width; p++) {
		int ok = raw->valid[3 * p] && raw->valid[3 * p + 1] &&
			 raw->valid[3 * p + 2];
		for (int c = 0; c < 3; c++) {
			j->r->data[3 * p + c] = raw->x[3 * p + c];
			j->v->data[3 * p + c] = ok ? raw->var[3 * p + c] : 0;
			j->m->data[3 * p + c] = (float)ok;
		}
	}
}

int glint_hdr_demosaic(const struct glint_raw_hdr *raw,
		       struct glint_image **radiance,
		       struct glint_image **variance,
		       struct glint_image **valid)
{
	int w = raw->width, h = raw->height;
	const char *fmt = raw->format;
	int rgb = !strcmp(fmt, "RGB16");

	*radiance = *variance = *valid = NULL;
	if (strcmp(fmt, "RGGB16") && strcmp(fmt, "GRBG16") &&
	    strcmp(fmt, "GBRG16") && strcmp(fmt, "BGGR16") &&
	    strcmp(fmt, "MONO16") && !rgb)
		return glint_error_set(EINVAL,
				       "demosaic: layout '%s': expected "
				       "RGGB16, GRBG16, GBRG16, BGGR16, "
				       "MONO16 or RGB16",
				       fmt);
	struct demosaic_job job = { raw,
				    { { 0 } },
				    { { { 0 } } },
				    { { { 0 } } },
				    glint_image_new(w, h),
				    glint_image_new(w, h),
				    glint_image_new(w, h) };
	if (!job.r || !job.v || !job.m) {
		glint_image_free(job.r);
		glint_image_free(job.v);
		glint_image_free(job.m);
		return glint_error_set(ENOMEM, "demosaic: out of memory");
	}
	if (rgb) {
		glint_parallel_for(h, 8, glint_cpu_count(), rgb_rows, &job);
	} else {
		int colour[4];
		cfa_cell(fmt, colour);
		demosaic_taps(&job, colour);
		/* Rows to every thread: each output pixel reads only the
		 * sites. */
		glint_parallel_for(h, 8, glint_cpu_count(), demosaic_rows,
				   &job);
	}
	*radiance = job.r;
	*variance = job.v;
	*valid = job.m;
	return 0;
}
