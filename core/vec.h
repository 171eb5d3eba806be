/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_VEC_H
#define GLINT_CORE_VEC_H

/*
 * Small 3-vector and 3x3 matrix helpers in double precision.
 *
 * Errors: none (inline arithmetic).  Threads: re-entrant.  Who frees:
 * nothing.
 */

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

struct vec3 {
	double x, y, z;
};

static inline struct vec3 v3(double x, double y, double z)
{
	struct vec3 r = { x, y, z };
	return r;
}

static inline struct vec3 v3_add(struct vec3 a, struct vec3 b)
{
	return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}

static inline struct vec3 v3_sub(struct vec3 a, struct vec3 b)
{
	return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}

static inline struct vec3 v3_scale(struct vec3 a, double s)
{
	return v3(a.x * s, a.y * s, a.z * s);
}

static inline double v3_dot(struct vec3 a, struct vec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}

static inline struct vec3 v3_cross(struct vec3 a, struct vec3 b)
{
	return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z,
		  a.x * b.y - a.y * b.x);
}

static inline double v3_len(struct vec3 a)
{
	return sqrt(v3_dot(a, a));
}

static inline struct vec3 v3_norm(struct vec3 a)
{
	double l = v3_len(a);
	return l > 0 ? v3_scale(a, 1.0 / l) : a;
}

/* Row-major 3x3 matrix. */
struct mat3 {
	double m[3][3];
};

static inline struct vec3 m3_mul(const struct mat3 *a, struct vec3 v)
{
	return v3(a->m[0][0] * v.x + a->m[0][1] * v.y + a->m[0][2] * v.z,
		  a->m[1][0] * v.x + a->m[1][1] * v.y + a->m[1][2] * v.z,
		  a->m[2][0] * v.x + a->m[2][1] * v.y + a->m[2][2] * v.z);
}

/* Transpose times v (inverse of a rotation). */
static inline struct vec3 m3_tmul(const struct mat3 *a, struct vec3 v)
{
	return v3(a->m[0][0] * v.x + a->m[1][0] * v.y + a->m[2][0] * v.z,
		  a->m[0][1] * v.x + a->m[1][1] * v.y + a->m[2][1] * v.z,
		  a->m[0][2] * v.x + a->m[1][2] * v.y + a->m[2][2] * v.z);
}

/*
 * Rotation from Euler angles in degrees, applied about the fixed axes X,
 * then Y, then Z: R = Rz * Ry * Rx.
 */
struct mat3 m3_rotation_xyz_deg(double rx, double ry, double rz);
/* a b */
struct mat3 m3_mul_m3(const struct mat3 *a, const struct mat3 *b);

/* Orthonormal frame (t, b, n) around the unit vector n (Duff et al. 2017). */
void v3_frame(struct vec3 n, struct vec3 *t, struct vec3 *b);

/*
 * The lat-long (equirectangular) convention of every environment map and
 * probe: map-space direction <-> (u, v) in [0, 1]^2, u = 0.5 looking down
 * -z, v = 0 straight up (+y).
 */
void glint_latlong_dir_to_uv(struct vec3 d, double *u, double *v);
struct vec3 glint_latlong_uv_to_dir(double u, double v);

/* Luminance of linear Rec.709 RGB. */
static inline double rgb_luminance(double r, double g, double b)
{
	return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

#endif
