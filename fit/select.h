/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_SELECT_H
#define GLINT_FIT_SELECT_H

/*
 * Model no more of the material than the photo supports.  Four nested
 * candidates, each fitted to the same pixels with the same weights and the
 * same fixed-sample estimator:
 *   torrance-sparrow   RGB diffuse, RGB specular, roughness, ior (8)
 *   grey specular      RGB diffuse, one specular, roughness, ior (6)
 *   constant Fresnel   RGB diffuse, RGB specular, roughness; F = 1 (7)
 *   lambert            RGB diffuse (3)
 * and, when asked (`richer`), three that model more than Torrance-Sparrow:
 *   ggx                a Trowbridge-Reitz lobe, Smith shadowing (8)
 *   oren-nayar         rough diffuse under the Beckmann lobe (9)
 *   two-lobe           a second, broader Beckmann lobe (12)
 * all scored by the information criteria on the weighted residual, for n
 * residuals and k parameters at the minimum weighted SSD S:
 *   BIC = n ln(S / n) + k ln n,   AIC = n ln(S / n) + 2 k
 * (Gaussian residuals of unknown variance: the fast renderer's own bias
 * is part of what the models leave).  The lowest BIC is chosen; the
 * standard errors of the full fit are reported beside it (e.g. the
 * spread of the specular channels against their errors).
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: called from one thread; the fits run
 * their own threads.  Who frees: json_decref() a document out.
 */

#include "fit.h"

#include <jansson.h>

enum {
	GLINT_SEL_RGB,
	GLINT_SEL_GREY,
	GLINT_SEL_CONST_FRESNEL,
	GLINT_SEL_LAMBERT,
	GLINT_SEL_GGX,
	GLINT_SEL_OREN_NAYAR,
	GLINT_SEL_TWO_LOBE,
	GLINT_SEL_N
};

struct glint_select_candidate {
	const char *name;
	int scored;  /* 0: not tried (the richer ones unless asked) */
	int k;	     /* free parameters */
	double cost; /* 1/2 weighted SSD at its minimum */
	double bic, aic;
	/* the parameters, in the terms of `model` (the grey one as a
	 * torrance-sparrow with equal specular channels) */
	const struct glint_model *model;
	double p[GLINT_MAX_PARAMS], se[GLINT_MAX_PARAMS];
};

struct glint_selection {
	struct glint_select_candidate c[GLINT_SEL_N];
	int n;		/* residuals (pixels x 3) */
	int chosen;	/* lowest BIC */
	int chosen_aic; /* lowest AIC */
	/* The candidates' own fits, where they have one (has_fit): RGB,
	 * constant Fresnel and the richer models; grey is derived from the
	 * RGB one and lambert is solved linearly. */
	struct glint_fit_result fit[GLINT_SEL_N];
	int has_fit[GLINT_SEL_N];
	char why[768];
};

/* Fit and score the candidates on photo in r's scene (o: the fit's
 * options; the same pixels and samples for every candidate); richer: also
 * the three larger models (three more fits). */
int glint_select_model(struct glint_renderer *r,
		       const struct glint_image *photo,
		       const struct glint_image *weight,
		       const struct glint_fit_opts *o, int richer,
		       struct glint_selection *out);

/* The same over several photos of one material, each in its own scene
 * (glint_fit_views()): every candidate fitted jointly, scored on every
 * photo's pixels together. */
int glint_select_model_views(const struct glint_fit_view *views, int nviews,
			     const struct glint_fit_opts *o, int richer,
			     struct glint_selection *out);

/* Caller json_decref()s. */
json_t *glint_selection_to_json(const struct glint_selection *s);

#endif
