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
 * Before the sensor, the optics (glint_sensor_optics): a real lens and the
 * optical low-pass filter in front of a Bayer sensor spread a point of
 * light over several photosites, so that every colour of the mosaic sees
 * it.  The point-spread function here is a Gaussian of `psf_sigma_px`
 * (the lens: a good lens near focus is 0.5-0.7 px on a 1.5 um pixel)
 * convolved with the OLPF's split of each ray into four, one pixel pitch
 * apart (two crossed birefringent plates), integrated over the pixel's
 * area.  The split's MTF, |cos(pi f)| per axis, is zero at the mosaic's
 * Nyquist frequency (half a cycle per pixel): however small a lamp,
 * each of the four sites of a 2 x 2 cell gets a quarter of its light, and
 * a demosaic that averages sites keeps each colour's flux.
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
	double psf_sigma_px; /* the lens's Gaussian blur, pixels (0: none) */
	int olpf;	     /* 1: the optical low-pass filter's 4-way split */
};

/* A 12-bit machine-vision-like sensor (docs/conventions.md). */
void glint_sensor_default(struct glint_sensor *s);

/*
 * The optics applied to radiance in place: the point-spread function above
 * (separable, the image's edge extended; flux is kept away from the
 * edges).  Nothing to do when psf_sigma_px is 0 and olpf is 0.  -ENOMEM
 * when out of memory, -EINVAL for a sigma outside [0, 8].
 */
int glint_sensor_optics(const struct glint_sensor *s, struct glint_image *img);

/* The optics' 1-D kernel: k[0..2 * radius] (radius <= 32) for taps -radius
 * ... radius, summing to 1; returns radius (0: the identity). */
int glint_sensor_psf_kernel(const struct glint_sensor *s, double k[65]);

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
