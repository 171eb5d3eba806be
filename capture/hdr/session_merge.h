/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_SESSION_MERGE_H
#define GLINT_CAPTURE_HDR_SESSION_MERGE_H

/*
 * A session's raw bracket, merged (capture/hdr/hdr_linear.h) and written.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: images out with
 * glint_image_free(), frames with glint_frames_free().
 */

#include "capture/camera/camera.h"
#include "capture/hdr/hdr_linear.h"

/* The noise model of session `dir`'s rig.json "sensor" section: m keeps
 * its values for what is absent (and all of them without a rig.json). */
int glint_session_noise(const char *dir, struct glint_noise_model *m);

/* The frames session.json lists, read from `dir`: *frames (n of them) is
 * the caller's, freed with glint_frames_free() also on failure. */
int glint_session_load_frames(const char *dir, struct glint_frame **frames,
			      int *n);
void glint_frames_free(struct glint_frame *f, int n);

/*
 * Write a merged raw bracket into folder `out` (made if missing): the
 * radiance, variance, weights (1/variance, 0 where invalid), validity mask
 * and a tone-mapped preview under names[0..4].  raw is demosaiced and
 * released; *valid_px counts pixels with a valid sample; the radiance goes
 * to *radiance (the caller frees it with glint_image_free) when that is not
 * NULL.  Each image is freed once written (at 12 MP 148 MB each).
 */
int glint_hdr_write(struct glint_raw_hdr *raw, const char *out,
		    const char *const names[5], int *width, int *height,
		    long *valid_px, struct glint_image **radiance);

/*
 * Merge a raw bracket (the streaming merge, frames folded in the order
 * given) and write it as glint_hdr_write() does, after turning the camera's
 * RGB into linear sRGB by rgb_cam (3 x 3, row-major; NULL: the frames' RGB
 * is kept, as glint's own cameras' is linear sRGB by declaration) with the
 * variance carried through.  Each frame's pixel data is released
 * (glint_frame_release: its metadata stays) once folded in.
 */
int glint_hdr_merge_write(struct glint_frame *frames, int n,
			  const struct glint_noise_model *nm,
			  const double *rgb_cam, const char *out,
			  const char *const names[5],
			  struct glint_hdr_report *rep, int *width, int *height,
			  long *valid_px, struct glint_image **radiance);

/* A session's bracket merged frame by frame as session.json lists them
 * (capture order: the rig's own merge, bit for bit), one frame in memory
 * at a time, and written as glint_hdr_write() does. */
int glint_session_merge_write(const char *dir,
			      const struct glint_noise_model *nm,
			      const char *out, const char *const names[5],
			      struct glint_hdr_report *rep, int *width,
			      int *height, long *valid_px);

#endif
