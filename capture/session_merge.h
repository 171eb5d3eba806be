/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_SESSION_MERGE_H
#define GLINT_CAPTURE_SESSION_MERGE_H

/* A session's raw bracket, merged (capture/hdr_linear.h) and written. */

#include "camera.h"
#include "hdr_linear.h"

/* The noise model of session `dir`'s rig.json "sensor" section: m keeps
 * its values for what is absent (and all of them without a rig.json). */
int glint_session_noise(const char *dir, struct glint_noise_model *m);

/* The frames session.json lists, read from `dir`: *frames (n of them) is
 * the caller's, freed with glint_frames_free() also on failure. */
int glint_session_load_frames(const char *dir, struct glint_frame **frames,
			      int *n);
void glint_frames_free(struct glint_frame *f, int n);

/*
 * Merge a raw bracket and write into folder `out` (made if missing) the
 * radiance, variance, weights (1/variance, 0 where invalid), validity mask
 * and a tone-mapped preview under names[0..4].  *valid_px counts pixels
 * with a valid sample; the radiance goes to *radiance (the caller frees
 * it with glint_image_free) when that is not NULL.  The frames' pixel
 * data is released (glint_frame_release: their metadata stays) once the
 * merge has read them, and each image is freed once written: a 12 MP
 * bracket of 22 frames is 540 MB, the merged images 148 MB each.
 */
int glint_hdr_merge_write(struct glint_frame *frames, int n,
			  const struct glint_noise_model *nm, const char *out,
			  const char *const names[5],
			  struct glint_hdr_report *rep, int *width, int *height,
			  long *valid_px, struct glint_image **radiance);

#endif
