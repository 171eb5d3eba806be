/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "capture/camera/camera.h"

#include "core/error.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void glint_frame_release(struct glint_frame *f)
{
	free(f->data);
	f->data = NULL;
}

static int verbose;

void glint_camera_set_verbose(int on)
{
	verbose = on;
}

int glint_camera_verbose(void)
{
	return verbose;
}

struct glint_camera {
	const struct glint_camera_ops *ops;
	struct glint_clock clock;
	void *priv;
	struct glint_camera_info info;
	double seconds; /* exposure and readout of every frame grabbed */
	int started;	/* ops->start() has run */
};

static const struct glint_camera_ops *const no_backends[] = { NULL };
static const struct glint_camera_ops *const *registered = no_backends;

void glint_camera_backends_set(const struct glint_camera_ops *const *list)
{
	registered = list ? list : no_backends;
}

const struct glint_camera_ops *const *glint_camera_backends(void)
{
	return registered;
}

int glint_camera_open(const char *backend, const char *device,
		      const struct glint_clock *clock,
		      struct glint_camera **out)
{
	const struct glint_camera_ops *ops = NULL;
	struct glint_camera *cam;
	int ret;

	*out = NULL;
	char names[64] = "";
	const struct glint_camera_ops *const *list = glint_camera_backends();
	for (int i = 0; list[i]; i++) {
		size_t n = strlen(names);
		if (!strcmp(list[i]->name, backend))
			ops = list[i];
		snprintf(names + n, sizeof(names) - n, "%s%s", i ? ", " : "",
			 list[i]->name);
	}
	if (!ops)
		return glint_error_set(EINVAL,
				       "camera backend '%s': this glint has "
				       "%s",
				       backend, names);
	cam = calloc(1, sizeof(*cam));
	if (!cam)
		return glint_error_set(ENOMEM, "out of memory");
	cam->ops = ops;
	cam->clock = clock ? *clock : glint_clock_real;
	ret = ops->open(device, clock ? clock : &glint_clock_real, &cam->priv);
	if (ret < 0)
		goto err_open;
	ret = ops->configure(cam->priv);
	if (!ret)
		ret = ops->describe(cam->priv, &cam->info);
	if (ret < 0)
		goto err_config;
	*out = cam;
	return 0;
err_config:
	ops->close(cam->priv);
err_open:
	free(cam);
	return ret;
}

void glint_camera_close(struct glint_camera *cam)
{
	if (!cam)
		return;
	cam->ops->close(cam->priv);
	free(cam);
}

int glint_camera_describe(struct glint_camera *cam,
			  struct glint_camera_info *info)
{
	*info = cam->info;
	return 0;
}

double glint_camera_seconds(const struct glint_camera *cam)
{
	return cam->seconds;
}

/* A frame from the backend, its exposure and readout counted on the
 * camera's own time: the applied exposure, or the fastest frame period
 * when that is longer (the sensor cannot read out faster).  What the host
 * does between frames (a busy machine, the simulator's rendering) is not
 * the camera's time. */
static int grab(struct glint_camera *cam, struct glint_frame *f)
{
	int ret = cam->ops->grab(cam->priv, f);
	if (ret == 0 && f->exposure_s > 0)
		cam->seconds +=
			fmax(f->exposure_s, cam->info.frame_period_min_s);
	return ret;
}

int glint_camera_start(struct glint_camera *cam)
{
	if (cam->started || !cam->ops->start)
		return 0;
	int ret = cam->ops->start(cam->priv);
	if (ret == 0)
		cam->started = 1;
	return ret;
}

static int check_request(const struct glint_camera_info *in, double exposure_s,
			 double gain)
{
	if (!in->manual_exposure)
		return glint_error_set(ENOTSUP,
				       "camera %s (%s) has no manual exposure "
				       "control: cannot bracket",
				       in->name, in->backend);
	if (exposure_s < in->exposure_min_s || exposure_s > in->exposure_max_s)
		return glint_error_set(ERANGE,
				       "camera %s: exposure %g s outside its "
				       "range [%g, %g] s",
				       in->name, exposure_s, in->exposure_min_s,
				       in->exposure_max_s);
	if (gain < in->gain_min || gain > in->gain_max)
		return glint_error_set(ERANGE,
				       "camera %s: gain %g outside its range "
				       "[%g, %g]",
				       in->name, gain, in->gain_min,
				       in->gain_max);
	return 0;
}

/* Does a frame carry the (quantised) request? */
static int matches(const struct glint_camera_info *in,
		   const struct glint_frame *f, double exposure_s, double gain)
{
	double tol_e = fmax(0.5 * in->exposure_step_s, 1e-9 * exposure_s);
	return fabs(f->exposure_s - exposure_s) <= tol_e &&
	       fabs(f->gain - gain) <= fmax(0.5 * in->gain_step, 1e-6 * gain);
}

int glint_camera_capture(struct glint_camera *cam, double exposure_s,
			 double gain, int max_drop, struct glint_frame *frame,
			 int *dropped)
{
	const struct glint_camera_info *in = &cam->info;
	int ret;

	memset(frame, 0, sizeof(*frame));
	if (dropped)
		*dropped = 0;
	ret = check_request(in, exposure_s, gain);
	if (ret == 0)
		ret = glint_camera_start(cam);
	if (ret < 0)
		return ret;
	ret = cam->ops->set_exposure(cam->priv, &exposure_s, &gain);
	if (ret < 0)
		return ret;
	for (int k = 0; k <= max_drop; k++) {
		ret = grab(cam, frame);
		if (ret < 0)
			return ret;
		if (matches(in, frame, exposure_s, gain))
			return 0;
		glint_frame_release(frame);
		if (dropped)
			(*dropped)++;
	}
	return glint_error_set(ETIMEDOUT,
			       "camera %s: exposure %g s / gain %g not "
			       "applied after %d frames",
			       in->name, exposure_s, gain, max_drop + 1);
}

#define STREAM_MAX 32

int glint_camera_stream(struct glint_camera *cam,
			const struct glint_stream_cb *cb, int max_drop,
			int *dropped)
{
	const struct glint_camera_info *in = &cam->info;
	double want_e[STREAM_MAX], want_g[STREAM_MAX];
	int n = 0, drops = 0, planning = 1, fresh = 1, ret;
	int depth = in->latency_frames + 1;
	double t_write = 0;

	if (dropped)
		*dropped = 0;
	if (depth > STREAM_MAX)
		depth = STREAM_MAX;
	ret = glint_camera_start(cam);
	if (ret < 0)
		return ret;
	for (;;) {
		/* One request per frame keeps `depth` in flight: the next
		 * only once a frame has started since the last one (frames
		 * queued before it do not count: a host slower than the
		 * camera would otherwise write faster than frames start, and
		 * a sensor keeps only the last of several writes). */
		if (planning && n < depth && (fresh || n == 0)) {
			double e, g;
			if (cb->plan(cb->ctx, &e, &g)) {
				ret = check_request(in, e, g);
				if (ret == 0)
					ret = cam->ops->set_exposure(cam->priv,
								     &e, &g);
				if (ret < 0)
					return ret;
				want_e[n] = e;
				want_g[n++] = g;
				t_write = cam->clock.now(cam->clock.ctx);
				fresh = 0;
			} else if (n == 0) {
				planning = 0;
			}
		}
		if (n == 0 && !planning)
			return 0;
		if (n == 0)
			continue; /* plan() is waiting for nothing: ask again */
		struct glint_frame f;
		ret = grab(cam, &f);
		if (ret < 0)
			return ret;
		if (f.t_start >= t_write)
			fresh = 1;
		int j = 0;
		while (j < n && !matches(in, &f, want_e[j], want_g[j]))
			j++;
		if (j == n) {
			glint_frame_release(&f);
			if (dropped)
				(*dropped)++;
			if (++drops > max_drop)
				return glint_error_set(
					ETIMEDOUT,
					"camera %s: exposure %g s / gain %g "
					"not applied after %d frames",
					in->name, want_e[0], want_g[0], drops);
			continue;
		}
		/* Requests before j were overtaken (the camera merged
		 * writes): forget them. */
		n -= j + 1;
		memmove(want_e, want_e + j + 1, (size_t)n * sizeof(double));
		memmove(want_g, want_g + j + 1, (size_t)n * sizeof(double));
		drops = 0;
		ret = cb->got(cb->ctx, &f);
		if (ret < 0)
			return ret;
	}
}
