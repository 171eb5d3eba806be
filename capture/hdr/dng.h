/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_DNG_H
#define GLINT_CAPTURE_HDR_DNG_H

/*
 * A raw frame as a DNG (Adobe's raw format, a TIFF; written with libtiff)
 * that raw tools open (dcraw/LibRaw, darktable, RawTherapee):
 *
 *  - one uncompressed 16-bit image in IFD 0 (NewSubFileType 0), the
 *    camera's numbers unchanged and right-aligned;
 *  - Bayer frames: PhotometricInterpretation CFA, CFARepeatPatternDim
 *    2 x 2, CFAPattern (0 red, 1 green, 2 blue) from the frame's layout;
 *    RGB frames LinearRaw, mono frames BlackIsZero;
 *  - BlackLevel (the frame's), WhiteLevel 2^bit_depth - 1;
 *  - ColorMatrix1 the XYZ (D65) to linear-sRGB matrix, AsShotNeutral 1 1 1,
 *    CalibrationIlluminant1 D65: glint's cameras are not colour
 *    calibrated, so their RGB is taken as linear sRGB (stated, not
 *    measured);
 *  - an EXIF IFD with ExposureTime (the exposure the camera confirmed it
 *    applied) and ISOSpeedRatings (100 x the applied gain);
 *  - ImageDescription: glint's frame metadata as JSON (frame_file.h), the
 *    same as the frame's sidecar file, with the pixels' CRC-32.
 *
 * Written atomically (a temporary file renamed into place).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (sizes are checked against the file before
 * anything is allocated).  Threads: re-entrant (libtiff handles are per
 * call).  Who frees: the caller, as each function says.
 */

#include "capture/camera/camera.h"

int glint_dng_write(const char *path, const struct glint_frame *f,
		    const char *metadata_json);

/*
 * Read a DNG glint wrote: the pixels, and its metadata JSON (malloc'd,
 * the caller frees; NULL when the file has none).  Sizes are checked
 * against the file's size before anything is allocated.
 */
int glint_dng_read(const char *path, struct glint_frame *f, char **metadata);

/* Does the file start like a TIFF ("II*\0" or "MM\0*")? */
int glint_dng_is_tiff(const char *path);

#endif
