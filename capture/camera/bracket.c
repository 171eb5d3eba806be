/* SPDX-License-Identifier: MIT */
#include "capture/camera/bracket.h"

#include "core/error.h"

#include <math.h>
#include <stdio.h>
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

/* Metering apart: its first guess. */
#define METER_FIRST_S 0.01

static int cancelled(const struct glint_bracket_opts *o)
{
	return o->cancel && *o->cancel;
}

/* The ROI's saturated samples and its 1st and 99th percentiles above
 * black, from a histogram of codes: one pass, however large the frame. */
static void roi_stats(const struct glint_frame *f, const struct glint_roi *roi,
		      int *saturated, double *p01, double *p99)
{
	struct glint_roi r = *roi;
	unsigned top = (1u << f->bit_depth) - 1;
	size_t n = 0;

	if (r.x1 <= r.x0 || r.y1 <= r.y0) {
		r.x0 = r.y0 = 0;
		r.x1 = f->width;
		r.y1 = f->height;
	}
	int ch = f->channels > 0 ? f->channels : 1;
	size_t *hist = calloc((size_t)top + 1, sizeof(*hist));
	*saturated = 0;
	*p01 = 0;
	if (p99)
		*p99 = 0;
	if (!hist)
		return;
	for (int y = r.y0; y < r.y1; y++) {
		const uint16_t *row =
			f->data + ((size_t)y * f->width + r.x0) * ch;
		for (size_t i = 0; i < (size_t)(r.x1 - r.x0) * ch; i++)
			hist[row[i] > top ? top : row[i]]++;
	}
	for (unsigned c = 0; c <= top; c++)
		n += hist[c];
	/* Clipped as the merge counts it (glint_frame_clip_dn), not only
	 * the top code: a frame whose brightest samples sit between the two
	 * would end the way down while the merge has no value there. */
	unsigned clip = (unsigned)ceil(glint_frame_clip_dn(f));
	*saturated = 0;
	for (unsigned c = clip < top ? clip : top; c <= top; c++)
		*saturated += (int)hist[c];
	/* The quantiles of the codes' distribution, each code standing for
	 * [c - 1/2, c + 1/2) with its samples spread evenly: the k-th sample's
	 * code alone is biased low by half a code on average, which at the
	 * few DN of a dark frame overstates the exposure the floor needs. */
	double q01 = 0.01 * (double)n, q99 = 0.99 * (double)n;
	size_t seen = 0;
	int got01 = 0;
	for (unsigned c = 0; c <= top && n; c++) {
		if (!hist[c])
			continue;
		double before = (double)seen, after = (double)(seen + hist[c]);
		seen += hist[c];
		if (!got01 && after >= q01) {
			*p01 = c - 0.5 + (q01 - before) / (double)hist[c] -
			       f->black_level;
			got01 = 1;
		}
		if (after >= q99) {
			if (p99)
				*p99 = c - 0.5 +
				       (q99 - before) / (double)hist[c] -
				       f->black_level;
			break;
		}
	}
	free(hist);
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
	e = fmin(fmax(METER_FIRST_S, in.exposure_min_s), in.exposure_max_s);
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

static int by_exposure(const void *a, const void *b)
{
	const struct glint_frame *x = a, *y = b;
	double ex = x->exposure_s * x->gain, ey = y->exposure_s * y->gain;
	return (ex > ey) - (ex < ey);
}

/* The planner, driven by glint_camera_stream(): requests run ahead of
 * the frames by the camera's latency, so it decides from what has
 * arrived and predicts where the linear sensor will reach its goals. */
struct planner {
	struct glint_camera_info in;
	const struct glint_bracket_opts *o;
	const struct glint_roi *roi;
	struct glint_camera *cam;
	struct glint_bracket *b;
	double cam_t0, step, e0;
	int phase; /* 0: down from e0, 1: up, 2: no more */
	double next_down, last_up;
	int requested;
	int low_done, high_done, down_exhausted, up_exhausted;
	double best_p01, best_eg; /* darkest-pixel level of the most exposed
				     frame seen, and its exposure x gain */
	double noise_p01;	  /* the lowest seen (<= 0): the read noise's
				     1st percentile, where there is no signal */
	struct glint_frame held;  /* the longest unsaturated frame so far */
	int has_held;
};

static int plan_next(void *ctx, double *e, double *g)
{
	struct planner *p = ctx;
	const struct glint_camera_info *in = &p->in;

	if (p->phase == 2 || (p->low_done && p->high_done))
		return 0;
	/* The caps: frames, and time on the camera's own clock (its
	 * exposures and readouts), so a busy host or a slow simulator
	 * does not cut a bracket short. */
	const char *cap = NULL;
	if (p->requested >= p->o->max_frames ||
	    p->requested >= GLINT_BRACKET_MAX)
		cap = "frame";
	else if (glint_camera_seconds(p->cam) - p->cam_t0 > p->o->max_time_s)
		cap = "time";
	else if (p->o->cancel && *p->o->cancel)
		cap = "cancel";
	if (cap) {
		p->b->truncated = 1;
		snprintf(p->b->stopped_by, sizeof(p->b->stopped_by), "%s", cap);
		p->phase = 2;
		return 0;
	}
	if (p->phase == 0 && (p->low_done || p->down_exhausted))
		p->phase = 1;
	if (p->phase == 0) {
		*e = p->next_down;
		*g = 1;
		if (*e <= in->exposure_min_s * (1 + 1e-9)) {
			*e = in->exposure_min_s;
			p->down_exhausted = 1; /* cannot go darker */
		}
		p->next_down = fmax(*e / p->step, in->exposure_min_s);
		p->requested++;
		return 1;
	}
	if (p->high_done || p->up_exhausted)
		return 0;
	/* Enough requested already, if the sensor is linear?  Predict from
	 * the most exposed frame whose darkest pixels are measurable: their
	 * 1st percentile is the signal's plus the noise's (negative), so the
	 * signal grows from that offset, not from zero (from zero, a frame a
	 * few DN up overstates the need by a third: one long frame too many
	 * on the test card). */
	double b = p->noise_p01;
	if (p->best_p01 - b >= 3) {
		double need =
			p->best_eg * (p->o->floor_dn - b) / (p->best_p01 - b);
		if (p->last_up >= need * 1.05)
			return 0; /* wait for the frames in flight */
	}
	double target = p->last_up * p->step;
	if (target <= in->exposure_max_s) {
		*e = target;
		*g = 1;
	} else if (target / in->exposure_max_s <= in->gain_max) {
		*e = in->exposure_max_s;
		*g = target / in->exposure_max_s;
		p->b->used_gain = 1;
	} else if (p->last_up < in->exposure_max_s * in->gain_max * 0.999) {
		*e = in->exposure_max_s; /* the last step: all there is */
		*g = in->gain_max;
		p->b->used_gain = 1;
	} else {
		p->up_exhausted = 1;
		p->b->camera_limit = 1;
		return 0;
	}
	p->last_up = *e * *g;
	p->requested++;
	return 1;
}

/* A frame into the bracket, and to the caller's on_frame. */
static int keep(struct planner *p, struct glint_frame *f)
{
	struct glint_bracket *b = p->b;
	int ret = 0;

	if (b->n >= GLINT_BRACKET_MAX) {
		glint_frame_release(f);
		return 0;
	}
	b->frames[b->n++] = *f;
	if (p->o->on_frame) {
		ret = p->o->on_frame(f, b->n - 1, p->o->ctx);
		if (ret > 0)
			ret = -EIO;
	}
	if (p->o->release_pixels)
		glint_frame_release(&b->frames[b->n - 1]);
	return ret;
}

static double eg(const struct glint_frame *f)
{
	return f->exposure_s * f->gain;
}

static int got_frame(void *ctx, struct glint_frame *f)
{
	struct planner *p = ctx;
	int sat, ret = 0;
	double p01;

	glint_frame_roi_stats(f, p->roi, &sat, &p01);
	if (sat == 0)
		p->low_done = 1;
	if (p01 >= p->o->floor_dn)
		p->high_done = 1;
	p->noise_p01 = fmin(p->noise_p01, p01);
	if (eg(f) > p->best_eg) {
		p->best_eg = eg(f);
		p->best_p01 = p01;
	}
	/* Of the frames with no saturated ROI sample only the longest is
	 * needed: it holds the brightest pixels unclipped with the most
	 * signal.  So an unsaturated frame waits here until a longer one
	 * replaces it or a saturated one shows it is the longest; the ones
	 * replaced are neither kept nor counted against the frame cap. */
	if (sat == 0) {
		if (p->has_held && eg(f) <= eg(&p->held)) {
			glint_frame_release(f);
			p->requested--;
			p->b->superseded++;
		} else {
			if (p->has_held) {
				glint_frame_release(&p->held);
				p->requested--;
				p->b->superseded++;
			}
			p->held = *f;
			p->has_held = 1;
		}
		return 0;
	}
	if (p->has_held) {
		p->has_held = 0;
		ret = keep(p, &p->held);
		if (ret < 0) {
			glint_frame_release(f);
			return ret;
		}
	}
	return keep(p, f);
}

int glint_bracket_capture(struct glint_camera *cam, const struct glint_roi *roi,
			  const struct glint_bracket_opts *o,
			  const struct glint_clock *clock,
			  struct glint_bracket *b)
{
	struct planner p;
	int ret;

	memset(b, 0, sizeof(*b));
	memset(&p, 0, sizeof(p));
	glint_camera_describe(cam, &p.in);
	if (!p.in.manual_exposure)
		return glint_error_set(ENOTSUP,
				       "camera %s (%s) has no manual exposure "
				       "control: cannot bracket",
				       p.in.name, p.in.backend);
	p.o = o;
	p.roi = roi;
	p.cam = cam;
	p.b = b;
	/* The camera gets ready first (the simulator renders its views):
	 * not part of the bracket's time. */
	ret = glint_camera_start(cam);
	if (ret < 0)
		return ret;
	double wall0 = clock->now(clock->ctx);
	p.cam_t0 = glint_camera_seconds(cam);
	p.step = exp2(o->step_ev);
	/* Start at o->start_s, or at the shortest exposure, and extend both
	 * ways: down from the start, then up from it.  From the shortest
	 * there is only the way up and no metering: each frame is kept and
	 * the goals end the ladder.  Below the scene's needs it spends a few
	 * frames of at most the frame period each, where metering apart
	 * spends frames that each wait out the sensor's latency and are
	 * thrown away, and a start in the middle pays that latency again
	 * when it turns from down to up (bench/capture times all three). */
	double e = o->start_s;
	if (e <= 0 && o->meter_apart) {
		ret = glint_bracket_meter(cam, roi, o, &e, &b->metering_frames);
		if (ret < 0)
			return ret;
	}
	if (e <= 0)
		e = p.in.exposure_min_s;
	e = fmin(fmax(e, p.in.exposure_min_s), p.in.exposure_max_s);
	b->metered_start_s = p.e0 = p.next_down = p.last_up = e;
	struct glint_stream_cb cb = { plan_next, got_frame, &p };
	ret = glint_camera_stream(cam, &cb, o->max_drop, NULL);
	if (ret == 0 && o->cancel && *o->cancel)
		ret = glint_error_set(ECANCELED, "capture cancelled");
	if (p.has_held) {
		p.has_held = 0;
		if (ret == 0)
			ret = keep(&p, &p.held);
		else
			glint_frame_release(&p.held);
	}
	if (ret < 0) {
		glint_bracket_release(b);
		return ret;
	}
	b->covered_low = p.low_done;
	b->covered_high = p.high_done;
	if (b->covered_low && b->covered_high) {
		b->truncated = 0;
		b->stopped_by[0] = '\0';
	}
	if (!b->covered_low && p.down_exhausted)
		b->camera_limit = 1;
	qsort(b->frames, (size_t)b->n, sizeof(b->frames[0]), by_exposure);
	b->seconds = glint_camera_seconds(cam) - p.cam_t0;
	b->wall_seconds = clock->now(clock->ctx) - wall0;
	return 0;
}

int glint_bracket_verdict(const struct glint_bracket *b,
			  const struct glint_bracket_opts *o)
{
	if (b->n == 0)
		return glint_error_set(EIO, "the bracket has no frames");
	if (!b->truncated)
		return 0;
	const struct glint_frame *lo = &b->frames[0],
				 *hi = &b->frames[b->n - 1];
	char cap[96];
	if (!strcmp(b->stopped_by, "frame"))
		snprintf(cap, sizeof(cap), "the frame cap (%d frames)",
			 o->max_frames);
	else if (!strcmp(b->stopped_by, "time"))
		snprintf(cap, sizeof(cap),
			 "the time cap (%g s of the camera's exposure and "
			 "readout)",
			 o->max_time_s);
	else
		snprintf(cap, sizeof(cap), "a cancel");
	return glint_error_set(
		EIO,
		"the bracket was stopped by %s before it covered the scene: "
		"%d frame%s, %.4g s .. %.4g s (gain %.3g), %s%s%s",
		cap, b->n, b->n == 1 ? "" : "s", lo->exposure_s, hi->exposure_s,
		hi->gain,
		b->covered_low ? ""
			       : "the shortest frame still clips the region",
		!b->covered_low && !b->covered_high ? "; " : "",
		b->covered_high ? ""
				: "the longest leaves its darkest pixels "
				  "under the floor");
}

void glint_bracket_release(struct glint_bracket *b)
{
	for (int i = 0; i < b->n; i++)
		glint_frame_release(&b->frames[i]);
	b->n = 0;
}
