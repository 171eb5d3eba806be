/* SPDX-License-Identifier: MIT */
/*
 * Lambertian diffuse plus a Trowbridge-Reitz (GGX) specular lobe with
 * height-correlated Smith shadowing and the exact dielectric Fresnel term:
 *
 *   f = kd / pi + ks D(h) G2(o, i) F(o.h) / (4 (n.i)(n.o))
 *
 * The same parameters as Torrance-Sparrow, but roughness is GGX's width a:
 * the lobe has the same peak as a Beckmann lobe of RMS slope a and a far
 * longer tail (the "haze" of real glossy surfaces).
 */
#include "microfacet.h"
#include "model.h"

enum { KD = 0, KS = 3, ROUGH = 6, IOR = 7 };

static const struct glint_param ggx_params[] = {
	{ "diffuse.r", "diffuse", 0, 0, 1, 0.5 },
	{ "diffuse.g", "diffuse", 1, 0, 1, 0.5 },
	{ "diffuse.b", "diffuse", 2, 0, 1, 0.5 },
	{ "specular.r", "specular", 0, 0, 1, 0.5 },
	{ "specular.g", "specular", 1, 0, 1, 0.5 },
	{ "specular.b", "specular", 2, 0, 1, 0.5 },
	{ "roughness", "roughness", -1, 1e-4, 1, 0.075 },
	{ "ior", "ior", -1, 1, 5, 1.5 },
};

static const int ggx_lobe_param[2] = { KD, KS };
static const int ggx_lobe_varies[2] = { 0, 1 };

static double ggx_lobe(const void *self, int j, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	if (j)
		return glint_ggx_lobe(p[ROUGH], p[IOR], wo, wi);
	return wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
}

static void ggx_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		      double *b)
{
	b[0] = ggx_lobe(self, 0, wo, wi);
	b[1] = ggx_lobe(self, 1, wo, wi);
}

static void ggx_eval(const void *self, struct vec3 wo, struct vec3 wi,
		     double f[3])
{
	const double *p = self;

	glint_lobes_eval(&glint_model_ggx, p, wo, wi, f);
}

static double ggx_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	return glint_lobes_pdf(&glint_model_ggx, p,
			       glint_fresnel_or_one(wo.z, p[IOR]), wo, wi);
}

static double ggx_sample(const void *self, struct vec3 wo, const double u[3],
			 struct vec3 *wi)
{
	const double *p = self;

	return glint_lobes_sample(&glint_model_ggx, p,
				  glint_fresnel_or_one(wo.z, p[IOR]), wo, u,
				  wi);
}

static double ggx_pdf_lobe(const void *self, int j, struct vec3 wo,
			   struct vec3 wi)
{
	const double *p = self;

	return glint_lobe_shape_pdf(j ? &glint_microfacet_ggx : NULL, p[ROUGH],
				    wo, wi);
}

static double ggx_sample_lobe(const void *self, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi)
{
	const double *p = self;

	return glint_lobe_shape_sample(j ? &glint_microfacet_ggx : NULL,
				       p[ROUGH], wo, u, wi);
}

static const double *ggx_albedo(const void *self, int j)
{
	return (const double *)self + ggx_lobe_param[j];
}

static const struct glint_bxdf_ops ggx_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = ggx_eval,
	.sample = ggx_sample,
	.pdf = ggx_pdf,
	.nlobes = 2,
	.albedo = ggx_albedo,
	.eval_lobes = ggx_lobes,
	.eval_lobe = ggx_lobe,
	.sample_lobe = ggx_sample_lobe,
	.pdf_lobe = ggx_pdf_lobe,
};

static const int ggx_width_param[] = { -1, ROUGH };

/* Every lobe but the diffuse one (0) carries F(o.h, ior): d log b_j /
 * d ior. */
static double ggx_factor_dlog(const double *p, int j, struct vec3 wo,
			      struct vec3 wi)
{
	return j ? glint_fresnel_half_dlog(p[IOR], wo, wi) : 0;
}

static const struct glint_fit_lobes ggx_fit = {
	.param = ggx_lobe_param,
	.varies = ggx_lobe_varies,
	.factor_param = IOR,
	.factor_dlog = ggx_factor_dlog,
	.roughness_param = ROUGH,
	.microfacet = &glint_microfacet_ggx,
	.width_param = ggx_width_param,
};

const struct glint_model glint_model_ggx = {
	.name = "ggx",
	.conventions =
		"Microfacet with a Trowbridge-Reitz (GGX) lobe: f = "
		"diffuse/pi + specular*D*G*F/(4 cos_i cos_o). D = GGX with "
		"width a = roughness: D = a^2/(pi cos^4(t_h) (a^2 + "
		"tan^2(t_h))^2) (a is not an RMS slope; pbrt's and Mitsuba's "
		"alpha, Disney's roughness squared). G = height-correlated "
		"Smith, 1/(1 + L(o) + L(i)), L(v) = (sqrt(1 + a^2 "
		"tan^2(t_v)) - 1)/2. F = exact unpolarised dielectric "
		"Fresnel at cos = o.h with index ior.",
	.nparams = 8,
	.params = ggx_params,
	.bxdf = &ggx_bxdf,
	.lobes = &ggx_fit,
};
