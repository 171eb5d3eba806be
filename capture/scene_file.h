/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_SCENE_FILE_H
#define GLINT_CAPTURE_SCENE_FILE_H

/*
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: nothing
 * (results are files and values).
 */

#include "capture/probe/sphere_detect.h"
#include "core/image.h"

#include <stddef.h>

/* What the rig file says about its optics and sample. */
struct glint_scene_optics {
	double focal_px;
	double principal[2]; /* -1 = the image centre */
	double pitch_um;
	double diameter_m;
	/* the camera's blur (core/pinhole.h): written into the scene when
	 * given, so that the fit renders the photo's pixels */
	double psf_sigma_px;
	int olpf;
	/* the mosaic the photo was demosaiced from ("RGGB" ...; "" none),
	 * so that the fit takes each pixel's measured colour */
	char cfa[8];
};

/* The newest complete probe session with an env.exr under root. */
int glint_session_latest_probe(const char *root, char *out, size_t n);

/* Find the sphere in the merged sample and write DIR/scene.json lit by
 * probe_dir's env.exr; *found (may be NULL) gets the circle. */
int glint_sample_write_scene(const char *dir, const struct glint_image *sample,
			     const struct glint_scene_optics *o,
			     const char *probe_dir, struct glint_circle *found);

#endif
