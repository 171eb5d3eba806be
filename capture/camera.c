/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "camera.h"

#include "core/error.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double real_now(void *ctx)
{
	struct timespec ts;
	(void)ctx;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void real_sleep_until(void *ctx, double t)
{
	struct timespec ts;
	ts.tv_sec = (time_t)t;
	ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
	(void)ctx;
	while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) ==
	       EINTR)
		;
}

const struct glint_clock glint_clock_real = { real_now, real_sleep_until,
					      NULL };

static double fake_now(void *ctx)
{
	return ((struct glint_fake_clock *)ctx)->t;
}

static void fake_sleep_until(void *ctx, double t)
{
	struct glint_fake_clock *fc = ctx;
	if (t > fc->t)
		fc->t = t;
}

struct glint_clock glint_clock_fake(struct glint_fake_clock *fc)
{
	struct glint_clock c = { fake_now, fake_sleep_until, fc };
	return c;
}

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
	void *priv;
	struct glint_camera_info info;
};

int glint_camera_open(const char *backend, const char *device,
		      const struct glint_clock *clock,
		      struct glint_camera **out)
{
	const struct glint_camera_ops *ops = NULL;
	struct glint_camera *cam;
	int ret;

	*out = NULL;
	char names[64] = "";
	for (int i = 0; glint_camera_backends[i]; i++) {
		size_t n = strlen(names);
		if (!strcmp(glint_camera_backends[i]->name, backend))
			ops = glint_camera_backends[i];
		snprintf(names + n, sizeof(names) - n, "%s%s", i ? ", " : "",
			 glint_camera_backends[i]->name);
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

int glint_camera_capture(struct glint_camera *cam, double exposure_s,
			 double gain, int max_drop, struct glint_frame *frame,
			 int *dropped)
{
	const struct glint_camera_info *in = &cam->info;
	int ret;

	memset(frame, 0, sizeof(*frame));
	if (dropped)
		*dropped = 0;
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
	ret = cam->ops->set_exposure(cam->priv, &exposure_s, &gain);
	if (ret < 0)
		return ret;
	double tol_e = fmax(0.5 * in->exposure_step_s, 1e-9 * exposure_s);
	for (int k = 0; k <= max_drop; k++) {
		ret = cam->ops->grab(cam->priv, frame);
		if (ret < 0)
			return ret;
		if (fabs(frame->exposure_s - exposure_s) <= tol_e &&
		    fabs(frame->gain - gain) <=
			    fmax(0.5 * in->gain_step, 1e-6 * gain))
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
