/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_CAMERA_BRACKET_H
#define GLINT_CAPTURE_CAMERA_BRACKET_H

/*
 * Exposure brackets that cover a region of interest's dynamic range.
 * From a start exposure the planner steps down (by step_ev) until the ROI
 * has no saturated pixel, and up until the ROI's darkest pixels (its 1st
 * percentile) are above the noise floor; the frames themselves are the
 * meter (no frames are spent before the bracket: wherever it starts, the
 * two goals bound it); when exposure reaches the
 * camera's maximum it raises gain instead, and says so.  Capped in frame
 * count and total time; every frame carries its applied exposure and gain.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (-ECANCELED when cancelled).  Threads: one thread
 * drives a bracket and its camera; cancel may be set from any thread or a
 * signal handler.  Who frees: glint_bracket_release() frees a bracket's
 * frames, also after an error.
 */

#include "capture/camera/camera.h"
#include "core/atomic.h"

#define GLINT_BRACKET_MAX 32

/* Pixel rectangle [x0, x1) x [y0, y1); all zero = the whole frame. */
struct glint_roi {
	int x0, y0, x1, y1;
};

struct glint_bracket_opts {
	double step_ev; /* default 1 */
	int max_frames; /* default 24 */
	/* Cap on the camera's time (its exposures and readouts, as it
	 * reports them: glint_camera_seconds()), default 60 s. */
	double max_time_s;
	double start_s; /* 0: metered by the bracket's own frames */
	/* Meter with frames of its own before the bracket starts
	 * (bench/capture compares the two). */
	int meter_apart;
	double floor_dn; /* darkest ROI pixels must exceed black + this */
	int max_drop;	 /* frames to wait for an exposure to land */
	/* Called with each frame as it is captured (capture order, from 0),
	 * e.g. to put it on disk before the next; nonzero return stops the
	 * bracket with that error. */
	int (*on_frame)(const struct glint_frame *f, int index, void *ctx);
	void *ctx;
	/* Each kept frame's pixels are released once on_frame has had them
	 * (only its metadata stays in the bracket): for a caller that
	 * streams them to disk and into a merge. */
	int release_pixels;
	/* Set (e.g. from a signal handler) to stop: -ECANCELED. */
	atomic_int *cancel;
};

void glint_bracket_default_opts(struct glint_bracket_opts *o);

struct glint_bracket {
	int n;
	struct glint_frame frames[GLINT_BRACKET_MAX]; /* shortest first */
	int used_gain;		       /* exposure ran out: gain was raised */
	int truncated;		       /* a cap stopped it before coverage */
	char stopped_by[8];	       /* then "frame", "time" or "cancel" */
	int covered_low, covered_high; /* the two goals reached */
	/* A goal not reached because the camera has no shorter exposure
	 * or no more exposure x gain: as far as it can go, not cut short. */
	int camera_limit;
	double seconds;		/* the camera's time (exposure and readout) */
	double wall_seconds;	/* on the clock given, preparation excluded */
	double metered_start_s; /* where it started */
	int metering_frames;	/* frames spent metering apart */
	int superseded; /* unclipped frames a longer unclipped one replaced
			   (captured, not kept) */
};

int glint_bracket_capture(struct glint_camera *cam, const struct glint_roi *roi,
			  const struct glint_bracket_opts *o,
			  const struct glint_clock *clock,
			  struct glint_bracket *out);
void glint_bracket_release(struct glint_bracket *b);

/* 0 when the bracket is whole: both goals reached, or reached as far as
 * the camera goes.  Else (a cap or a cancel stopped it first, or it has
 * no frame) an error saying which cap, what it got and which goal it
 * missed: such a bracket is never merged as if it were complete. */
int glint_bracket_verdict(const struct glint_bracket *b,
			  const struct glint_bracket_opts *o);

/* ROI statistics of a frame: clipped sample count (glint_frame_clip_dn)
 * and the 1st percentile
 * of (value - black level). */
void glint_frame_roi_stats(const struct glint_frame *f,
			   const struct glint_roi *roi, int *saturated,
			   double *p01);

/* A start exposure: the one that puts the ROI's 99th percentile near
 * half the range, found in at most 5 frames from 10 ms (fewer when
 * the first lands); frames are not kept.  The bracket calls it only with
 * meter_apart set. */
int glint_bracket_meter(struct glint_camera *cam, const struct glint_roi *roi,
			const struct glint_bracket_opts *o, double *start_s,
			int *frames);

#endif
