/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_FRAME_FILE_H
#define GLINT_CAPTURE_HDR_FRAME_FILE_H

/*
 * A raw frame on disk: a DNG (dng.h) when the path ends in ".dng", as
 * sessions write them; else, as older sessions did, a 16-bit PNG (greyscale for
 * Bayer and mono layouts, RGB for three-channel frames) holding the camera's
 * numbers unchanged and right-aligned (0 .. 2^bit_depth - 1, not rescaled),
 * with the frame's metadata as JSON in an iTXt chunk keyed "glint:frame" (the
 * same JSON as the frame's sidecar file).  Lossless, written atomically (temp +
 * fsync + rename + directory fsync); any PNG reader opens it.  docs/capture.md
 * documents the layout.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (truncated, inconsistent or edited frames named).
 * Threads: re-entrant.  Who frees: the caller frees the metadata text
 * (free()) and a frame read (glint_frame_release()).
 */

#include "capture/camera/camera.h"

/* The frame's metadata as a JSON object text (caller frees): its index
 * in the session, the camera's values and "pixels_crc32", the CRC-32 of
 * the samples as the PNG stores them (16-bit big-endian, row by row). */
char *glint_frame_metadata_json(const struct glint_frame *f, int index);

/* That CRC-32 of a frame's samples (what session.json also records for
 * each frame, so that a frame from another session is told apart). */
uint32_t glint_frame_pixels_crc32(const struct glint_frame *f);

int glint_frame_write(const char *path, const struct glint_frame *f,
		      const char *metadata_json);

/* Read pixel data back, from a DNG or a PNG whatever the name (format
 * and bit depth from the metadata: the PNG's chunk, the DNG's
 * ImageDescription, whose layout must agree with the DNG's tags);
 * fails naming the file on anything truncated or inconsistent, or when
 * the pixels do not match their checksum (an edited frame).  *index (may
 * be NULL) is the index the metadata gives, -1 when it has none. */
int glint_frame_read(const char *path, struct glint_frame *f, int *index);
/* The same, with *pixels_crc (may be NULL) the CRC-32 of the samples read
 * (glint_frame_pixels_crc32(), computed once for the checksum check). */
int glint_frame_read_crc(const char *path, struct glint_frame *f, int *index,
			 uint32_t *pixels_crc);

#endif
