/* SPDX-License-Identifier: MIT */
#include "sensor.h"

#include "core/error.h"

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include <math.h>
#include <stdlib.h>

void glint_sensor_default(struct glint_sensor *s)
{
	/* Sony IMX-class numbers: 10 ke- full well, 2.5 e- read noise,
	 * 12-bit ADC spanning the full well, 64 DN black level. */
	s->exposure_s = 0.01;
	s->gain = 4095.0 / 10000.0;
	s->k = 1e5;
	s->read_noise_e = 2.5;
	s->black_level = 64;
	s->full_well_e = 10000;
	s->bits = 12;
	s->noise = 1;
	s->quantise = 1;
	s->seed = 1;
	s->psf_sigma_px = 0.6;
	s->olpf = 1;
}

/* The Gaussian's integral over [a, b]. */
static double gauss_int(double sigma, double a, double b)
{
	if (sigma <= 0) /* a delta on a pixel's border: half to each side */
		return (a < 0 && 0 < b) ? 1 : (a == 0 || b == 0) ? 0.5 : 0;
	double r = 1 / (sigma * sqrt(2.0));
	return 0.5 * (erf(b * r) - erf(a * r));
}

int glint_sensor_psf_kernel(const struct glint_sensor *s, double k[65])
{
	double sigma = s->psf_sigma_px;
	double split = s->olpf ? 0.5 : 0;
	/* pixel i ([i - 0.5, i + 0.5]) meets the support, |x| < 4 sigma +
	 * split + 0.5, while i < 4 sigma + split + 1 */
	int radius = (int)ceil(4 * sigma + split + 1) - 1;

	if (sigma <= 0 && !s->olpf) {
		k[0] = 1;
		return 0;
	}
	if (radius > 32)
		radius = 32;
	double sum = 0;
	for (int i = -radius; i <= radius; i++) {
		double a = i - 0.5, b = i + 0.5, v;
		/* pixel box x (lens Gaussian * the split's two deltas) */
		v = split > 0 ? 0.5 * (gauss_int(sigma, a - split, b - split) +
				       gauss_int(sigma, a + split, b + split))
			      : gauss_int(sigma, a, b);
		k[i + radius] = v;
		sum += v;
	}
	for (int i = 0; i <= 2 * radius; i++)
		k[i] /= sum;
	return radius;
}

int glint_sensor_optics(const struct glint_sensor *s, struct glint_image *img)
{
	double k[65];
	int w = img->width, h = img->height;

	if (!(s->psf_sigma_px >= 0 && s->psf_sigma_px <= 8))
		return glint_error_set(EINVAL,
				       "sensor optics: psf sigma %g px: "
				       "expected 0..8",
				       s->psf_sigma_px);
	int r = glint_sensor_psf_kernel(s, k);
	if (r == 0)
		return 0;
	int n = w > h ? w : h;
	double *line = malloc((size_t)(n + 2 * r) * 3 * sizeof(double));
	if (!line)
		return glint_error_set(ENOMEM, "sensor optics: out of memory");
	/* Rows, then columns; each line copied with its ends extended. */
	for (int pass = 0; pass < 2; pass++) {
		int len = pass ? h : w, count = pass ? w : h;
		for (int j = 0; j < count; j++) {
			for (int i = -r; i < len + r; i++) {
				int ii = i < 0 ? 0 : i >= len ? len - 1 : i;
				const float *p =
					pass ? glint_image_px(img, j, ii)
					     : glint_image_px(img, ii, j);
				for (int c = 0; c < 3; c++)
					line[3 * (i + r) + c] = p[c];
			}
			for (int i = 0; i < len; i++) {
				float *o = pass ? glint_image_px(img, j, i)
						: glint_image_px(img, i, j);
				for (int c = 0; c < 3; c++) {
					double acc = 0;
					for (int t = 0; t <= 2 * r; t++)
						acc += k[t] *
						       line[3 * (i + t) + c];
					o[c] = (float)acc;
				}
			}
		}
	}
	free(line);
	return 0;
}

static double adc_max(const struct glint_sensor *s)
{
	return ldexp(1.0, s->bits) - 1;
}

double glint_sensor_exposure_for(const struct glint_sensor *s, double l,
				 double level)
{
	double dn = level * (adc_max(s) - s->black_level);
	return dn / (s->gain * s->k * l);
}

int glint_sensor_capture(const struct glint_sensor *s,
			 const struct glint_image *radiance,
			 struct glint_image *dn)
{
	size_t n = (size_t)radiance->width * radiance->height * 3;
	gsl_rng *rng = NULL;

	if (dn->width != radiance->width || dn->height != radiance->height)
		return glint_error_set(EINVAL, "sensor: output %dx%d for %dx%d",
				       dn->width, dn->height, radiance->width,
				       radiance->height);
	if (!(s->exposure_s > 0) || !(s->gain > 0) || !(s->k > 0) ||
	    s->bits < 1 || s->bits > 24)
		return glint_error_set(EINVAL,
				       "sensor: exposure %g s, gain %g, k %g, "
				       "%d bits: expected positive values and "
				       "1..24 bits",
				       s->exposure_s, s->gain, s->k, s->bits);
	if (s->noise) {
		rng = gsl_rng_alloc(gsl_rng_mt19937);
		if (!rng)
			return glint_error_set(ENOMEM, "out of memory");
		gsl_rng_set(rng, (unsigned long)s->seed);
	}
	for (size_t i = 0; i < n; i++) {
		double mean = fmax(0, radiance->data[i]) * s->k * s->exposure_s;
		double e = mean;
		if (rng) {
			/* Poisson for photon shot noise; beyond 1e7 its
			 * normal limit (gsl_ran_poisson takes unsigned). */
			e = mean < 1e7
				    ? (double)gsl_ran_poisson(rng, mean)
				    : mean + gsl_ran_gaussian(rng, sqrt(mean));
			e += gsl_ran_gaussian(rng, s->read_noise_e);
		}
		e = fmin(e, s->full_well_e);
		double v = s->gain * e + s->black_level;
		if (s->quantise)
			v = floor(v + 0.5);
		dn->data[i] = (float)fmin(fmax(v, 0), adc_max(s));
	}
	gsl_rng_free(rng);
	return 0;
}

int glint_sensor_to_radiance(const struct glint_sensor *s,
			     const struct glint_image *dn,
			     struct glint_image *radiance,
			     struct glint_image *weight)
{
	size_t npx = (size_t)dn->width * dn->height;
	double scale = s->gain * s->k * s->exposure_s;
	double sat_dn =
		fmin(adc_max(s), s->gain * s->full_well_e + s->black_level) -
		0.5;

	for (size_t px = 0; px < npx; px++) {
		int saturated = 0;
		double var[3];
		for (int c = 0; c < 3; c++) {
			double v = dn->data[3 * px + c];
			if (!isfinite(v) || v >= sat_dn)
				saturated = 1;
			double e = fmax(0, (v - s->black_level) / s->gain);
			radiance->data[3 * px + c] =
				(float)((v - s->black_level) / scale);
			/* Variance in DN: shot (estimated from the signal),
			 * read and quantisation, then in radiance units. */
			double vdn = s->gain * s->gain *
					     (e + s->read_noise_e *
							  s->read_noise_e) +
				     (s->quantise ? 1.0 / 12 : 0);
			var[c] = vdn / (scale * scale);
		}
		if (!weight)
			continue;
		for (int c = 0; c < 3; c++)
			weight->data[3 * px + c] =
				saturated ? 0.0f
					  : (float)(1 / fmax(var[c], 1e-30));
	}
	return 0;
}
