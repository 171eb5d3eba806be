/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_IRRADIANCE_H
#define GLINT_FIT_RENDER_IRRADIANCE_H

/*
 * Irradiance E(n) = integral of L(w) max(0, n.w) dw over an env map, on a
 * lat-long grid of normals (the map's convention, world frame), looked up
 * bilinearly.  The integral is a deterministic sum over the map's texels,
 * each weighted by the mean of the bilinear radiance over it (what
 * glint_envmap_lookup returns) and its exact solid angle; the map is first
 * reduced to at most 128 texels across.  Texels flagged in `exclude` (hot
 * texels integrated elsewhere) are left out.
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
