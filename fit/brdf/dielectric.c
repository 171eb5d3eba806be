/* SPDX-License-Identifier: MIT */
/*
 * The smooth dielectric sphere (fit/render/dielectric_paths.h): RGB
 * transmission per traversal of the diameter and the index of refraction.  Not
 * a BRDF: it has no bxdf and no lobes (the renderer and the fitter follow its
 * paths with fit/render/dielectric_paths.c instead).
 */
#include "model.h"

static const struct glint_param dielectric_params[] = {
	{ "transmission.r", "transmission", 0, 0, 1, 0.5 },
	{ "transmission.g", "transmission", 1, 0, 1, 0.5 },
	{ "transmission.b", "transmission", 2, 0, 1, 0.5 },
	{ "ior", "ior", -1, 1.01, 4, 1.5 },
};

const struct glint_model glint_model_dielectric = {
	.name = "dielectric",
	.conventions =
		"smooth dielectric sphere: exact unpolarised Fresnel at each "
		"interface, Snell refraction, total internal reflection, "
		"internal bounces followed until their Fresnel weight is "
		"below 1e-4; transmission = fraction of light surviving one "
		"traversal of the sphere's diameter inside the material "
		"(Beer-Lambert, sigma = -ln(T) / diameter; a path of length "
		"L inside is attenuated by T^(L / diameter)); interface "
		"losses are not part of it; ior relative to air",
	.nparams = 4,
	.params = dielectric_params,
};
