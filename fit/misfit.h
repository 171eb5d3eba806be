/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_MISFIT_H
#define GLINT_FIT_MISFIT_H

/*
 * Where the fitted model misses the photo ("misfit made
 * visible"): the residual (render - photo) of the pixels wholly on the
 * sphere, binned by two angles:
 *  - from the view direction (the angle between normal and view: 0 at
 *    the sphere's centre, 90 at its rim), where a non-Lambertian diffuse
 *    shows;
 *  - from the mirror direction to the map's brightest direction (0 in the
 *    highlight), where a lobe of the wrong shape shows.
 * Per band: the pixel count, the mean residual and its standard error (from
 * the spread within the band), and, with a noise model, the mean of the
 * squared weighted residual (chi^2 per value: about 1 at the noise).  A
 * band whose mean is more than 5 standard errors from 0 is structure the
 * noise does not make.  Without weights the residual is relative to the
 * photo's mean on the sphere and chi^2 is not given.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: nothing
 * (results are values).
 */

#include "fit/render/tracer.h"
#include "fit/scene/envmap.h"
#include "core/image.h"

#include <jansson.h>

#define GLINT_MISFIT_BANDS 9

struct glint_misfit_band {
	double lo_deg, hi_deg;
	long n;	     /* pixels */
	double mean; /* mean residual (weighted or relative) */
	double se;   /* its standard error */
	double chi2; /* mean squared weighted residual; NAN without weights */
};

struct glint_misfit {
	int weighted; /* 1: residuals in noise units */
	struct glint_misfit_band view[GLINT_MISFIT_BANDS];
	struct glint_misfit_band mirror[GLINT_MISFIT_BANDS];
	double light[3];     /* the map's brightest direction (world) */
	double chi2;	     /* over all the pixels; NAN without weights */
	double render_noise; /* as given (0 when not known) */
	int structured;
	char verdict[448];
};

/*
 * Analyse the residual of `render` against `photo` over the pixels whose
 * coverage (cov, from glint_renderer_shade) is whole.  weight (may be
 * NULL) is the fit's per-pixel, per-channel 1/variance.  render_noise is
 * the render's own Monte Carlo variance in units of the photo's (0 for a
 * noiseless render; NAN: not known, taken as 0): the residual's variance
 * is the photo's times 1 + render_noise, and the weighted residuals are
 * scaled to it, so that chi^2 per value is about 1 at the noise however
 * many samples the render took.  Fails only on a size mismatch or no
 * pixel on the sphere.
 */
int glint_misfit_analyse(const struct glint_gbuffer *gb,
			 const struct glint_envmap *env,
			 const struct glint_image *photo,
			 const struct glint_image *render,
			 const struct glint_image *weight,
			 const struct glint_image *cov, double render_noise,
			 struct glint_misfit *m);

/* The map's brightest direction (world): the texel of most power
 * (radiance x solid angle), the mirror angle's reference. */
struct vec3 glint_misfit_light(const struct glint_envmap *env);

/* The view and mirror band (0 .. GLINT_MISFIT_BANDS - 1) of a pixel from
 * its spp hits hs, as glint_misfit_analyse() bins it. */
void glint_misfit_bands(const struct glint_hit *hs, int spp, struct vec3 light,
			int *view_band, int *mirror_band);

/* params.json's "misfit": the verdict, the light direction and both band
 * tables.  A new reference. */
json_t *glint_misfit_json(const struct glint_misfit *m);

#endif
