/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_PER_LIGHT_H
#define GLINT_FIT_PER_LIGHT_H

/*
 * One material from many lights, checked light by light: beside a joint
 * fit of several photos (each under its own light), every photo fitted
 * alone with the same model, and each parameter's per-light values set
 * against the angle of that photo's brightest light from the view
 * direction.  A model that explains every light gives values that agree
 * within their errors; one that cannot (a lobe of the wrong shape, a
 * Fresnel curve of the wrong form) makes a parameter drift with the
 * light's angle.
 *
 * Per parameter: the weighted least-squares line value = a + b angle over
 * the lights (weights 1 / se^2, se each fit's whole standard error: its
 * systematic part, the fast render's and the light's, changes with the
 * light's direction too; without it the rig's two lamps, one material,
 * drifted in roughness by 3.3 standard errors), its slope b per 10
 * degrees with its standard error and z = b / se(b); and chi^2 per degree
 * of freedom of the values about the joint fit's.  A parameter drifts
 * when |z| >= GLINT_DRIFT_Z.  Parameters a light does not determine
 * (glint_fit_result's interval over half the bounds) count for that
 * light only where determined.
 *
 * When every light is within a degree of the same angle from the view
 * (one lamp, the turntable turned) there is no trend to test and the
 * photos are not fitted one by one (values NAN).
 *
 * Errors: a negative errno with glint_error_msg() naming the photo.
 * Threads: the fits use o->nthreads.  Who frees: nothing (values).
 */

#include "fit/fit.h"

#include <jansson.h>

/* |z| of a drift: 3 standard errors (two-sided 0.27 % by chance per
 * parameter; about 2 % over a model's eight). */
#define GLINT_DRIFT_Z 3.0

struct glint_per_light {
	int nviews, nparams;
	double angle_deg[GLINT_FIT_MAX_VIEWS]; /* brightest light from view */
	double p[GLINT_FIT_MAX_VIEWS][GLINT_MAX_PARAMS];
	double se[GLINT_FIT_MAX_VIEWS][GLINT_MAX_PARAMS]; /* INFINITY: not
							     determined */
	double rel_rmse[GLINT_FIT_MAX_VIEWS];
	/* per parameter, over the lights that determine it */
	int used[GLINT_MAX_PARAMS];
	double slope[GLINT_MAX_PARAMS], slope_se[GLINT_MAX_PARAMS]; /* per 10
								       deg */
	double z[GLINT_MAX_PARAMS];	   /* NAN: fewer than 2 angles */
	double chi2_dof[GLINT_MAX_PARAMS]; /* about the joint value */
	int drifts[GLINT_MAX_PARAMS];
	int ndrift;
	char verdict[512];
};

/* Fit each of views[0 .. nv - 1] alone with model and o, and set them
 * against joint (the fit of all of them). */
int glint_fit_per_light(const struct glint_fit_view *views, int nv,
			const struct glint_model *model,
			const struct glint_fit_opts *o,
			const struct glint_fit_result *joint,
			struct glint_per_light *out);

/* params.json's "per_light": the lights' table, each parameter's trend
 * and the verdict.  A new reference. */
json_t *glint_per_light_json(const struct glint_per_light *pl,
			     const struct glint_model *model);

#endif
