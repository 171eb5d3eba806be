/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_IRRADIANCE_H
#define GLINT_FIT_RENDER_IRRADIANCE_H

/*
 * Irradiance E(n) = integral of L(w) max(0, n.w) dw over an env map, on a
 * lat-long grid of normals (the map's convention, world frame), looked up
 * with Catmull-Rom weights (bilinear weights missed by up to 2.5 % next to
 * a softbox's horizon on a 64-wide grid; the cubic on 128 is within
 * 0.1 %: tests/unit/test_envmap.c).
 *
 * Each grid value is the integral over the map's texels, each taken as
 * the mean of the bilinear radiance over it (what glint_envmap_lookup
 * returns) times its exact first moment (the integral of w dw over the
 * texel).  Where a group of texels lies wholly above the normal's horizon
 * the cosine is linear in w, so the group adds n . (sum of its moments)
 * exactly; a tree of such groups (lat-long rectangles with bounding
 * cones) leaves only the texels across the horizon to sum one by one, each
 * as its clamped n . moment (never above the true share: a 64 x 32 map's
 * 5.6 degree texels leave a uniform map's irradiance 0.12 % low).  Maps
 * wider than 256 are first reduced by an integer factor (cells whose
 * moments are the sums of their texels').  Texels flagged in `exclude`
 * (hot texels integrated elsewhere) are left out.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: built on nthreads threads, then read
 * only.  Who frees: glint_irradiance_free().
 */

#include "fit/scene/envmap.h"

struct glint_irradiance {
	int w, h;
	double *e; /* w * h * 3 */
};

int glint_irradiance_build(const struct glint_envmap *env,
			   const unsigned char *exclude, int w, int nthreads,
			   struct glint_irradiance *ir);
void glint_irradiance_lookup(const struct glint_irradiance *ir, struct vec3 n,
			     double e[3]);
void glint_irradiance_free(struct glint_irradiance *ir);

#endif
