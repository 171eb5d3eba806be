/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_SIM_SCENE_H
#define GLINT_TESTS_SIM_SCENE_H

/*
 * The simulated rig of the fit tests: 192 x 192, a 100 mm lens on a 36 mm
 * sensor, a 10 cm sphere at 0.5 m (53 px in radius), and a noise-free
 * photo of a Table-1 material from the reference renderer.
 */

#include "core/error.h"
#include "fit/render/render.h"
#include "sim/reference.h"

#include <stdio.h>

static inline void sim_scene_192(struct glint_scene *s, const char *map,
				 double rot_y)
{
	glint_scene_defaults(s);
	glint_pinhole_init(&s->cam, 192, 192, 0.1, 0.036 / 192, 0, 0,
			   v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
	s->sphere_centre = v3(0, 0, -0.5);
	s->sphere_radius = 0.05;
	snprintf(s->env_path, sizeof(s->env_path), "%s", map);
	s->env_rotation[1] = rot_y;
	s->env_scale = 1;
}

/* The reference photo of (m, p) in r's scene with spp samples per pixel
 * and `samples` per technique; NULL on failure. */
static inline struct glint_image *sim_photo_spp(const struct glint_renderer *r,
						const struct glint_model *m,
						const double *p, int spp,
						int samples)
{
	struct glint_image *photo =
		glint_image_new(r->scene.cam.width, r->scene.cam.height);
	struct glint_reference_opts ro;

	glint_reference_default_opts(&ro);
	ro.spp = spp;
	ro.samples = samples;
	if (photo &&
	    glint_reference_render(&r->scene, r->env, m, p, &ro, photo) < 0) {
		glint_image_free(photo);
		photo = NULL;
	}
	return photo;
}

/* The same at 4 samples per pixel, 64 per technique. */
static inline struct glint_image *sim_photo(const struct glint_renderer *r,
					    const struct glint_model *m,
					    const double *p)
{
	return sim_photo_spp(r, m, p, 4, 64);
}

#endif
