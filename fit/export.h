/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_EXPORT_H
#define GLINT_FIT_EXPORT_H

/*
 * The fitted material in a renderer's own model.  Target models differ from
 * glint's (glTF: GGX with separable Smith visibility, Schlick Fresnel and a
 * Fresnel-weighted mix with the diffuse; glint: Beckmann or GGX, V-cavity or
 * height-correlated Smith, exact Fresnel, diffuse added), so the target's
 * parameters are not copied across: they are fitted, by bounded
 * least squares, to glint's BRDF over a fixed set of directions, and the
 * fit's residual is reported with the export.
 *
 * The direction set: 8 view angles (5 to 75 degrees) and, for each, 512
 * incident directions drawn half from glint's own sampler and half
 * cosine-weighted (a defensive mixture: highlights and the rest are both
 * seen).  The residual is the relative RMS difference of reflected
 * radiance under uniform light, sqrt(sum (f_t - f) cos^2 / pdf) over
 * sqrt(sum f cos^2 / pdf) (squares inside).
 */

#include "fit/brdf/model.h"

#include <jansson.h>

/*
 * glTF 2.0 metallic-roughness dielectric (metallic 0) with
 * KHR_materials_ior and KHR_materials_specular, as the specifications
 * state it (glTF 2.0 Appendix B; KHR_materials_specular, first ratified
 * text):
 *   a = roughness^2
 *   D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2)
 *   V = 1 / ((|n.l| + sqrt(a^2 + (1 - a^2)(n.l)^2))
 *            (|n.v| + sqrt(a^2 + (1 - a^2)(n.v)^2)))
 *   f0 = min(((ior - 1)/(ior + 1))^2 specular_color, 1) specular
 *   F = f0 + (specular - f0)(1 - |v.h|)^5              (per channel)
 *   f = (1 - F) base / pi + F D V
 */
struct glint_gltf_material {
	double base[3];
	double roughness;
	double ior;
	double specular;
	double specular_color[3];
};

/* The glTF BRDF above, f[3] per steradian; 0 below the surface. */
void glint_gltf_brdf(const struct glint_gltf_material *g, struct vec3 wo,
		     struct vec3 wi, double f[3]);

/*
 * Fit g to glint's (model, p): base colour, roughness, specular and
 * specular colour (ior is held at the model's own, or 1.5 for models
 * without one); *residual as above.  Refuses transparent models.
 */
int glint_gltf_refit(const struct glint_model_ops *model, const double *p,
		     struct glint_gltf_material *g, double *residual);

/* The relative RMS difference of g from (model, p) over the set above. */
double glint_gltf_residual(const struct glint_model_ops *model, const double *p,
			   const struct glint_gltf_material *g);

/* A glTF 2.0 document holding the one material (named `name`), with the
 * refit's residual and source in its extras.  Caller json_decref()s. */
json_t *glint_gltf_document(const struct glint_gltf_material *g,
			    const char *name, const char *source,
			    const struct glint_model_ops *model,
			    double residual);

#endif
