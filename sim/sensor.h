/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_SENSOR_H
#define GLINT_SIM_SENSOR_H

/*
 * A linear camera sensor: scene radiance L becomes electrons
 *   e ~ Poisson(L * k * t)  (+ Gaussian read noise, clipped at full well)
 * and raw numbers  DN = round(g * e + black), clipped to [0, 2^bits - 1].
 * k (electrons per unit radiance per second) folds aperture, pixel area and
 * quantum efficiency together.  Noise-free mode: e = L k t exactly (still
 * clipped and quantised unless `quantise` is off).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant; a sensor's state is the
 * caller's.  Who frees: nothing (the caller's images).
 */

#include "core/image.h"

#include <stdint.h>

struct glint_sensor {
	double exposure_s;   /* t */
	double gain;	     /* g: DN per electron */
	double k;	     /* electrons per (radiance unit x second) */
	double read_noise_e; /* RMS electrons */
	double black_level;  /* DN */
	double full_well_e;  /* electrons */
	int bits;	     /* ADC bits */
	int noise;	     /* 0: noise-free */
	int quantise;	     /* 0: keep DN as real numbers (exact checks) */
	uint64_t seed;
};

/* A 12-bit machine-vision-like sensor (docs/conventions.md). */
void glint_sensor_default(struct glint_sensor *s);

/* Raw DN image (as floats) of radiance; same size. */
int glint_sensor_capture(const struct glint_sensor *s,
			 const struct glint_image *radiance,
			 struct glint_image *dn);

/*
 * Back to radiance, (DN - black) / (g k t), and per-pixel weights for the
 * fit: 1 / variance of that estimate (shot + read + quantisation noise),
 * 0 where any channel is saturated (at full well or the ADC maximum) or
 * not finite.  weight may be NULL.
 */
int glint_sensor_to_radiance(const struct glint_sensor *s,
			     const struct glint_image *dn,
			     struct glint_image *radiance,
			     struct glint_image *weight);

/* The exposure time that puts radiance `l` at fraction `level` of the
 * ADC range. */
double glint_sensor_exposure_for(const struct glint_sensor *s, double l,
				 double level);

#endif
