/* SPDX-License-Identifier: MIT */
/*
 * Embree 3 scene of the sample.  A sphere is user geometry by default: its
 * analytic hit in double precision is exact to sub-pixel level and, measured
 * on this machine (bench/render), faster than RTC_GEOMETRY_TYPE_SPHERE_POINT.
 */
#include "tracer.h"
#include "tracer_internal.h"

#include "sampling.h"

#include "core/error.h"
#include "core/parallel.h"

#include <embree3/rtcore.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

void tracer_set_lane(struct RTCRayHit16 *rh, int k, struct vec3 o,
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
			tracer_set_lane(&rh, k, v3(r[0], r[1], r[2]),
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
