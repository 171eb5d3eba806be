/* SPDX-License-Identifier: MIT */
/*
 * Primary rays into G-buffers (tracer.h): each pixel's pattern of
 * samples, traced in packets of 16, kept dense or for chosen pixels.
 */
#include "tracer.h"
#include "tracer_internal.h"

#include "sampling.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/*
 * Primary sample s of pixel (x, y): point s of a Hammersley set of spp
 * points, toroidally shifted per pixel; the lens uses a differently
 * shuffled set (index s * 2654435761 mod spp, rotated per pixel) so that
 * lens and pixel positions are not correlated.
 */
struct pixel_pattern {
	int spp;
	double (*base)[2]; /* Hammersley points */
	int *perm;	   /* lens index shuffle */
	/* the camera's blur as a pixel filter (core/pinhole.h) */
	int filtered;
	float filter[GLINT_PIXEL_FILTER_N + 1];
};

static int pattern_init(struct pixel_pattern *pp, int spp)
{
	pp->spp = spp;
	pp->base = malloc((size_t)spp * sizeof(*pp->base));
	pp->perm = malloc((size_t)spp * sizeof(*pp->perm));
	if (!pp->base || !pp->perm) {
		free(pp->base);
		free(pp->perm);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int k = 0; k < spp; k++) {
		pp->base[k][0] = (k + 0.5) / spp;
		pp->base[k][1] = glint_radical2((uint32_t)k);
		pp->perm[k] = (int)((uint32_t)k * 2654435761u % (uint32_t)spp);
	}
	return 0;
}

static void pattern_free(struct pixel_pattern *pp)
{
	free(pp->base);
	free(pp->perm);
}

struct pixel_shift {
	double pix[2], lens[2];
	int rot;
};

static void pixel_shift(int x, int y, int spp, struct pixel_shift *ps)
{
	uint32_t seed = glint_hash3((uint32_t)x, (uint32_t)y, 0x51u);
	uint32_t lseed = seed ^ 0xa511e9b3u;

	ps->pix[0] = glint_u01(glint_hash32(seed));
	ps->pix[1] = glint_u01(glint_hash32(seed ^ 0x9e3779b9U));
	ps->lens[0] = glint_u01(glint_hash32(lseed));
	ps->lens[1] = glint_u01(glint_hash32(lseed ^ 0x9e3779b9U));
	ps->rot = (int)(glint_hash32(seed) % (uint32_t)spp);
}

static inline double frac(double v)
{
	return v >= 1 ? v - 1 : v;
}

static void pattern_sample(const struct pixel_pattern *pp,
			   const struct pixel_shift *ps, int s, double pix[2],
			   double lens[2])
{
	int k = pp->perm[s] + ps->rot;

	k = k >= pp->spp ? k - pp->spp : k;
	pix[0] = frac(pp->base[s][0] + ps->pix[0]);
	pix[1] = frac(pp->base[s][1] + ps->pix[1]);
	lens[0] = frac(pp->base[k][0] + ps->lens[0]);
	lens[1] = frac(pp->base[k][1] + ps->lens[1]);
	if (pp->filtered) {
		pix[0] = glint_pixel_filter_map(pp->filter, pix[0]);
		pix[1] = glint_pixel_filter_map(pp->filter, pix[1]);
	}
}

void glint_pixel_sample(int x, int y, int s, int spp, double pix[2],
			double lens[2])
{
	struct pixel_shift ps;
	uint32_t k = (uint32_t)s * 2654435761u % (uint32_t)spp;

	pixel_shift(x, y, spp, &ps);
	k = (k + (uint32_t)ps.rot) % (uint32_t)spp;
	pix[0] = frac((s + 0.5) / spp + ps.pix[0]);
	pix[1] = frac(glint_radical2((uint32_t)s) + ps.pix[1]);
	lens[0] = frac((k + 0.5) / spp + ps.lens[0]);
	lens[1] = frac(glint_radical2(k) + ps.lens[1]);
}

static void store_hit(const struct RTCRayHit16 *rh, int k, struct glint_hit *h)
{
	double o[3] = { rh->ray.org_x[k], rh->ray.org_y[k], rh->ray.org_z[k] };
	double d[3] = { rh->ray.dir_x[k], rh->ray.dir_y[k], rh->ray.dir_z[k] };
	unsigned g = rh->hit.geomID[k];

	for (int c = 0; c < 3; c++)
		h->d[c] = (float)d[c];
	if (g == RTC_INVALID_GEOMETRY_ID) {
		h->geom = -1;
		return;
	}
	/* The sphere callback solved in double; t and Ng come back as float
	 * (relative error 6e-8: 3e-8 m at the demo's 0.5 m). */
	double n[3] = { rh->hit.Ng_x[k], rh->hit.Ng_y[k], rh->hit.Ng_z[k] };
	double p[3], len;
	for (int c = 0; c < 3; c++)
		p[c] = o[c] + rh->ray.tfar[k] * d[c];
	len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0)
		len = -len;
	for (int c = 0; c < 3; c++) {
		h->p[c] = (float)p[c];
		h->n[c] = (float)(n[c] / len);
	}
	h->geom = (int32_t)g;
}

static void flush_packet(struct glint_tracer *t, struct RTCRayHit16 *rh,
			 int *valid, int count, struct glint_hit **dst)
{
	struct RTCIntersectContext ctx;

	rtcInitIntersectContext(&ctx);
	ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
	for (int k = count; k < 16; k++)
		valid[k] = 0;
	rtcIntersect16(valid, t->scene, &ctx, rh);
	for (int k = 0; k < count; k++)
		store_hit(rh, k, dst[k]);
}

/* What re-traces a sparse G-buffer's pixels: the tracer (borrowed), the
 * camera and the pattern. */
struct glint_gbuffer_src {
	struct glint_tracer *t;
	struct glint_pinhole cam;
	struct pixel_pattern pattern;
};

/* Rays gathered into a packet of 16, their hits written through dst. */
struct packet {
	_Alignas(64) struct RTCRayHit16 rh;
	_Alignas(64) int valid[16];
	struct glint_hit *dst[16];
	int count;
};

static void packet_flush(struct glint_tracer *t, struct packet *pk)
{
	if (pk->count)
		flush_packet(t, &pk->rh, pk->valid, pk->count, pk->dst);
	pk->count = 0;
}

/* Pixel (x, y)'s spp samples into out[0 .. spp). */
static void trace_pixel(const struct glint_gbuffer *gb, struct packet *pk,
			int x, int y, struct glint_hit *out)
{
	const struct glint_gbuffer_src *src = gb->src;
	struct pixel_shift ps;

	pixel_shift(x + gb->frame_x, y + gb->frame_y, gb->spp, &ps);
	for (int s = 0; s < gb->spp; s++) {
		double pix[2], lens[2];
		struct vec3 o, d;
		pattern_sample(&src->pattern, &ps, s, pix, lens);
		glint_pinhole_ray(&src->cam, x + pix[0], y + pix[1], lens[0],
				  lens[1], &o, &d);
		tracer_set_lane(&pk->rh, pk->count, o, d);
		pk->valid[pk->count] = -1;
		pk->dst[pk->count] = &out[s];
		if (++pk->count == 16)
			packet_flush(src->t, pk);
	}
}

static void count_cover(struct glint_gbuffer *gb, int y,
			const struct glint_hit *row)
{
	for (int x = 0; x < gb->width; x++) {
		int n = 0;
		for (int s = 0; s < gb->spp; s++)
			n += row[(size_t)x * gb->spp + s].geom >= 0;
		gb->cover[(size_t)y * gb->width + x] = (uint16_t)n;
	}
}

struct primary_job {
	struct glint_gbuffer *gb;
	struct glint_progress *progress;
	int failed;
};

static void primary_rows(void *ctx, int y0, int y1, int thread)
{
	struct primary_job *job = ctx;
	struct glint_gbuffer *gb = job->gb;
	size_t row = (size_t)gb->width * gb->spp;
	struct glint_hit *buf = NULL;
	struct packet pk;

	(void)thread;
	glint_thread_ftz();
	pk.count = 0;
	if (!gb->hits && !(buf = malloc(row * sizeof(*buf)))) {
		job->failed = 1;
		return;
	}
	for (int y = y0; y < y1; y++) {
		struct glint_hit *dst = buf ? buf : gb->hits + (size_t)y * row;
		for (int x = 0; x < gb->width; x++)
			trace_pixel(gb, &pk, x, y, dst + (size_t)x * gb->spp);
		if (buf) { /* sparse: the row is counted, then dropped */
			packet_flush(gb->src->t, &pk);
			count_cover(gb, y, buf);
		}
		if (job->progress)
			glint_progress_add(job->progress, 1);
	}
	packet_flush(gb->src->t, &pk);
	for (int y = y0; !buf && y < y1; y++)
		count_cover(gb, y, gb->hits + (size_t)y * row);
	free(buf);
}

static int gbuffer_begin(struct glint_tracer *t,
			 const struct glint_pinhole *cam, int spp,
			 struct glint_gbuffer *gb)
{
	memset(gb, 0, sizeof(*gb));
	if (!t->committed)
		return glint_error_set(EINVAL, "tracer used before commit");
	if (spp < 1 || spp > 4096)
		return glint_error_set(
			EINVAL, "samples per pixel %d: expected 1..4096", spp);
	gb->width = cam->width;
	gb->height = cam->height;
	gb->spp = spp;
	gb->frame_x = cam->frame_x;
	gb->frame_y = cam->frame_y;
	gb->frame_width = cam->frame_width;
	memcpy(gb->cfa, cam->cfa, sizeof(gb->cfa));
	gb->src = calloc(1, sizeof(*gb->src));
	gb->cover =
		malloc((size_t)cam->width * cam->height * sizeof(*gb->cover));
	if (!gb->src || !gb->cover ||
	    pattern_init(&gb->src->pattern, spp) < 0) {
		free(gb->src);
		free(gb->cover);
		memset(gb, 0, sizeof(*gb));
		return glint_error_set(ENOMEM,
				       "out of memory for a %dx%d G-buffer",
				       cam->width, cam->height);
	}
	gb->src->t = t;
	gb->src->cam = *cam;
	gb->src->pattern.filtered = glint_pixel_filter_on(cam);
	if (gb->src->pattern.filtered)
		glint_pixel_filter_table(cam, gb->src->pattern.filter);
	return 0;
}

const float *glint_gbuffer_filter(const struct glint_gbuffer *gb)
{
	return gb->src && gb->src->pattern.filtered ? gb->src->pattern.filter
						    : NULL;
}

void glint_gbuffer_pixel_sample(const struct glint_gbuffer *gb, int x, int y,
				int s, double pix[2], double lens[2])
{
	struct pixel_shift ps;
	pixel_shift(x, y, gb->spp, &ps);
	pattern_sample(&gb->src->pattern, &ps, s, pix, lens);
}

static int gbuffer_trace(struct glint_gbuffer *gb, int nthreads,
			 struct glint_progress *progress)
{
	struct primary_job job = { gb, progress, 0 };

	glint_parallel_for(gb->height, 2, nthreads, primary_rows, &job);
	if (job.failed) {
		glint_gbuffer_free(gb);
		return glint_error_set(ENOMEM, "out of memory tracing a row");
	}
	return 0;
}

int glint_tracer_primary(struct glint_tracer *t,
			 const struct glint_pinhole *cam, int spp, int nthreads,
			 struct glint_progress *progress,
			 struct glint_gbuffer *gb)
{
	int ret = gbuffer_begin(t, cam, spp, gb);

	if (ret < 0)
		return ret;
	gb->hits = malloc((size_t)cam->width * cam->height * spp *
			  sizeof(*gb->hits));
	if (!gb->hits) {
		glint_gbuffer_free(gb);
		return glint_error_set(ENOMEM,
				       "out of memory for %dx%d x %d samples",
				       cam->width, cam->height, spp);
	}
	return gbuffer_trace(gb, nthreads, progress);
}

int glint_tracer_primary_sparse(struct glint_tracer *t,
				const struct glint_pinhole *cam, int spp,
				int nthreads, struct glint_progress *progress,
				struct glint_gbuffer *gb)
{
	int ret = gbuffer_begin(t, cam, spp, gb);
	size_t n = (size_t)cam->width * cam->height;

	if (ret < 0)
		return ret;
	gb->slot = malloc(n * sizeof(*gb->slot));
	if (!gb->slot) {
		glint_gbuffer_free(gb);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (size_t i = 0; i < n; i++)
		gb->slot[i] = -1;
	return gbuffer_trace(gb, nthreads, progress);
}

struct keep_job {
	struct glint_gbuffer *gb;
	const int32_t *pix; /* the pixels to trace, slots assigned */
};

static void keep_pixels(void *ctx, int lo, int hi, int thread)
{
	struct keep_job *job = ctx;
	struct glint_gbuffer *gb = job->gb;
	struct packet pk;

	(void)thread;
	glint_thread_ftz();
	pk.count = 0;
	for (int k = lo; k < hi; k++) {
		int32_t i = job->pix[k];
		trace_pixel(gb, &pk, i % gb->width, i / gb->width,
			    gb->stored + (size_t)gb->slot[i] * gb->spp);
	}
	packet_flush(gb->src->t, &pk);
}

int glint_gbuffer_keep(struct glint_gbuffer *gb, const int32_t *pix, int n,
		       int nthreads)
{
	if (gb->hits)
		return 0;
	int32_t *todo = malloc((size_t)(n ? n : 1) * sizeof(*todo));
	int m = 0;
	if (!todo)
		return glint_error_set(ENOMEM, "out of memory");
	for (int k = 0; k < n; k++)
		if (gb->slot[pix[k]] < 0) {
			gb->slot[pix[k]] = gb->nstored + m;
			todo[m++] = pix[k];
		}
	if (m) {
		size_t want = (size_t)(gb->nstored + m) * gb->spp;
		struct glint_hit *st =
			realloc(gb->stored, want * sizeof(*gb->stored));
		if (!st) {
			for (int k = 0; k < m; k++)
				gb->slot[todo[k]] = -1;
			free(todo);
			return glint_error_set(ENOMEM, "out of memory");
		}
		gb->stored = st;
		gb->nstored += m;
		struct keep_job job = { gb, todo };
		glint_parallel_for(m, 256, nthreads, keep_pixels, &job);
	}
	free(todo);
	return 0;
}

const struct glint_hit *glint_gbuffer_row(const struct glint_gbuffer *gb, int y,
					  struct glint_hit *buf)
{
	if (gb->hits)
		return gb->hits + (size_t)y * gb->width * gb->spp;
	struct packet pk;
	pk.count = 0;
	for (int x = 0; x < gb->width; x++)
		trace_pixel(gb, &pk, x, y, buf + (size_t)x * gb->spp);
	packet_flush(gb->src->t, &pk);
	return buf;
}

double glint_gbuffer_dense_mb(void)
{
	const char *e = getenv("GLINT_GBUFFER_MB");
	char *end;
	double v = e ? strtod(e, &end) : NAN;
	return e && end != e && !*end && v >= 0 ? v : 256;
}

void glint_gbuffer_free(struct glint_gbuffer *gb)
{
	free(gb->hits);
	free(gb->cover);
	free(gb->slot);
	free(gb->stored);
	if (gb->src)
		pattern_free(&gb->src->pattern);
	free(gb->src);
	memset(gb, 0, sizeof(*gb));
}
