/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_LIGHT_CLASS_H
#define GLINT_SIM_LIGHT_CLASS_H

/*
 * Lighting classes: procedural lat-long radiance maps (the convention of
 * core/vec.h: +Y up, u = 0.5 looking down -Z) of the kinds of light a
 * sphere meets in labs and studios, beyond the shared photographed maps:
 *
 *   window-room     an interior lit by two windows near the horizon (mullions,
 *                   a sunlit patch on the floor), dim walls elsewhere
 *   softbox-studio  key, fill and rim softboxes (soft-edged rectangles)
 *                   over a dark studio
 *   overcast        the CIE standard overcast sky (zenith 3x the horizon)
 *                   over ground of albedo 0.2
 *   sun-sky         a clear sky with a sun of 0.53 degrees (about two texels
 *                   at 1024 px) holding most of the irradiance
 *   lamp-fill       one small warm lamp (3 degrees) and a dim bounce card
 *   night-lamps     six small lamps (sodium, LED) near the horizon under a
 *                   dark sky
 *
 * The maps are for a sphere seen by a camera on +Z (the fixtures' and the
 * sim camera's set-up) with no map rotation: key lights sit on the
 * camera's side.  A small source's irradiance at normal incidence is
 * exact: its radiance is set from the solid angle its painted texels
 * cover (sub-texel coverage, 8 x 8 samples per edge texel), so a lamp
 * narrower than a texel keeps its flux.  Deterministic: the same name
 * and width give the same map.
 *
 * Errors: -EINVAL naming the class and the choices, -ENOMEM; the message
 * in glint_error_msg().  Threads: re-entrant.  Who frees: the image out
 * with glint_image_free().
 */

#include "core/image.h"
#include "core/vec.h"

/* The classes' names, NULL-terminated, in the order above. */
extern const char *const glint_sim_light_classes[];

/* A width x width/2 map of class name (width even, 64 to 16384). */
int glint_sim_light_class(const char *name, int width,
			  struct glint_image **out);

/* The direction (map space) and irradiance at normal incidence of the
 * class's small sources (the sun, the lamps: those under 5 degrees
 * across), at most max of them; returns how many the class has.  What
 * a test checks a probe's source finder against. */
int glint_sim_light_class_sources(const char *name, struct vec3 *dir,
				  double (*irradiance)[3], int max);

#endif
