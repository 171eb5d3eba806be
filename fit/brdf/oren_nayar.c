/* SPDX-License-Identifier: MIT */
/*
 * Rough diffuse (Oren-Nayar's qualitative model) under a Torrance-Sparrow
 * specular lobe:
 *
 *   f = kd ON(sigma; o, i) + ks D(h) G F(o.h) / (4 (n.i)(n.o))
 *
 * ON is glint_oren_nayar (microfacet.h): a matte surface of V-grooves
 * whose facet slopes have standard deviation sigma (radians) looks flatter
 * than Lambert's: darker toward the lit rim, brighter back toward the
 * light.  sigma = 0 is torrance-sparrow exactly.  The parameters are
 * torrance-sparrow's in the same order, then diffuse_roughness = sigma.
 */
#include "microfacet.h"
#include "model.h"

enum { KD = 0, KS = 3, ROUGH = 6, IOR = 7, SIGMA = 8 };

static const struct glint_param on_params[] = {
	{ "diffuse.r", "diffuse", 0, 0, 1, 0.5 },
	{ "diffuse.g", "diffuse", 1, 0, 1, 0.5 },
	{ "diffuse.b", "diffuse", 2, 0, 1, 0.5 },
	{ "specular.r", "specular", 0, 0, 1, 0.5 },
	{ "specular.g", "specular", 1, 0, 1, 0.5 },
	{ "specular.b", "specular", 2, 0, 1, 0.5 },
	{ "roughness", "roughness", -1, 1e-4, 1, 0.075 },
	{ "ior", "ior", -1, 1, 5, 1.5 },
	{ "diffuse_roughness", "diffuse_roughness", -1, 0, 1, 0.3 },
};

static const int on_lobe_param[2] = { KD, KS };
static const int on_lobe_varies[2] = { 1, 1 };

static void on_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		     double *b)
{
	const double *p = self;

	b[0] = glint_oren_nayar(p[SIGMA], wo, wi);
	b[1] = glint_beckmann_lobe(p[ROUGH], p[IOR], wo, wi);
}

static void on_eval(const void *self, struct vec3 wo, struct vec3 wi,
		    double f[3])
{
	const double *p = self;

	glint_lobes_eval(&glint_model_oren_nayar, p, wo, wi, f);
}

static double on_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	return glint_lobes_pdf(&glint_model_oren_nayar, p,
			       glint_fresnel_or_one(wo.z, p[IOR]), wo, wi);
}

static double on_sample(const void *self, struct vec3 wo, const double u[3],
			struct vec3 *wi)
{
	const double *p = self;

	return glint_lobes_sample(&glint_model_oren_nayar, p,
				  glint_fresnel_or_one(wo.z, p[IOR]), wo, u,
				  wi);
}

/* The rough-diffuse lobe is sampled by cosine: it stays within a factor
 * of a few of Lambert's shape for sigma <= 1. */
static double on_pdf_lobe(const void *self, int j, struct vec3 wo,
			  struct vec3 wi)
{
	const double *p = self;

	return glint_lobe_shape_pdf(j ? &glint_microfacet_beckmann : NULL,
				    p[ROUGH], wo, wi);
}

static double on_sample_lobe(const void *self, int j, struct vec3 wo,
			     const double u[2], struct vec3 *wi)
{
	const double *p = self;

	return glint_lobe_shape_sample(j ? &glint_microfacet_beckmann : NULL,
				       p[ROUGH], wo, u, wi);
}

static const double *on_albedo(const void *self, int j)
{
	return (const double *)self + on_lobe_param[j];
}

static const struct glint_bxdf_ops on_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = on_eval,
	.sample = on_sample,
	.pdf = on_pdf,
	.nlobes = 2,
	.albedo = on_albedo,
	.eval_lobes = on_lobes,
	.sample_lobe = on_sample_lobe,
	.pdf_lobe = on_pdf_lobe,
};

static const int on_width_param[] = { -1, ROUGH };

static const struct glint_fit_lobes on_fit = {
	.param = on_lobe_param,
	.varies = on_lobe_varies,
	.roughness_param = ROUGH,
	.microfacet = &glint_microfacet_beckmann,
	.width_param = on_width_param,
};

const struct glint_model glint_model_oren_nayar = {
	.name = "oren-nayar",
	.conventions =
		"Oren-Nayar rough diffuse under a Torrance-Sparrow lobe: f = "
		"diffuse*(A + B max(0, cos(phi_i - phi_o)) sin(alpha) "
		"tan(beta))/pi + specular*D*G*F/(4 cos_i cos_o), A = 1 - "
		"s^2/(2(s^2 + 0.33)), B = 0.45 s^2/(s^2 + 0.09), s = "
		"diffuse_roughness = standard deviation of the facet slope "
		"angle in radians (MaterialX oren_nayar_diffuse_bsdf's "
		"roughness), alpha = max(t_i, t_o), beta = min(t_i, t_o). "
		"Specular as torrance-sparrow: D Beckmann with roughness = "
		"RMS slope, G V-cavity, F exact dielectric Fresnel with ior.",
	.nparams = 9,
	.params = on_params,
	.bxdf = &on_bxdf,
	.lobes = &on_fit,
};
