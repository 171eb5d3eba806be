/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_HDR_HDR_RESPONSE_H
#define GLINT_CAPTURE_HDR_HDR_RESPONSE_H

/*
 * 8-bit (camera-encoded) brackets: recover the camera's response curve,
 * then merge.  docs/hdr.md states the methods and the test numbers.
 *
 * A response is 256 x 3 values: exposure (relative radiance x time)
 * producing each code value, per channel, normalised so code 128 maps
 * to 1.
 *
 * Debevec & Malik (SIGGRAPH 1997): least squares for g = ln(response) and
 * the log irradiance of sample pixels, with g(128) = 0, a second-difference
 * smoothness term weighted by lambda, and the hat weight
 * w(z) = min(z - floor, 255 - z) + 1, 0 at or below the floor (with
 * floor 0 this is OpenCV's CalibrateDebevec hat).
 * Sample pixels: OpenCV's grid (samples = 70: 6 x 11 on a 512 x 768
 * image), so results are comparable.
 *
 * Robertson, Borman & Stevenson (1999): alternate the irradiance estimate
 * E_j = sum_i w t_i I(z_ij) / sum_i w t_i^2 and the response
 * I(m) = mean over samples at code m of t_i E_j, with the weight
 * exp(-4 (z - 127.5)^2 / 127.5^2), all pixels, until the response changes
 * by less than `threshold`.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: images out with
 * glint_image_free().
 */

#include "core/image.h"

#include <stdint.h>

struct glint_ldr_stack {
	int n, width, height;
	const uint8_t *const *rgb; /* n images, width * height * 3 bytes */
	const double *times;	   /* exposure times, seconds */
};

struct glint_debevec_opts {
	int samples;   /* default 70 */
	double lambda; /* default 10 */
	/* Codes at or below floor[c] carry no information (the camera's
	 * black level and noise): weight 0.  -1: estimate it (see
	 * glint_ldr_floor); 0: none, as OpenCV. */
	int floor[3];
};

void glint_debevec_default_opts(struct glint_debevec_opts *o);

/* Per channel, the code below which a stack holds no signal: 3 codes above
 * the 5th percentile of its shortest exposure (where nearly everything
 * is black). */
void glint_ldr_floor(const struct glint_ldr_stack *s, int floor[3]);

/*
 * Does the stack's brightness rise with its exposure times?  For each
 * frame and the next longer one, per channel, over pixels informative in
 * both (above the floor, below 255): a longer exposure must make most of
 * those that change brighter (at least half; a true bracket gives nearly
 * all, frames in the wrong order for their times nearly none), and two
 * frames must not be identical (a duplicated file).  names[i] (may be
 * NULL) names frame i in the message.
 */
int glint_ldr_check_order(const struct glint_ldr_stack *s,
			  const char *const *names);

int glint_response_debevec(const struct glint_ldr_stack *s,
			   const struct glint_debevec_opts *o,
			   double response[256][3]);

int glint_response_robertson(const struct glint_ldr_stack *s, int max_iter,
			     double threshold, double response[256][3],
			     int *iterations);

/*
 * Merge with a response (Debevec's weighted mean of log irradiance,
 * ln E = sum w(z) (ln I(z) - ln t) / sum w(z), per channel, hat weight
 * zero at 255 and at or below floor[c]: clipped and black samples never
 * contribute).  valid is 0 where every frame was clipped or black in a
 * channel.  floor may be NULL (estimated); valid may be NULL.  *out and
 * *valid are the caller's, freed with glint_image_free().
 */
int glint_ldr_merge(const struct glint_ldr_stack *s,
		    const double response[256][3], const int *floor,
		    struct glint_image **out, struct glint_image **valid);

#endif
