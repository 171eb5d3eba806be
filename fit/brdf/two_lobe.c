/* SPDX-License-Identifier: MIT */
/*
 * Torrance-Sparrow with two specular lobes: a sharp one and a broad one
 * (the long tail real highlights have and one Beckmann lobe lacks),
 * sharing the Fresnel term:
 *
 *   f = kd / pi + (ks D_m G_m + ks2 D_m2 G_m2) F(o.h) / (4 (n.i)(n.o))
 *
 * The parameters are torrance-sparrow's in the same order, then the
 * second lobe's RGB albedo and RMS slope.  Nothing orders the lobes; the
 * fit starts the second one broad (roughness2 0.3).
 */
#include "microfacet.h"
#include "model.h"

enum { KD = 0, KS = 3, ROUGH = 6, IOR = 7, KS2 = 8, ROUGH2 = 11 };

static const struct glint_param two_params[] = {
	{ "diffuse.r", "diffuse", 0, 0, 1, 0.5 },
	{ "diffuse.g", "diffuse", 1, 0, 1, 0.5 },
	{ "diffuse.b", "diffuse", 2, 0, 1, 0.5 },
	{ "specular.r", "specular", 0, 0, 1, 0.5 },
	{ "specular.g", "specular", 1, 0, 1, 0.5 },
	{ "specular.b", "specular", 2, 0, 1, 0.5 },
	{ "roughness", "roughness", -1, 1e-4, 1, 0.075 },
	{ "ior", "ior", -1, 1, 5, 1.5 },
	{ "specular2.r", "specular2", 0, 0, 1, 0.1 },
	{ "specular2.g", "specular2", 1, 0, 1, 0.1 },
	{ "specular2.b", "specular2", 2, 0, 1, 0.1 },
	{ "roughness2", "roughness2", -1, 1e-4, 1, 0.3 },
};

static const int two_lobe_param[3] = { KD, KS, KS2 };
static const int two_lobe_varies[3] = { 0, 1, 1 };

static void two_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		      double *b)
{
	const double *p = self;

	b[0] = wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
	b[1] = glint_beckmann_lobe(p[ROUGH], p[IOR], wo, wi);
	b[2] = glint_beckmann_lobe(p[ROUGH2], p[IOR], wo, wi);
}

static void two_eval(const void *self, struct vec3 wo, struct vec3 wi,
		     double f[3])
{
	const double *p = self;

	glint_lobes_eval(&glint_model_two_lobe, p, wo, wi, f);
}

static double two_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	return glint_lobes_pdf(&glint_model_two_lobe, p,
			       glint_fresnel_or_one(wo.z, p[IOR]), wo, wi);
}

static double two_sample(const void *self, struct vec3 wo, const double u[3],
			 struct vec3 *wi)
{
	const double *p = self;

	return glint_lobes_sample(&glint_model_two_lobe, p,
				  glint_fresnel_or_one(wo.z, p[IOR]), wo, u,
				  wi);
}

static double lobe_m(const double *p, int j)
{
	return j == 1 ? p[ROUGH] : p[ROUGH2];
}

static double two_pdf_lobe(const void *self, int j, struct vec3 wo,
			   struct vec3 wi)
{
	const double *p = self;

	return glint_lobe_shape_pdf(j ? &glint_microfacet_beckmann : NULL,
				    lobe_m(p, j), wo, wi);
}

static double two_sample_lobe(const void *self, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi)
{
	const double *p = self;

	return glint_lobe_shape_sample(j ? &glint_microfacet_beckmann : NULL,
				       lobe_m(p, j), wo, u, wi);
}

static const double *two_albedo(const void *self, int j)
{
	return (const double *)self + two_lobe_param[j];
}

static const struct glint_bxdf_ops two_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = two_eval,
	.sample = two_sample,
	.pdf = two_pdf,
	.nlobes = 3,
	.albedo = two_albedo,
	.eval_lobes = two_lobes,
	.sample_lobe = two_sample_lobe,
	.pdf_lobe = two_pdf_lobe,
};

static const int two_width_param[] = { -1, ROUGH, ROUGH2 };

/* Every lobe but the diffuse one (0) carries F(o.h, ior): d log b_j /
 * d ior. */
static double two_factor_dlog(const double *p, int j, struct vec3 wo,
			      struct vec3 wi)
{
	return j ? glint_fresnel_half_dlog(p[IOR], wo, wi) : 0;
}

static const struct glint_fit_lobes two_fit = {
	.param = two_lobe_param,
	.varies = two_lobe_varies,
	.factor_param = IOR,
	.factor_dlog = two_factor_dlog,
	.roughness_param = ROUGH,
	.microfacet = &glint_microfacet_beckmann,
	.width_param = two_width_param,
};

const struct glint_model glint_model_two_lobe = {
	.name = "two-lobe",
	.conventions =
		"Torrance-Sparrow with two specular lobes: f = diffuse/pi + "
		"(specular*D(roughness)*G(roughness) + specular2*"
		"D(roughness2)*G(roughness2))*F/(4 cos_i cos_o). Each D "
		"Beckmann with its roughness = RMS microfacet slope, each G "
		"V-cavity, one exact dielectric Fresnel F at cos = o.h with "
		"index ior.",
	.nparams = 12,
	.params = two_params,
	.bxdf = &two_bxdf,
	.lobes = &two_fit,
};
