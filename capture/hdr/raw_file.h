/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_RAW_FILE_H
#define GLINT_CAPTURE_HDR_RAW_FILE_H

/*
 * A raw frame from any camera's file, for the linear merge
 * (capture/hdr/hdr_linear.h), by what the file is:
 *
 *  - a frame glint wrote (a DNG or PNG holding glint's frame metadata):
 *    capture/hdr/frame_file.h, its checksum checked;
 *  - a 16-bit TIFF (a raw converter's linear output, e.g. dcraw -4 -T):
 *    libtiff, RGB16 or MONO16 as stored, black 0, white 65535, the
 *    exposure time and ISO from its EXIF directory; its colour is the
 *    converter's output space (dcraw's default: linear sRGB);
 *  - anything else (a DNG from another writer, CR2/CR3, NEF, ARW, RAF,
 *    ORF, RW2 and the rest LibRaw reads): LibRaw's unpacked sensor values
 *    of the visible area, unscaled.  A 2 x 2 Bayer mosaic becomes
 *    RGGB16 .. BGGR16, a linear DNG RGB16, a monochrome sensor MONO16;
 *    other mosaics (X-Trans, CMYG) are refused, named.  Black level per
 *    site (LibRaw's black, per-colour cblack and its repeat pattern: sites
 *    whose black is above the lowest are brought down to it), white level
 *    LibRaw's maximum, exposure time and ISO from the file's metadata
 *    (gain = ISO / 100: only the ratio between a bracket's frames matters
 *    to the merge), and the camera-to-sRGB matrix (below).
 *
 * The colour matrix, when the file has one (a DNG's ColorMatrix, LibRaw's
 * table for a camera raw): linear sRGB = rgb_cam x diag(pre_mul) x camera
 * RGB, with LibRaw's rgb_cam and its daylight multipliers pre_mul scaled to
 * green 1: a neutral surface in D65 light comes out grey, whatever light
 * the photo was taken in (a measurement, not a white-balanced picture).
 *
 * Errors: a negative errno with glint_error_msg() naming the file and what
 * was wrong (LibRaw's own message for what it cannot read; sizes checked
 * against glint's image limits and the file's size before unpacking).
 * LibRaw runs in a forked child process (one per file): a crash of
 * LibRaw's own parsers on a hostile file is a refusal naming the signal.
 * Threads: re-entrant (libraw_r, one handle per call).  Who frees: the
 * caller, a frame with glint_frame_release().
 */

#include "capture/camera/camera.h"

struct glint_raw_info {
	char reader[48];   /* "glint frame", "libtiff", "LibRaw 0.20.2" */
	char camera[144];  /* make and model as the file names them */
	int has_matrix;	   /* rgb_cam is the file's camera -> sRGB */
	double rgb_cam[9]; /* row-major; identity without a matrix */
	int has_exposure;  /* the file gave the exposure time */
	double iso;	   /* 0: the file gives none (gain 1) */
};

/* Read `path` as the list above says.  A file without an exposure time
 * is read (has_exposure 0, exposure_s 0) for the caller to give one. */
int glint_raw_file_read(const char *path, struct glint_frame *f,
			struct glint_raw_info *info);

/* 1 when `path` holds 8-bit camera-encoded photos (JPEG, an 8-bit PNG or
 * TIFF) that need a response curve rather than the raw merge, 0 when not,
 * or a negative errno naming the file when it cannot be read. */
int glint_raw_file_is_8bit(const char *path);

#endif
