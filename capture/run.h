/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_RUN_H
#define GLINT_CAPTURE_RUN_H

/*
 * One capture, as `glint capture` and the rig daemon run it: a bracket
 * into a new session (every frame on disk before the next), the session
 * finished complete or incomplete, the merge, and then for a probe the
 * unwrap to env.exr, for a sample its scene.json lit by a probe session.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected; a failed stage stops the run, named.  Threads:
 * one thread; cancel may be set from a signal handler.  Who frees: nothing
 * (the run's results are files).
 */

#include "capture/camera/bracket.h"
#include "core/path.h"

#include "core/atomic.h"

#include <jansson.h>

/* What a capture needs to know of the rig (appliance/rig.c fills it from the
 * rig file). */
struct glint_capture_setup {
	const char *backend, *device; /* camera */
	char *text; /* the rig file as recorded in each session (owned by
		       whoever built the setup) */
	struct glint_bracket_opts bracket;
	struct glint_roi roi[2];       /* probe, sample */
	double focal_px, principal[2]; /* optics; 0 = not given */
	double pitch_um;	       /* optics.pixel_pitch_um */
	double psf_sigma_px; /* optics.psf_sigma_px: the camera's blur */
	int olpf;	     /* optics.olpf */
	double diameter_m;   /* sample.diameter_m */
	/* reference: a matte gray ball calibrating the probe
	 * (capture/probe/probe_calibrate.h); ref_albedo 0: none.  Beside
	 * the chrome one, in roi[0]'s photo at ref_roi; or with ref_own, at
	 * its own turntable position, a capture of kind "reference" (ref_roi
	 * where it is in that photo, all of it when empty). */
	double ref_albedo, ref_albedo_sigma;
	struct glint_roi ref_roi;
	int ref_own;
};

struct glint_capture_result {
	char session[GLINT_PATH_MAX]; /* the session folder ("" if none) */
	char scene[GLINT_PATH_MAX];   /* a sample's scene.json, "" if none */
	json_t *summary; /* complete: what glint capture --json prints;
			    the caller owns it (json_decref) */
};

/*
 * Capture `kind` ("probe", "reference" or "sample") into a new session
 * under `out`; a sample's scene is lit by the probe session `probe` (NULL:
 * the newest complete probe session under out).  A reference (the gray
 * ball alone) calibrates the probe session `probe`'s map into its own
 * session, which then lights a sample as a probe session does.  *cancel (may be
 * NULL) stops it with -ECANCELED.  On failure the message names the session
 * kept (incomplete, its frames whole) and res->summary is NULL.
 */
int glint_capture_run(const struct glint_capture_setup *setup, const char *kind,
		      const char *out, const char *probe, atomic_int *cancel,
		      struct glint_capture_result *res);

/* The merge's plausibility check: how many of its standard deviations
 * below zero a dark site of an n-site merge may lie by chance (the depth
 * reached somewhere in one photo in 10,000; at least 5).  A site deeper
 * than that refuses the photo (a wrong black level or noise model). */
double glint_negative_sigma_limit(size_t n);

#endif
