/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_HDR_LINEAR_H
#define GLINT_CAPTURE_HDR_HDR_LINEAR_H

/*
 * Merging a bracket of raw (linear) frames into radiance with a per-pixel
 * variance: docs/hdr.md.
 *
 * Per photosite, frame i gives x_i = (DN_i - black) / (t_i g_i) in "DN per
 * second at unity gain" (the session's radiometric unit: a probe and a
 * sample from the same camera share it).  Its variance follows the sensor:
 *   var(DN) = g c (DN - black) + (g c r)^2 + 1/12
 * (shot noise, read noise r electrons, quantisation; c = DN per electron at
 * unity gain), evaluated at the merged estimate (two passes) so bright and
 * dark samples are not biased by their own noise.  Frames are combined with
 * inverse-variance weights; a sample at or above `saturation_dn` gets
 * weight zero (clipped highlights never leak in).  A site clipped in every
 * frame is invalid: its value is the lower bound from the shortest frame.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant; a stream merge belongs to
 * one thread.  Who frees: glint_raw_hdr_release() a merge's arrays,
 * glint_hdr_stream_free() a stream.
 */

#include "capture/camera/camera.h"
#include "core/image.h"

#include <stdint.h>

struct glint_noise_model {
	double dn_per_electron; /* c, at unity gain */
	double read_noise_e;	/* r */
	double saturation_dn;	/* 0: 95 % of the range above black */
};

/* The simulated 12-bit sensor's numbers (sim/sensor.c). */
void glint_noise_default(struct glint_noise_model *m);

/*
 * The conversion gain of a camera glint knows nothing of, from its own
 * bracket (photon transfer): at each site well exposed (5-80 % of the
 * range) in two frames adjacent in exposure, the second frame's value less
 * the first's scaled by their exposure ratio has the variance
 * c (g_b d_b + r^2 g_a d_a) of shot noise; the median of the squared
 * difference over that, over all pairs (at most about 4 M samples), is
 * 0.455 c.  Linear RGB frames (a raw converter's output, whose colour
 * matrix gives each channel its own noise) take the noisiest channel's.
 * m->dn_per_electron is set when at least 1000 sites qualify (*used says
 * how many), else left as it is.  The frames must pass the
 * merge's checks.
 */
int glint_noise_from_bracket(const struct glint_frame *frames, int n,
			     struct glint_noise_model *m, long *used);

/* Per-photosite merge (before demosaicing). */
struct glint_raw_hdr {
	int width, height;
	char format[16]; /* the frames' layout: RGGB16 ... MONO16 */
	float *x;	 /* radiance per site */
	float *var;	 /* its variance */
	uint8_t *valid;	 /* 0: clipped in every frame */
};

/* What the merge saw. */
struct glint_hdr_report {
	int frames;
	long sites, invalid_sites; /* clipped everywhere */
	long dark_sites;	   /* below 3 sigma of read noise everywhere */
	/* Motion check, per pair of frames adjacent in exposure: of the
	 * sites well exposed in both, the fraction disagreeing by more than
	 * 5 sigma (about 6e-7 of them by chance). */
	int pairs;
	double disagree[32];
	long compared[32];
	int moved;	       /* some pair disagrees on > 1 % of > 100 sites */
	double pair_tg[32][2]; /* each pair's exposure x gain (s) */
};

/* 0 for a bracket whose frames agree; for a moved one (rep->moved) an
 * error naming `what` (the session or the files), the pair of frames
 * that disagrees most (by exposure x gain) and on what share of the
 * sites both expose well: frames of another scene among the bracket
 * (probe frames among a sample's) or a rig that moved are refused, never
 * merged into one image. */
int glint_hdr_report_check_moved(const struct glint_hdr_report *rep,
				 const char *what);

int glint_hdr_merge_raw(const struct glint_frame *frames, int n,
			const struct glint_noise_model *noise,
			struct glint_raw_hdr *out,
			struct glint_hdr_report *report);
void glint_raw_hdr_release(struct glint_raw_hdr *h);

/*
 * The same merge folded in frame by frame as a bracket arrives, in any
 * order: memory of the accumulators (12 bytes a site) and one frame held
 * back, where glint_hdr_merge_raw() needs every frame at once (a 12 MP
 * bracket of 22 frames is 540 MB).  Each frame's weight is its variance at
 * an estimate its own noise is not in: the frames folded before it and the
 * one after it (the frame is held back until the next arrives; the last
 * one uses those before it).  The merged variance is evaluated at the
 * final estimate over the frames unclipped at the site, as the batch
 * merge's second pass.  The motion check compares frames adjacent in
 * arrival order (a bracket going up in exposure: adjacent in exposure).
 * At most GLINT_HDR_STREAM_MAX frames.
 */
#define GLINT_HDR_STREAM_MAX 32
struct glint_hdr_stream;

int glint_hdr_stream_new(const struct glint_noise_model *noise,
			 struct glint_hdr_stream **out);
/* Fold frame f in (its pixels are copied: the caller keeps f).  An error
 * leaves the stream unusable but still to be freed. */
int glint_hdr_stream_add(struct glint_hdr_stream *s,
			 const struct glint_frame *f);
/* The merged bracket (*out is the caller's, as glint_hdr_merge_raw's);
 * the stream's accumulators become out's images, so the stream is empty
 * afterwards (free it). */
int glint_hdr_stream_finish(struct glint_hdr_stream *s,
			    struct glint_raw_hdr *out,
			    struct glint_hdr_report *report);
void glint_hdr_stream_free(struct glint_hdr_stream *s);

/*
 * Demosaic to RGB (bilinear per channel: a site's own colour is kept, the
 * other two are the mean of the nearest valid sites of that colour in its
 * 3x3 neighbourhood) with variances propagated (the mean of k sites has
 * the sum of their variances over k^2; neighbouring output pixels share
 * sites, so their errors correlate).  MONO16 gives grey.  valid is 1 where
 * every channel had a valid site, else 0 (variance 0 there: weight 0).
 */
int glint_hdr_demosaic(const struct glint_raw_hdr *raw,
		       struct glint_image **radiance,
		       struct glint_image **variance,
		       struct glint_image **valid);

#endif
