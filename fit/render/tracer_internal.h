/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_TRACER_INTERNAL_H
#define GLINT_FIT_RENDER_TRACER_INTERNAL_H

/*
 * What tracer.c (the Embree scene, secondary rays) and gbuffer.c (primary
 * rays into G-buffers) share; private to fit/render/.
 */

#include "core/vec.h"

#include <embree3/rtcore.h>

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

/* Lane k of a packet of 16: a ray from o along d over [0, inf), no hit. */
void tracer_set_lane(struct RTCRayHit16 *rh, int k, struct vec3 o,
		     struct vec3 d);

#endif
