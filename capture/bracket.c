/* SPDX-License-Identifier: MIT */
#include "bracket.h"

#include "core/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void glint_bracket_default_opts(struct glint_bracket_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->step_ev = 1;
	o->max_frames = 24;
	o->max_time_s = 60;
	o->start_s = 0;
	o->floor_dn = 16;
	o->max_drop = 6;
}

static int cancelled(const struct glint_bracket_opts *o)
{
	return o->cancel && *o->cancel;
}

static int cmp_u16(const void *a, const void *b)
{
	return (int)*(const uint16_t *)a - (int)*(const uint16_t *)b;
}

static void roi_stats(const struct glint_frame *f, const struct glint_roi *roi,
		      int *saturated, double *p01, double *p99)
{
	struct glint_roi r = *roi;
	uint16_t top = (uint16_t)((1u << f->bit_depth) - 1);
	int n = 0;

	if (r.x1 <= r.x0 || r.y1 <= r.y0) {
		r.x0 = r.y0 = 0;
		r.x1 = f->width;
		r.y1 = f->height;
	}
	int ch = f->channels > 0 ? f->channels : 1;
	uint16_t *v = malloc((size_t)(r.x1 - r.x0) * (r.y1 - r.y0) * ch *
			     sizeof(uint16_t));
	*saturated = 0;
	*p01 = 0;
	if (p99)
		*p99 = 0;
	if (!v)
		return;
	for (int y = r.y0; y < r.y1; y++)
		for (int x = r.x0; x < r.x1; x++)
			for (int c = 0; c < ch; c++) {
				uint16_t d = f->data[((size_t)y * f->width +
						      x) * ch +
						     c];
				*saturated += d >= top;
				v[n++] = d;
			}
	qsort(v, (size_t)n, sizeof(uint16_t), cmp_u16);
	*p01 = v[(size_t)(0.01 * (n - 1))] - f->black_level;
	if (p99)
		*p99 = v[(size_t)(0.99 * (n - 1))] - f->black_level;
	free(v);
}

void glint_frame_roi_stats(const struct glint_frame *f,
			   const struct glint_roi *roi, int *saturated,
			   double *p01)
{
	roi_stats(f, roi, saturated, p01, NULL);
}

int glint_bracket_meter(struct glint_camera *cam, const struct glint_roi *roi,
			const struct glint_bracket_opts *o, double *start_s,
			int *frames)
{
	struct glint_camera_info in;
	struct glint_frame f;
	double e, p01, p99;
	int sat, ret;

	glint_camera_describe(cam, &in);
	e = fmin(fmax(0.01, in.exposure_min_s), in.exposure_max_s);
	*frames = 0;
	for (int k = 0; k < 5; k++) {
		if (cancelled(o))
			return glint_error_set(ECANCELED, "capture cancelled");
		ret = glint_camera_capture(cam, e, 1, o->max_drop, &f, NULL);
		if (ret < 0)
			return ret;
		(*frames)++;
		roi_stats(&f, roi, &sat, &p01, &p99);
		double range = (1 << f.bit_depth) - 1 - f.black_level;
		glint_frame_release(&f);
		double next;
		if (p99 >= 0.98 * range)
			next = e / 16; /* clipped: no measure, jump down */
		else if (p99 >= 0.25 * range && p99 <= 0.75 * range)
			break;
		else
			next = e * 0.5 * range / fmax(p99, 1);
		next = fmin(fmax(next, in.exposure_min_s), in.exposure_max_s);
		if (fabs(next - e) <= 0.5 * in.exposure_step_s)
			break; /* at a limit */
		e = next;
	}
	*start_s = e;
	return 0;
}

static int take(struct glint_camera *cam, double e, double g,
		const struct glint_bracket_opts *o, struct glint_bracket *b,
		struct glint_frame *f)
{
	if (b->n >= GLINT_BRACKET_MAX || b->n >= o->max_frames) {
		b->truncated = 1;
		return 1;
	}
	if (cancelled(o))
		return glint_error_set(ECANCELED, "capture cancelled");
	int ret = glint_camera_capture(cam, e, g, o->max_drop, f, NULL);
	if (ret < 0)
		return ret;
	b->frames[b->n++] = *f;
	if (o->on_frame) {
		ret = o->on_frame(f, b->n - 1, o->ctx);
		if (ret)
			return ret < 0 ? ret : -EIO;
	}
	return 0;
}

static int by_exposure(const void *a, const void *b)
{
	const struct glint_frame *x = a, *y = b;
	double ex = x->exposure_s * x->gain, ey = y->exposure_s * y->gain;
	return (ex > ey) - (ex < ey);
}

int glint_bracket_capture(struct glint_camera *cam, const struct glint_roi *roi,
			  const struct glint_bracket_opts *o,
			  const struct glint_clock *clock,
			  struct glint_bracket *b)
{
	struct glint_camera_info in;
	struct glint_frame f;
	double t0 = clock->now(clock->ctx), step = exp2(o->step_ev);
	int sat, ret;
	double p01;

	memset(b, 0, sizeof(*b));
	glint_camera_describe(cam, &in);
	if (!in.manual_exposure)
		return glint_error_set(ENOTSUP,
				       "camera %s (%s) has no manual exposure "
				       "control: cannot bracket",
				       in.name, in.backend);
	/* Start at o->start_s or a metered exposure, and extend both ways. */
	double e = o->start_s;
	if (e <= 0) {
		ret = glint_bracket_meter(cam, roi, o, &e, &b->metering_frames);
		if (ret < 0)
			return ret;
	}
	e = fmin(fmax(e, in.exposure_min_s), in.exposure_max_s);
	b->metered_start_s = e;
	ret = take(cam, e, 1, o, b, &f);
	if (ret < 0)
		goto err;
	double e0 = e;
	/* Down until nothing in the ROI saturates. */
	glint_frame_roi_stats(&f, roi, &sat, &p01);
	while (sat > 0 && !ret) {
		if (e / step < in.exposure_min_s) {
			if (e <= in.exposure_min_s)
				break; /* cannot go darker */
			e = in.exposure_min_s;
		} else {
			e /= step;
		}
		if (clock->now(clock->ctx) - t0 > o->max_time_s) {
			b->truncated = 1;
			break;
		}
		ret = take(cam, e, 1, o, b, &f);
		if (ret == 0)
			glint_frame_roi_stats(&f, roi, &sat, &p01);
	}
	if (ret < 0)
		goto err;
	b->covered_low = sat == 0;
	/* Up from the start until the darkest ROI pixels clear the floor. */
	e = e0;
	double g = 1;
	f = b->frames[0];
	glint_frame_roi_stats(&f, roi, &sat, &p01);
	ret = 0;
	while (p01 < o->floor_dn && !ret) {
		/* Exposure x gain steps by exactly step_ev; gain makes up
		 * what the longest exposure cannot. */
		double target = e * g * step;
		if (target <= in.exposure_max_s) {
			e = target;
			g = 1;
		} else if (target / in.exposure_max_s <= in.gain_max) {
			e = in.exposure_max_s;
			g = target / in.exposure_max_s;
			b->used_gain = 1;
		} else {
			break; /* exposure and gain exhausted */
		}
		if (clock->now(clock->ctx) - t0 > o->max_time_s) {
			b->truncated = 1;
			break;
		}
		ret = take(cam, e, g, o, b, &f);
		if (ret == 0)
			glint_frame_roi_stats(&f, roi, &sat, &p01);
	}
	if (ret < 0)
		goto err;
	b->covered_high = p01 >= o->floor_dn;
	qsort(b->frames, (size_t)b->n, sizeof(b->frames[0]), by_exposure);
	b->seconds = clock->now(clock->ctx) - t0;
	return 0;
err:
	glint_bracket_release(b);
	return ret;
}

void glint_bracket_release(struct glint_bracket *b)
{
	for (int i = 0; i < b->n; i++)
		glint_frame_release(&b->frames[i]);
	b->n = 0;
}
