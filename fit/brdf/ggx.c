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

static void ggx_lobes(const double *p, struct vec3 wo, struct vec3 wi,
		      double *b)
{
	b[0] = wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
	b[1] = glint_ggx_lobe(p[ROUGH], p[IOR], wo, wi);
}

static void ggx_eval(const double *p, struct vec3 wo, struct vec3 wi,
		     double f[3])
{
	glint_lobes_eval(&glint_model_ggx, p, wo, wi, f);
}

static double ggx_pdf(const double *p, struct vec3 wo, struct vec3 wi)
{
	return glint_lobes_pdf(&glint_model_ggx, p,
			       glint_fresnel_or_one(wo.z, p[IOR]), wo, wi);
}

static double ggx_sample(const double *p, struct vec3 wo, const double u[3],
			 struct vec3 *wi)
{
	return glint_lobes_sample(&glint_model_ggx, p,
				  glint_fresnel_or_one(wo.z, p[IOR]), wo, u,
				  wi);
}

static double ggx_pdf_lobe(const double *p, int j, struct vec3 wo,
			   struct vec3 wi)
{
	return glint_lobe_shape_pdf(j ? GLINT_LOBE_GGX : GLINT_LOBE_COSINE,
				    p[ROUGH], wo, wi);
}

static double ggx_sample_lobe(const double *p, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi)
{
	return glint_lobe_shape_sample(j ? GLINT_LOBE_GGX : GLINT_LOBE_COSINE,
				       p[ROUGH], wo, u, wi);
}

/* D(t) / D(0) = a^4 / (a^2 cos^2 t + sin^2 t)^2 is below 1e-12 once
 * sin t > 1000 a: a bound only for the smoothest lobes. */
static double ggx_lobe_extent(const double *p, int j)
{
	double s = 1000 * p[ROUGH];
	return j == 1 && s < 1 ? 2 * asin(s) : -1;
}

/* GGX's core: D falls to half at tan t_h = a sqrt(sqrt(2) - 1) =
 * 0.6436 a, the mirror direction's angle twice that, which a Gaussian
 * reaches at 1.1774 sigma: sigma = 1.0932 a.  Widening keeps that core
 * (its tails are not widened). */
#define GGX_CORE 1.0932

static double ggx_lobe_width(const double *p, int j)
{
	return j == 1 ? GGX_CORE * p[ROUGH] : -1;
}

static void ggx_lobe_widen(double *p, int j, double s)
{
	if (j == 1)
		p[ROUGH] = sqrt(p[ROUGH] * p[ROUGH] +
				s * s / (GGX_CORE * GGX_CORE));
}

const struct glint_model_ops glint_model_ggx = {
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
	.eval = ggx_eval,
	.sample = ggx_sample,
	.pdf = ggx_pdf,
	.roughness_param = ROUGH,
	.nlobes = 2,
	.lobe_param = ggx_lobe_param,
	.lobe_varies = ggx_lobe_varies,
	.eval_lobes = ggx_lobes,
	.sample_lobe = ggx_sample_lobe,
	.pdf_lobe = ggx_pdf_lobe,
	.lobe_extent = ggx_lobe_extent,
	.lobe_width = ggx_lobe_width,
	.lobe_widen = ggx_lobe_widen,
};
