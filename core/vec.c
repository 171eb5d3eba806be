/* SPDX-License-Identifier: MIT */
#include "vec.h"

#include <math.h>

struct mat3 m3_mul_m3(const struct mat3 *a, const struct mat3 *b)
{
	struct mat3 r;

	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			r.m[i][j] = a->m[i][0] * b->m[0][j] +
				    a->m[i][1] * b->m[1][j] +
				    a->m[i][2] * b->m[2][j];
	return r;
}

struct mat3 m3_rotation_xyz_deg(double rx, double ry, double rz)
{
	double a = rx * M_PI / 180, b = ry * M_PI / 180, c = rz * M_PI / 180;
	struct mat3 x = {
		{ { 1, 0, 0 }, { 0, cos(a), -sin(a) }, { 0, sin(a), cos(a) } }
	};
	struct mat3 y = {
		{ { cos(b), 0, sin(b) }, { 0, 1, 0 }, { -sin(b), 0, cos(b) } }
	};
	struct mat3 z = {
		{ { cos(c), -sin(c), 0 }, { sin(c), cos(c), 0 }, { 0, 0, 1 } }
	};
	struct mat3 zy = m3_mul_m3(&z, &y);

	return m3_mul_m3(&zy, &x);
}

void v3_frame(struct vec3 n, struct vec3 *t, struct vec3 *b)
{
	double sign = copysign(1.0, n.z);
	double a = -1.0 / (sign + n.z);
	double bb = n.x * n.y * a;

	*t = v3(1.0 + sign * n.x * n.x * a, sign * bb, -sign * n.x);
	*b = v3(bb, sign + n.y * n.y * a, -n.y);
}

void glint_latlong_dir_to_uv(struct vec3 d, double *u, double *v)
{
	double y = d.y < -1 ? -1 : d.y > 1 ? 1 : d.y;
	double phi = atan2(d.x, -d.z);

	*u = 0.5 + phi / (2 * M_PI);
	*v = acos(y) / M_PI;
}

struct vec3 glint_latlong_uv_to_dir(double u, double v)
{
	double phi = 2 * M_PI * (u - 0.5), theta = M_PI * v;
	double s = sin(theta);

	return v3(s * sin(phi), cos(theta), -s * cos(phi));
}
