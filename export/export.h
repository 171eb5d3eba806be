/* SPDX-License-Identifier: MIT */
#ifndef GLINT_EXPORT_EXPORT_H
#define GLINT_EXPORT_EXPORT_H

/*
 * The fitted material in a renderer's own model.  Target models differ from
 * glint's (Beckmann or GGX, V-cavity or Smith shadowing, exact or Schlick
 * Fresnel, a diffuse term added or Fresnel-weighted), so the target's
 * parameters are not copied across: they are fitted, by bounded
 * least squares, to glint's BRDF over a fixed set of directions, and the
 * fit's residual is reported with the export.
 *
 * The direction set: 8 view angles (5 to 75 degrees) and, for each, 512
 * incident directions drawn half from glint's own sampler and half
 * cosine-weighted (a defensive mixture: highlights and the rest are both
 * seen).  The residual is the relative RMS difference of reflected
 * radiance under uniform light, sqrt(sum (f_t - f)^2 cos^2 / pdf) over
 * sqrt(sum f^2 cos^2 / pdf).
 *
 * The targets, each as its renderer evaluates it (f per steradian, RGB;
 * F_d(c, n) the exact unpolarised dielectric Fresnel term, which is also
 * what Mitsuba's and pbrt's conductor Fresnel give with k = 0):
 *
 * GLTF: glTF 2.0 metallic-roughness dielectric (metallic 0) with
 *   KHR_materials_ior and KHR_materials_specular (specification Appendix
 *   B; the extension's first ratified text).  x = base[3], roughness,
 *   specular, specular_color[3]:
 *     a = roughness^2, D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2)
 *     V = 1 / ((|n.l| + sqrt(a^2 + (1 - a^2)(n.l)^2))
 *              (|n.v| + sqrt(a^2 + (1 - a^2)(n.v)^2)))
 *     f0 = min(((ior - 1)/(ior + 1))^2 specular_color, 1) specular
 *     F = f0 + (specular - f0)(1 - |v.h|)^5, f = (1 - F) base/pi + F D V
 *
 * MITSUBA: Mitsuba 3, a blendbsdf of diffuse and roughconductor (eta =
 *   ior, k = 0; Beckmann, or GGX for glint's GGX models) with
 *   specular_reflectance.  x = kd[3], alpha, ks[3] (the blend's weight w
 *   is chosen when writing: diffuse reflectance kd / (1 - w), specular
 *   reflectance ks / w):
 *     f = kd/pi + ks F_d(i.h, ior) D(h) G1(i, h) G1(o, h) / (4 cos_i cos_o)
 *   Beckmann G1 is Mitsuba's rational approximation, with
 *   a = 1 / (alpha tan t): 1 if a >= 1.6, else
 *   (3.535 a + 2.181 a^2) / (1 + 2.276 a + 2.577 a^2); GGX G1 is
 *   2 / (1 + sqrt(1 + alpha^2 tan^2 t)).
 *
 * PBRT: pbrt-v4, a mix material (amount a) of diffuse (reflectance R) and
 *   conductor (Trowbridge-Reitz roughness alpha with remaproughness false,
 *   eta per RGB channel, k = 0).  x = R[3], a, alpha, eta[3]:
 *     f = (1 - a) R/pi + a F_d(|o.h|, eta) D(h) G / (4 cos_i cos_o)
 *   with Trowbridge-Reitz D and G = 1 / (1 + L(o) + L(i)),
 *   L = (sqrt(1 + alpha^2 tan^2 t) - 1) / 2.
 *
 * BLENDER: Blender (3.x, Cycles; EEVEE approximates it), a node material:
 *   Add(Diffuse BSDF (kd, roughness 0), Mix(Fresnel(ior_b), black Diffuse,
 *   Glossy BSDF (Beckmann, or GGX for glint's GGX models; ks, roughness
 *   sqrt(alpha)))).  The Fresnel
 *   node weighs by the view direction, not the half vector.  x = kd[3],
 *   alpha, ks[3], ior_b:
 *     f = kd/pi + ks F_d(n.o, ior_b) D(h) G1(i) G1(o) / (4 cos_i cos_o)
 *   with Beckmann D and Cycles's G1 (the rational approximation above),
 *   or GGX D and its separable Smith G1.
 *
 * MATERIALX: MaterialX 1.38 standard_surface (base 1, metalness 0, no
 *   coat, sheen, subsurface or transmission), as MaterialX's reference
 *   dielectric_bsdf layers it over oren_nayar_diffuse_bsdf.  x =
 *   base_color[3], diffuse_roughness s, specular_roughness r, specular w,
 *   specular_color t[3], specular_IOR n:
 *     a = r^2, F = F_d(v.h, n), G2 height-correlated Smith (GGX)
 *     E(v) = the GGX lobe's directional albedo with Fresnel
 *       f0 + (1 - f0)(1 - v.h)^5, f0 = ((n - 1)/(n + 1))^2; Ess(v) the
 *       same with F = 1 (both integrated numerically here, where
 *       MaterialX's shaders use its fitted curve)
 *     c = 1 + F (1 - Ess) / Ess (the multiple-scattering compensation)
 *     f = w t F D G2 c / (4 cos_i cos_o)
 *         + (1 - w E c) base_color ON(s) / pi
 *   with ON(s) the Oren-Nayar factor (fit/brdf/microfacet.h) times pi.
 *
 * A transparent (dielectric) sphere is not refitted: every target has a
 * smooth dielectric interface and a Beer-Lambert interior, so the
 * transmission per diameter T and the ior carry across exactly given the
 * sphere's diameter d (absorption sigma = -ln(T) / d).  The residual is
 * then the relative RMS difference of the interface's reflectance R(cos)
 * from the exact Fresnel term over a cosine-weighted hemisphere: 0 where
 * the target uses the exact term (Mitsuba, pbrt, Blender's sharp Glass
 * BSDF, MaterialX's dielectric_bsdf), Schlick's approximation's error for
 * glTF.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected (the format, the model, the file).  Threads:
 * re-entrant; the format names are static.  Who frees: the text
 * glint_export_text() returns, with free().
 */

#include "fit/brdf/model.h"

#include <jansson.h>

enum glint_export_format {
	GLINT_EXPORT_GLTF,
	GLINT_EXPORT_MITSUBA,
	GLINT_EXPORT_PBRT,
	GLINT_EXPORT_BLENDER,
	GLINT_EXPORT_MATERIALX,
	GLINT_EXPORT_NFORMATS
};

/* "gltf", "mitsuba", "pbrt", "blender", "materialx", then NULL (the
 * command-line names). */
extern const char *const glint_export_format_names[];

/* A comma-separated list of those names as a bit set (bit k: format k);
 * -EINVAL naming a bad name (with the likeliest meant) or an empty list. */
int glint_export_formats_parse(const char *list, unsigned *formats);

#define GLINT_EXPORT_MAX_X 10

struct glint_export {
	enum glint_export_format format;
	double x[GLINT_EXPORT_MAX_X]; /* the target's parameters, above */
	double ior;		      /* held at the model's own, or 1.5 */
	int ggx;		      /* MITSUBA: the GGX distribution */
	double residual;	      /* relative RMS difference, above */
	/* A transparent sphere: x[0..2] its transmission per diameter. */
	int dielectric;
	double diameter_m;
};

/*
 * Fit the target's parameters to glint's (model, p), into e (format
 * set); e->residual as above.  A transparent model's parameters carry
 * across (above) and need the sphere's diameter in metres (diameter_m;
 * NAN when unknown refuses them).
 */
int glint_export_refit(enum glint_export_format format,
		       const struct glint_model *model, const double *p,
		       double diameter_m, struct glint_export *e);

/* The target's BRDF with e's parameters, f[3]; 0 below the surface (and
 * for a dielectric). */
void glint_export_brdf(const struct glint_export *e, struct vec3 wo,
		       struct vec3 wi, double f[3]);

/* The relative RMS difference of e from (model, p) over the set above. */
double glint_export_residual(const struct glint_model *model, const double *p,
			     const struct glint_export *e);

/* The file name extension of a format's files (".gltf", ".xml", ".pbrt",
 * ".py", ".mtlx"). */
const char *glint_export_extension(enum glint_export_format format);

/*
 * The export's file, as text (malloc'd; NULL on allocation failure): the
 * material named `name` (characters other than letters, digits, '-', '_'
 * and '.' become '_'), with the refit's residual and its source.
 */
char *glint_export_text(const struct glint_export *e, const char *name,
			const char *source, const struct glint_model *model);

/*
 * A material's name from where its fit lives, into buf (n bytes): a
 * fit's folder or its params.json; a folder named fit (SESSION/fit, or
 * one not made yet) is named after the folder holding it, any other
 * folder is itself the name; a material file its stem (copper.json ->
 * copper).  "material" when the path names nothing
 * (".", "/").  Returns buf.
 */
const char *glint_export_name_from_path(const char *path, char *buf, size_t n);

/* The target's parameters by their names in the target, as JSON. */
json_t *glint_export_params_json(const struct glint_export *e);

#endif
