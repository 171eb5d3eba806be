/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_CAMERA_CAMERA_H
#define GLINT_CAPTURE_CAMERA_CAMERA_H

/*
 * Cameras behind one interface: an ops table per backend (sim today; V4L2
 * and libcamera next), an opaque handle, and generic logic on top that
 * only returns frames whose *applied* exposure and gain are the requested
 * ones (real sensors apply a new exposure a few frames late).
 *
 * Time comes from an injectable clock so that the simulated camera's frame
 * timing (frame period >= exposure) runs instantly in tests.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (the device and the control).  Threads: a camera
 * is driven by one thread; the backend list is set once before any camera
 * opens.  Who frees: glint_camera_close() a camera, glint_frame_release()
 * each captured frame (frames outlive their camera).
 */

#include "core/clock.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GLINT_CAMERA_MAX_FORMATS 128 /* vivid offers over 80 */

struct glint_camera_info {
	char backend[16];
	char name[64];
	int width, height;
	int nformats;
	char formats[GLINT_CAMERA_MAX_FORMATS][16]; /* e.g. "RGGB16" */
	int bit_depth;	     /* of the configured format */
	int manual_exposure; /* exposure can be set with AE off */
	double exposure_min_s, exposure_max_s, exposure_step_s;
	double gain_min, gain_max, gain_step;
	double frame_period_min_s; /* fastest frame period */
	/* Frames between a set_exposure() and the first frame exposed with
	 * it, at most (how deep to pipeline requests). */
	int latency_frames;
	char exposure_control[40]; /* how exposure is set, for the record */
	char gain_control[40];
	char detail[96]; /* driver, bus, path */
};

/* One frame as captured. */
struct glint_frame {
	int width, height;
	/* Layout of data: "RGGB16" (also GRBG16, GBRG16, BGGR16): Bayer, one
	 * uint16 per pixel; "MONO16": one per pixel; "RGB16": three per
	 * pixel.  Values are the camera's numbers, right-aligned. */
	char format[16];
	char source_format[16]; /* as the camera delivered it, e.g. "pRCC" */
	int channels;		/* samples per pixel: 1 or 3 */
	int bit_depth;		/* significant bits */
	int linear;		/* 0: the camera encoded it (YUYV, RGB24) */
	uint16_t *data;		/* width * height * channels, owned */
	double exposure_s;	/* applied, as the camera reports it */
	double gain;		/* applied analogue gain */
	double black_level;	/* DN */
	/* DN where the sensor saturates (a raw file's WhiteLevel, e.g. 15520
	 * of a 14-bit range); 0: the top code, 2^bit_depth - 1. */
	double white_level;
	/* Exposure window on the clock given to glint_camera_open()
	 * (V4L2: CLOCK_MONOTONIC, which glint_clock_real is). */
	double t_start, t_end;
	uint64_t sequence;
};

void glint_frame_release(struct glint_frame *f);

/* Where a frame's samples count as clipped when the sensor's own
 * saturation is not known: 95 % of the range above black (a sensor's
 * response bends before its top code).  The bracket planner and the merge
 * use the same level, so a bracket covers what the merge can use. */
static inline double glint_frame_white_dn(const struct glint_frame *f)
{
	return f->white_level > 0 ? f->white_level
				  : (double)((1u << f->bit_depth) - 1);
}

static inline double glint_frame_clip_dn(const struct glint_frame *f)
{
	double top = glint_frame_white_dn(f);
	return f->black_level + 0.95 * (top - f->black_level);
}

struct glint_camera_ops {
	/* Backend name ("sim", "v4l2", "libcamera"). */
	const char *name;
	/* Open `device` (backend-specific; NULL = the first/default). */
	int (*open)(const char *device, const struct glint_clock *clock,
		    void **priv);
	/* Release everything. */
	void (*close)(void *priv);
	/* Capabilities of the opened camera. */
	int (*describe)(void *priv, struct glint_camera_info *info);
	/* Choose the format: raw Bayer at the highest bit depth if offered,
	 * else the most linear one. */
	int (*configure)(void *priv);
	/* Request exposure and gain with auto exposure off (takes effect
	 * after the camera's latency); on return both hold the values the
	 * camera will apply (its quantisation of the request). */
	int (*set_exposure)(void *priv, double *exposure_s, double *gain);
	/* The next frame, with what was applied to it. */
	int (*grab)(void *priv, struct glint_frame *frame);
	/* Optional: device names this backend can open, one per call of
	 * `found`; returns the count or a negative errno. */
	int (*enumerate)(void (*found)(const char *device, void *ctx),
			 void *ctx);
	/* Optional: get ready to deliver frames at once (the simulated
	 * camera renders or loads its views), so that no frame waits on
	 * work the camera would not do.  Called once, before the first
	 * request of a capture or stream. */
	int (*start)(void *priv);
};

struct glint_camera;

/* Open a camera by backend name and device: *out is the caller's, closed
 * with glint_camera_close().  clock (may be NULL: the real one) must
 * outlive the camera. */
int glint_camera_open(const char *backend, const char *device,
		      const struct glint_clock *clock,
		      struct glint_camera **out);
void glint_camera_close(struct glint_camera *cam);
int glint_camera_describe(struct glint_camera *cam,
			  struct glint_camera_info *info);

/* The backend's start(), once (a no-op after the first and for a backend
 * without one); glint_camera_capture() and glint_camera_stream() call it
 * themselves, so a caller needs it only to do that work at a time of its
 * choosing. */
int glint_camera_start(struct glint_camera *cam);

/* Seconds of exposure and readout of every frame the camera has delivered
 * since it was opened, as it reports them (each frame's applied exposure,
 * or the fastest frame period when that is longer): the camera's own
 * time, which the host's load does not stretch.  Bracket caps count it. */
double glint_camera_seconds(const struct glint_camera *cam);

/*
 * A frame exposed as requested: set exposure and gain, then grab frames,
 * dropping those whose applied values differ from the request by more
 * than the camera's step, until one matches (at most max_drop frames).
 * Fails, naming the control, on a camera without manual exposure or a
 * request outside its range.  *dropped (may be NULL) counts drops.
 */
int glint_camera_capture(struct glint_camera *cam, double exposure_s,
			 double gain, int max_drop, struct glint_frame *frame,
			 int *dropped);

/*
 * Pipelined capture: frames at a planned sequence of exposures, each
 * requested while earlier ones are still in flight, so the camera's
 * latency costs frames once per stream instead of once per exposure.
 * plan() gives the next request (returns 0 when there are no more; it is
 * asked again later, so it may wait for frames); got() receives each
 * frame whose applied values match a request, in request order, and owns
 * its data (a negative return stops the stream with that error).  A
 * frame matching no outstanding request is dropped (at most max_drop in
 * a row).  Returns when plan() has no more and every request has arrived.
 */
struct glint_stream_cb {
	int (*plan)(void *ctx, double *exposure_s, double *gain);
	int (*got)(void *ctx, struct glint_frame *frame);
	void *ctx;
};
int glint_camera_stream(struct glint_camera *cam,
			const struct glint_stream_cb *cb, int max_drop,
			int *dropped);

/* The real backends built into capture/ (V4L2 and libcamera when their
 * meson features are on).  The simulated camera is sim/'s. */
extern const struct glint_camera_ops glint_camera_v4l2_ops;
extern const struct glint_camera_ops glint_camera_libcamera_ops;

/*
 * The backends glint_camera_open() chooses from by name: a NULL-terminated
 * list in static storage, set once by the program before any camera is
 * opened (cmd/backends.c registers the real ones and sim's).  Until then
 * the list is empty and every open fails naming no backend.
 */
void glint_camera_backends_set(const struct glint_camera_ops *const *list);
/* The registered list (never NULL; valid for the program's lifetime). */
const struct glint_camera_ops *const *glint_camera_backends(void);

/* Backend libraries' own logging (libcamera's): silenced unless on. */
void glint_camera_set_verbose(int on);
int glint_camera_verbose(void);

#ifdef __cplusplus
}
#endif

#endif
