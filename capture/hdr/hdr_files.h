/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_HDR_FILES_H
#define GLINT_CAPTURE_HDR_HDR_FILES_H

/*
 * HDR merges of files named by the user, as `glint hdr` runs them:
 * 8-bit photos with their exposure times (capture/hdr/hdr_response.h), and
 * raw frames or a session's bracket (capture/hdr/session_merge.h) with the
 * merge's report written beside the result.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees:
 * glint_frames_free() the frames read; images with glint_image_free().
 */

#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/raw_file.h"

#include <jansson.h>

/*
 * n exposure times (seconds; "1/250" allowed) into t[n]: from `file`
 * (one per line, '#' comments and blank lines skipped) when it is not
 * NULL, else from the comma-separated `list`.  A count other than n, or
 * a time that is not positive, is an error naming the line or token.
 */
int glint_exposure_times_read(const char *list, const char *file, int n,
			      double *t);

/* The same from each photo's EXIF ExposureTime (JPEG and TIFF,
 * core/exif.h); an error names the first photo without one. */
int glint_exposure_times_exif(const char *const *files, int n, double *t);

struct glint_ldr_merge_info {
	int width, height;
	int iterations; /* Robertson's; 0 for Debevec */
};

/*
 * Merge n 8-bit photos files[] taken with exposure times t[] (any
 * order of files is refused when brightness does not rise with the
 * times: glint_ldr_check_order) with the response recovered by `method`
 * ("robertson" or "debevec"), and write into folder `out` (made if
 * missing): hdr.exr, mask.png, hdr.png (a tone-mapped preview) and
 * response.csv (a comment line, then 256 rows of r,g,b) and response.png
 * (its plot, log2 exposure against code value).  Each file is written
 * atomically.
 */
int glint_ldr_merge_files(const char *const *files, int n, const double *t,
			  const char *method, const char *out,
			  struct glint_ldr_merge_info *info);

/* Raw frames read from files[n] (capture/hdr/raw_file.h: glint's own,
 * 16-bit TIFFs, any raw file LibRaw reads), with exposure times times[n]
 * in place of the files' own when times is not NULL (a file without one is
 * an error otherwise).  *info: frame 0's reader, camera and colour matrix;
 * every frame must come from the same camera by the same reader.  *frames
 * is the caller's, freed with glint_frames_free() also on failure. */
int glint_frames_read(const char *const *files, int n, const double *times,
		      struct glint_frame **frames, struct glint_raw_info *info);

/*
 * The merge's record, written atomically to out/hdr.json: the frame
 * count, size, valid pixels, clipped and dark sites, the motion check per
 * frame pair, the noise model used and, when `input` is not NULL (the
 * record takes it), what the frames were ("input").  *doc (the same
 * document) is the caller's to json_decref() when doc is not NULL.
 */
int glint_hdr_report_write(const char *out, int frames, int width, int height,
			   long valid_px, const struct glint_hdr_report *rep,
			   const struct glint_noise_model *nm, json_t *input,
			   json_t **doc);

/* What a bracket of files was, for hdr.json's "input": the reader, the
 * camera, where the exposure times came from, the colour conversion and
 * its matrix, the frames' layout, white and black levels. */
json_t *glint_raw_input_json(const struct glint_raw_info *info,
			     const struct glint_frame *f0,
			     const char *times_from);

#endif
