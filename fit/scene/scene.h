/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_SCENE_SCENE_H
#define GLINT_FIT_SCENE_SCENE_H

/*
 * A scene file (JSON, docs/scene.md): camera, sphere, environment map and
 * render settings.  Lengths in metres except where a key says _mm or _um;
 * angles in degrees; pixel coordinates with (0, 0) the top-left corner.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (file, key, value).  Threads: re-entrant.  Who
 * frees: nothing (a scene is a value).
 */

#include "core/pinhole.h"

#define GLINT_PATH_MAX 4096

struct glint_scene {
	struct glint_pinhole cam;
	struct vec3 sphere_centre;     /* metres, world */
	double sphere_radius;	       /* metres */
	char env_path[GLINT_PATH_MAX]; /* resolved against the scene's dir */
	double env_rotation[3];	       /* degrees about X, Y, Z */
	double env_scale;
	/* the relative standard uncertainty of the map's radiance per
	 * channel (environment.scale_sigma: a probe calibrated by a gray
	 * ball states it); 0: the map is taken as exact */
	double env_scale_sigma[3];
	/* environment.sources: a probe's env-sources.json (its compact
	 * sources and their flux's uncertainty), resolved against the
	 * scene's folder; "" when none */
	char env_sources_path[GLINT_PATH_MAX];
	/* the map is an 8-bit image taken as sRGB-encoded (--srgb); else
	 * such a map is refused (glint_radiance_check) */
	int env_srgb;
	int spp;	   /* primary samples per pixel */
	int light_samples; /* env-map samples per hit */
	int brdf_samples;  /* BRDF samples per hit */
};

/* Defaults: see docs/scene.md. */
void glint_scene_defaults(struct glint_scene *s);

/* The primary hits a pixel of a scene whose file does not give
 * render.samples_per_pixel: 4, or 16 when cam has a blur. */
int glint_scene_spp_default(const struct glint_pinhole *cam);
/* Env-map and BRDF samples a hit when the scene file does not say, for spp
 * primary hits a pixel: 32 up to 4 hits, 128 / spp above (scene.c). */
int glint_scene_samples_default(int spp);

/* Parse and validate a scene file; messages name the key and bounds. */
int glint_scene_load(const char *path, struct glint_scene *s);

/* Parse from an already loaded document; `dir` resolves relative paths. */
struct json_t;
int glint_scene_from_json(const char *file, const char *dir,
			  struct json_t *root, struct glint_scene *s);

#endif
