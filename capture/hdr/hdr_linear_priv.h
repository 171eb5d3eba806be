/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_HDR_LINEAR_PRIV_H
#define GLINT_CAPTURE_HDR_HDR_LINEAR_PRIV_H

/*
 * What the batch merge (hdr_linear.c) and the streaming merge
 * (hdr_stream.c) share: the checks on a frame and the per-frame constants
 * of the noise model.  Private to capture/.
 */

#include "capture/hdr/hdr_linear.h"

/* Frame `i` is one the linear merge takes, and matches `first` (frame 0;
 * NULL when it is frame 0). */
int glint_hdr_check_frame(const struct glint_frame *f, int i,
			  const struct glint_frame *first);

/* What every site needs of one frame, computed once per merge. */
struct merge_frame {
	const uint16_t *data;
	double black, sat, top; /* DN: black level, clipping, full scale */
	double tg;		/* exposure x gain */
	double gc;		/* DN per electron at this gain */
	double floor_var;	/* read noise and quantisation, DN^2 */
	double inv_tg2;
};

void glint_merge_frame_init(struct merge_frame *k, const struct glint_frame *f,
			    const struct glint_noise_model *m);

/* Variance of x = (DN - black) / (t g) when the expected signal is d DN. */
static inline double glint_merge_var_x(const struct merge_frame *k, double d)
{
	return (k->gc * (d > 0 ? d : 0) + k->floor_var) * k->inv_tg2;
}

/* A pair of frames' values at one site, for the motion check: 1 when both
 * are well exposed (2 % .. 90 % of the range), with *z their difference per
 * unit exposure over its sigma at the estimate xhat. */
int glint_merge_pair_z(const struct merge_frame *a, const struct merge_frame *b,
		       size_t s, double xhat, double *z);

/* The report's pair fractions from its counts and the moved flag; then
 * an error (out released) when no site has a usable value.  shortest_tg:
 * the shortest frame's exposure x gain, for the message. */
int glint_hdr_report_finish(struct glint_hdr_report *rep,
			    struct glint_raw_hdr *out, double shortest_tg);

#endif
