/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_TRACER_H
#define GLINT_FIT_RENDER_TRACER_H

/*
 * The sample's geometry in an Embree scene, and the primary-ray pass that
 * fills a G-buffer once per fit (the geometry never changes while a fit
 * re-shades).  Build: _new, _add_*, _commit; then trace.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (Embree's own errors included).  Threads: a tracer
 * is built by one thread; once committed its queries are safe from many
 * (call glint_thread_ftz() once per thread).  Who frees:
 * glint_tracer_free(), glint_gbuffer_free().
 */

#include "core/pinhole.h"

#include "core/log.h"

#include <stddef.h>
#include <stdint.h>

struct glint_tracer;

/* How a sphere is given to Embree (bench/render measures both). */
enum glint_sphere_kind {
	GLINT_SPHERE_USER,  /* user geometry, analytic double-precision hit */
	GLINT_SPHERE_POINT, /* RTC_GEOMETRY_TYPE_SPHERE_POINT */
};

/* An empty Embree scene on its own device: *out is the caller's, freed
 * with glint_tracer_free(). */
int glint_tracer_new(struct glint_tracer **out);
void glint_tracer_free(struct glint_tracer *t);
int glint_tracer_add_sphere(struct glint_tracer *t, struct vec3 centre,
			    double radius, enum glint_sphere_kind kind);
/* Triangle mesh: nv float triples, nt index triples (copied). */
int glint_tracer_add_mesh(struct glint_tracer *t, const float *verts, int nv,
			  const uint32_t *tris, int nt);
int glint_tracer_commit(struct glint_tracer *t);
/* 1 when the scene is one sphere: nothing can shadow a lit hemisphere. */
int glint_tracer_is_convex(const struct glint_tracer *t);

/* One primary-ray sample. */
struct glint_hit {
	float p[3];   /* hit point (world, m) */
	float n[3];   /* unit shading normal, facing the ray */
	float d[3];   /* unit ray direction */
	int32_t geom; /* geometry id, -1 for a miss */
};

/*
 * Per-pixel stratified samples of a camera: width * height * spp hits.
 * Dense, every pixel's hits are held (`hits`); sparse, only the pixels
 * asked for with glint_gbuffer_keep() are (`slot`, `stored`: 40 bytes a
 * sample is 2 GB for a 12 MP frame at 4 samples), and a row is traced
 * again when it is read (glint_gbuffer_row()).  Either way `cover` holds
 * each pixel's count of samples that hit, and a pixel's samples are the
 * same (the same rays, traced the same way).
 */
struct glint_gbuffer {
	int width, height, spp;
	struct glint_hit *hits; /* dense: [(y * width + x) * spp + s] */
	int frame_x, frame_y, frame_width; /* the camera's (pinhole.h) */
	signed char cfa[4];		   /* the camera's (pinhole.h) */
	uint16_t *cover;		   /* [y * width + x]: hits of spp */
	int32_t *slot;		  /* sparse: pixel's row of stored, or -1 */
	struct glint_hit *stored; /* sparse: [slot * spp + s] */
	int nstored;
	struct glint_gbuffer_src *src; /* what traces it (tracer.c) */
};

/* Pixel i's index in the whole frame (glint_pinhole's window), which
 * seeds its samples. */
static inline uint32_t glint_gbuffer_frame_pixel(const struct glint_gbuffer *gb,
						 size_t i)
{
	if (!gb->frame_width)
		return (uint32_t)i;
	size_t y = i / (size_t)gb->width, x = i % (size_t)gb->width;
	return (uint32_t)((y + (size_t)gb->frame_y) * (size_t)gb->frame_width +
			  x + (size_t)gb->frame_x);
}

/* Pixel i's spp hits, or NULL when a sparse G-buffer does not hold them
 * (glint_gbuffer_keep()). */
static inline const struct glint_hit *
glint_gbuffer_pixel(const struct glint_gbuffer *gb, size_t i)
{
	if (gb->hits)
		return gb->hits + i * (size_t)gb->spp;
	if (!gb->slot || gb->slot[i] < 0)
		return NULL;
	return gb->stored + (size_t)gb->slot[i] * (size_t)gb->spp;
}

/*
 * Trace spp deterministic stratified sub-pixel samples per pixel (and lens
 * samples for a thin lens) with rtcIntersect16 packets on nthreads threads
 * (0 = all CPUs).  progress may be NULL.  Free with glint_gbuffer_free();
 * the tracer must outlive the G-buffer.  _sparse keeps only `cover`.
 */
int glint_tracer_primary(struct glint_tracer *t,
			 const struct glint_pinhole *cam, int spp, int nthreads,
			 struct glint_progress *progress,
			 struct glint_gbuffer *gb);
int glint_tracer_primary_sparse(struct glint_tracer *t,
				const struct glint_pinhole *cam, int spp,
				int nthreads, struct glint_progress *progress,
				struct glint_gbuffer *gb);
/* The largest dense G-buffer a renderer makes, in MiB: GLINT_GBUFFER_MB
 * in the environment, default 256 (a 1.6 MP window at 4 samples);
 * above it the renderer's G-buffer is sparse (render.h). */
double glint_gbuffer_dense_mb(void);

/* Hold pixels pix[0 .. n) of a sparse G-buffer (traced now); nothing to
 * do for a dense one. */
int glint_gbuffer_keep(struct glint_gbuffer *gb, const int32_t *pix, int n,
		       int nthreads);
/* Row y's width * spp hits: the dense G-buffer's own, or traced into buf
 * (width * spp hits, the caller's).  Safe from several threads. */
const struct glint_hit *glint_gbuffer_row(const struct glint_gbuffer *gb, int y,
					  struct glint_hit *buf);
void glint_gbuffer_free(struct glint_gbuffer *gb);

/* Nearest hit of one ray beyond tnear: its geometry id (-1 for none),
 * distance and unit geometric normal (outward for the sphere; not flipped
 * towards the ray).  For secondary rays, e.g. inside a transparent
 * sphere; call glint_thread_ftz() once per thread first. */
int glint_tracer_intersect1(struct glint_tracer *t, struct vec3 org,
			    struct vec3 dir, double tnear, double *thit,
			    struct vec3 *ng);

/* 1 when the segment org + t dir, t in (tnear, tfar), hits anything. */
int glint_tracer_occluded(struct glint_tracer *t, struct vec3 org,
			  struct vec3 dir, double tnear, double tfar);

/*
 * Raw throughput for benchmarks: intersect n rays given as interleaved
 * origin/direction float sextuples with rtcIntersect16 (packet = 1) or
 * rtcIntersect1 (packet = 0), writing geometry ids (or -1) to hit_geom.
 * Single-threaded, no G-buffer work.
 */
void glint_tracer_intersect_raw(struct glint_tracer *t, const float *rays,
				int n, int32_t *hit_geom, int packet);

/* The stratified sample position s of spp in pixel (x, y): offsets in
 * [0, 1)^2 for the pixel and for the lens; deterministic. */
void glint_pixel_sample(int x, int y, int s, int spp, double pix[2],
			double lens[2]);

/* Where gb's tracer put sample s of frame pixel (x, y): the position
 * above mapped through the camera's pixel filter (core/pinhole.h), in
 * pixels from the pixel's corner (outside [0, 1) when the camera
 * blurs). */
void glint_gbuffer_pixel_sample(const struct glint_gbuffer *gb, int x, int y,
				int s, double pix[2], double lens[2]);

/* gb's camera's pixel filter table (core/pinhole.h), NULL without one;
 * it lives as long as gb. */
const float *glint_gbuffer_filter(const struct glint_gbuffer *gb);

#endif
