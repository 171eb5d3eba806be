/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_TRACER_H
#define GLINT_FIT_RENDER_TRACER_H

/*
 * The sample's geometry in an Embree scene, and the primary-ray pass that
 * fills a G-buffer once per fit (the geometry never changes while a fit
 * re-shades).  Build: _new, _add_*, _commit; then trace.
 */

#include "fit/scene/pinhole.h"

#include "core/log.h"

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

/* Per-pixel stratified samples of a camera: width * height * spp hits. */
struct glint_gbuffer {
	int width, height, spp;
	struct glint_hit *hits; /* [(y * width + x) * spp + s] */
};

/*
 * Trace spp deterministic stratified sub-pixel samples per pixel (and lens
 * samples for a thin lens) with rtcIntersect16 packets on nthreads threads
 * (0 = all CPUs).  progress may be NULL.  Free with glint_gbuffer_free().
 */
int glint_tracer_primary(struct glint_tracer *t,
			 const struct glint_pinhole *cam, int spp, int nthreads,
			 struct glint_progress *progress,
			 struct glint_gbuffer *gb);
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

#endif
