/* SPDX-License-Identifier: MIT */
/*
 * Embree 3 scene of the sample.  A sphere is user geometry by default: its
 * analytic hit in double precision is exact to sub-pixel level and, measured
 * on this machine (bench/render), faster than RTC_GEOMETRY_TYPE_SPHERE_POINT.
 */
#include "tracer.h"

#include "sampling.h"

#include "core/error.h"
#include "core/parallel.h"

#include <embree3/rtcore.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GLINT_MAX_GEOMS 64

struct sphere_geom {
	double c[3];
	double r;
};

struct glint_tracer {
	RTCDevice dev;
	RTCScene scene;
	int ngeom;
	int nsphere;
	struct sphere_geom *spheres[GLINT_MAX_GEOMS];
	int committed;
};

static void embree_error(void *user, enum RTCError code, const char *msg)
{
	(void)user;
	glint_error_set(EIO, "Embree error %d: %s", (int)code, msg);
}

int glint_tracer_new(struct glint_tracer **out)
{
	struct glint_tracer *t = calloc(1, sizeof(*t));

	*out = NULL;
	if (!t)
		return glint_error_set(ENOMEM, "out of memory");
	t->dev = rtcNewDevice(NULL);
	if (!t->dev) {
		free(t);
		return glint_error_set(EIO, "Embree: rtcNewDevice failed (%d)",
				       (int)rtcGetDeviceError(NULL));
	}
	rtcSetDeviceErrorFunction(t->dev, embree_error, NULL);
	t->scene = rtcNewScene(t->dev);
	rtcSetSceneBuildQuality(t->scene, RTC_BUILD_QUALITY_HIGH);
	*out = t;
	return 0;
}

void glint_tracer_free(struct glint_tracer *t)
{
	if (!t)
		return;
	rtcReleaseScene(t->scene);
	rtcReleaseDevice(t->dev);
	for (int i = 0; i < t->ngeom; i++)
		free(t->spheres[i]);
	free(t);
}

/*
 * Embree hands user geometry callbacks opaque RTCRayHitN / RTCRayN blocks
 * (the accessors are C++ only).  Layout, N lanes each: org x y z, tnear,
 * dir x y z, time, tfar, mask, id, flags; then the hit: Ng x y z, u, v,
 * primID, geomID, instID.
 */
enum {
	RAY_OX,
	RAY_OY,
	RAY_OZ,
	RAY_TNEAR,
	RAY_DX,
	RAY_DY,
	RAY_DZ,
	RAY_TIME,
	RAY_TFAR,
	RAY_MASK,
	RAY_ID,
	RAY_FLAGS,
	HIT_NX,
	HIT_NY,
	HIT_NZ,
	HIT_U,
	HIT_V,
	HIT_PRIM,
	HIT_GEOM,
	HIT_INST
};

static inline float *lane(void *base, unsigned n, int field, unsigned i)
{
	return (float *)base + (size_t)field * n + i;
}

/* Nearest t in (tnear, tfar) where the ray meets the sphere, or -1. */
static double sphere_hit(const struct sphere_geom *s, const double o[3],
			 const double d[3], double tnear, double tfar)
{
	double oc[3] = { o[0] - s->c[0], o[1] - s->c[1], o[2] - s->c[2] };
	double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
	double b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
	double cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - s->r * s->r;
	double disc = b * b - dd * cc;

	if (disc < 0)
		return -1;
	/* Stable roots: q = -(b + sign(b) sqrt(disc)). */
	double q = -(b + copysign(sqrt(disc), b));
	double t0 = q / dd, t1 = q != 0 ? cc / q : t0;
	if (t0 > t1) {
		double tmp = t0;
		t0 = t1;
		t1 = tmp;
	}
	if (t0 > tnear && t0 < tfar)
		return t0;
	if (t1 > tnear && t1 < tfar)
		return t1;
	return -1;
}

static void ray_lane(void *rh, unsigned n, unsigned i, double o[3], double d[3])
{
	o[0] = *lane(rh, n, RAY_OX, i);
	o[1] = *lane(rh, n, RAY_OY, i);
	o[2] = *lane(rh, n, RAY_OZ, i);
	d[0] = *lane(rh, n, RAY_DX, i);
	d[1] = *lane(rh, n, RAY_DY, i);
	d[2] = *lane(rh, n, RAY_DZ, i);
}

static void sphere_intersect(const struct RTCIntersectFunctionNArguments *a)
{
	const struct sphere_geom *s = a->geometryUserPtr;
	void *rh = a->rayhit;
	unsigned n = a->N;

	for (unsigned i = 0; i < n; i++) {
		double o[3], d[3];
		if (!a->valid[i])
			continue;
		ray_lane(rh, n, i, o, d);
		double t = sphere_hit(s, o, d, *lane(rh, n, RAY_TNEAR, i),
				      *lane(rh, n, RAY_TFAR, i));
		if (t < 0)
			continue;
		*lane(rh, n, RAY_TFAR, i) = (float)t;
		for (int k = 0; k < 3; k++)
			*lane(rh, n, HIT_NX + k, i) =
				(float)(o[k] + t * d[k] - s->c[k]);
		*lane(rh, n, HIT_U, i) = 0;
		*lane(rh, n, HIT_V, i) = 0;
		*(unsigned *)lane(rh, n, HIT_PRIM, i) = a->primID;
		*(unsigned *)lane(rh, n, HIT_GEOM, i) = a->geomID;
		*(unsigned *)lane(rh, n, HIT_INST, i) = a->context->instID[0];
	}
}

static void sphere_occluded(const struct RTCOccludedFunctionNArguments *a)
{
	const struct sphere_geom *s = a->geometryUserPtr;
	void *r = a->ray;
	unsigned n = a->N;

	for (unsigned i = 0; i < n; i++) {
		double o[3], d[3];
		if (!a->valid[i])
			continue;
		ray_lane(r, n, i, o, d);
		if (sphere_hit(s, o, d, *lane(r, n, RAY_TNEAR, i),
			       *lane(r, n, RAY_TFAR, i)) >= 0)
			*lane(r, n, RAY_TFAR, i) = -INFINITY;
	}
}

static void sphere_bounds(const struct RTCBoundsFunctionArguments *a)
{
	const struct sphere_geom *s = a->geometryUserPtr;
	struct RTCBounds *b = a->bounds_o;

	b->lower_x = (float)(s->c[0] - s->r) - 1e-6f;
	b->lower_y = (float)(s->c[1] - s->r) - 1e-6f;
	b->lower_z = (float)(s->c[2] - s->r) - 1e-6f;
	b->upper_x = (float)(s->c[0] + s->r) + 1e-6f;
	b->upper_y = (float)(s->c[1] + s->r) + 1e-6f;
	b->upper_z = (float)(s->c[2] + s->r) + 1e-6f;
}

static int attach(struct glint_tracer *t, RTCGeometry g)
{
	rtcCommitGeometry(g);
	rtcAttachGeometryByID(t->scene, g, (unsigned)t->ngeom);
	rtcReleaseGeometry(g);
	t->ngeom++;
	t->committed = 0;
	return 0;
}

int glint_tracer_add_sphere(struct glint_tracer *t, struct vec3 centre,
			    double radius, enum glint_sphere_kind kind)
{
	RTCGeometry g;

	if (t->ngeom >= GLINT_MAX_GEOMS)
		return glint_error_set(ENOSPC, "too many geometries (max %d)",
				       GLINT_MAX_GEOMS);
	if (!(radius > 0) || !isfinite(radius))
		return glint_error_set(EINVAL, "sphere radius %g: expected > 0",
				       radius);
	struct sphere_geom *s = malloc(sizeof(*s));
	if (!s)
		return glint_error_set(ENOMEM, "out of memory");
	s->c[0] = centre.x;
	s->c[1] = centre.y;
	s->c[2] = centre.z;
	s->r = radius;
	t->spheres[t->ngeom] = s;
	t->nsphere++;
	if (kind == GLINT_SPHERE_POINT) {
		g = rtcNewGeometry(t->dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
		float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
						   RTC_FORMAT_FLOAT4,
						   4 * sizeof(float), 1);
		v[0] = (float)centre.x;
		v[1] = (float)centre.y;
		v[2] = (float)centre.z;
		v[3] = (float)radius;
	} else {
		g = rtcNewGeometry(t->dev, RTC_GEOMETRY_TYPE_USER);
		rtcSetGeometryUserPrimitiveCount(g, 1);
		rtcSetGeometryUserData(g, s);
		rtcSetGeometryBoundsFunction(g, sphere_bounds, NULL);
		rtcSetGeometryIntersectFunction(g, sphere_intersect);
		rtcSetGeometryOccludedFunction(g, sphere_occluded);
	}
	return attach(t, g);
}

int glint_tracer_add_mesh(struct glint_tracer *t, const float *verts, int nv,
			  const uint32_t *tris, int nt)
{
	if (t->ngeom >= GLINT_MAX_GEOMS)
		return glint_error_set(ENOSPC, "too many geometries (max %d)",
				       GLINT_MAX_GEOMS);
	if (nv < 3 || nt < 1)
		return glint_error_set(
			EINVAL,
			"mesh with %d vertices and %d triangles: "
			"expected at least 3 and 1",
			nv, nt);
	for (int i = 0; i < 3 * nt; i++)
		if (tris[i] >= (uint32_t)nv)
			return glint_error_set(EINVAL,
					       "mesh triangle %d uses vertex "
					       "%u: expected < %d",
					       i / 3, tris[i], nv);
	RTCGeometry g = rtcNewGeometry(t->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
	float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
					   RTC_FORMAT_FLOAT3, 3 * sizeof(float),
					   (size_t)nv);
	uint32_t *ix = rtcSetNewGeometryBuffer(
		g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
		3 * sizeof(uint32_t), (size_t)nt);
	memcpy(v, verts, (size_t)nv * 3 * sizeof(float));
	memcpy(ix, tris, (size_t)nt * 3 * sizeof(uint32_t));
	t->spheres[t->ngeom] = NULL;
	return attach(t, g);
}

int glint_tracer_commit(struct glint_tracer *t)
{
	glint_error_clear();
	rtcCommitScene(t->scene);
	if (rtcGetDeviceError(t->dev) != RTC_ERROR_NONE)
		return glint_error_set(EIO, "Embree scene commit failed: %s",
				       glint_error_msg());
	t->committed = 1;
	return 0;
}

int glint_tracer_is_convex(const struct glint_tracer *t)
{
	return t->ngeom == 1 && t->nsphere == 1;
}

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

static void set_lane(struct RTCRayHit16 *rh, int k, struct vec3 o,
		     struct vec3 d)
{
	rh->ray.org_x[k] = (float)o.x;
	rh->ray.org_y[k] = (float)o.y;
	rh->ray.org_z[k] = (float)o.z;
	rh->ray.dir_x[k] = (float)d.x;
	rh->ray.dir_y[k] = (float)d.y;
	rh->ray.dir_z[k] = (float)d.z;
	rh->ray.tnear[k] = 0;
	rh->ray.tfar[k] = INFINITY;
	rh->ray.time[k] = 0;
	rh->ray.mask[k] = 0xffffffffu;
	rh->ray.id[k] = (unsigned)k;
	rh->ray.flags[k] = 0;
	rh->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
	rh->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
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
		set_lane(&pk->rh, pk->count, o, d);
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
	return 0;
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

int glint_tracer_occluded(struct glint_tracer *t, struct vec3 org,
			  struct vec3 dir, double tnear, double tfar)
{
	struct RTCIntersectContext ctx;
	struct RTCRay r = {
		.org_x = (float)org.x,
		.org_y = (float)org.y,
		.org_z = (float)org.z,
		.tnear = (float)tnear,
		.dir_x = (float)dir.x,
		.dir_y = (float)dir.y,
		.dir_z = (float)dir.z,
		.tfar = (float)tfar,
		.mask = 0xffffffffu,
	};

	rtcInitIntersectContext(&ctx);
	rtcOccluded1(t->scene, &ctx, &r);
	return r.tfar < 0;
}

static void intersect_raw1(struct glint_tracer *t, const float *rays, int n,
			   int32_t *hit_geom)
{
	struct RTCIntersectContext ctx;

	rtcInitIntersectContext(&ctx);
	for (int i = 0; i < n; i++) {
		const float *r = rays + 6 * (size_t)i;
		struct RTCRayHit rh = {
			.ray = { .org_x = r[0],
				 .org_y = r[1],
				 .org_z = r[2],
				 .dir_x = r[3],
				 .dir_y = r[4],
				 .dir_z = r[5],
				 .tfar = INFINITY,
				 .mask = 0xffffffffu },
			.hit = { .geomID = RTC_INVALID_GEOMETRY_ID },
		};
		rtcIntersect1(t->scene, &ctx, &rh);
		hit_geom[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID
				      ? -1
				      : (int32_t)rh.hit.geomID;
	}
}

void glint_tracer_intersect_raw(struct glint_tracer *t, const float *rays,
				int n, int32_t *hit_geom, int packet)
{
	_Alignas(64) struct RTCRayHit16 rh;
	_Alignas(64) int valid[16];
	struct RTCIntersectContext ctx;

	glint_thread_ftz();
	if (!packet) {
		intersect_raw1(t, rays, n, hit_geom);
		return;
	}
	rtcInitIntersectContext(&ctx);
	ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
	for (int b = 0; b < n; b += 16) {
		int m = n - b < 16 ? n - b : 16;
		for (int k = 0; k < 16; k++) {
			valid[k] = k < m ? -1 : 0;
			if (k >= m)
				continue;
			const float *r = rays + 6 * (size_t)(b + k);
			set_lane(&rh, k, v3(r[0], r[1], r[2]),
				 v3(r[3], r[4], r[5]));
		}
		rtcIntersect16(valid, t->scene, &ctx, &rh);
		for (int k = 0; k < m; k++)
			hit_geom[b + k] =
				rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID
					? -1
					: (int32_t)rh.hit.geomID[k];
	}
}

int glint_tracer_intersect1(struct glint_tracer *t, struct vec3 org,
			    struct vec3 dir, double tnear, double *thit,
			    struct vec3 *ng)
{
	struct RTCIntersectContext ctx;
	struct RTCRayHit rh = {
		.ray = { .org_x = (float)org.x,
			 .org_y = (float)org.y,
			 .org_z = (float)org.z,
			 .tnear = (float)tnear,
			 .dir_x = (float)dir.x,
			 .dir_y = (float)dir.y,
			 .dir_z = (float)dir.z,
			 .tfar = INFINITY,
			 .mask = 0xffffffffu },
		.hit = { .geomID = RTC_INVALID_GEOMETRY_ID },
	};

	rtcInitIntersectContext(&ctx);
	rtcIntersect1(t->scene, &ctx, &rh);
	if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
		return -1;
	*thit = rh.ray.tfar;
	*ng = v3_norm(v3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
	return (int)rh.hit.geomID;
}
