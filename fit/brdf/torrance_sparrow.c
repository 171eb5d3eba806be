/* SPDX-License-Identifier: MIT */
/*
 * Torrance-Sparrow, parameterised as in Joshi & Jensen's Table 1: RGB
 * diffuse, RGB specular, roughness, index of refraction.
 *
 *   f = kd / pi + ks D(h) G F(i.h) / (4 (n.i)(n.o))
 *
 * D: Beckmann with roughness = RMS microfacet slope m; G: the V-cavity
 * shadowing/masking of Torrance & Sparrow (1967) in Cook & Torrance's form;
 * F: exact unpolarised dielectric Fresnel with the given ior.
 */
#include "microfacet.h"
#include "model.h"

#include <string.h>

enum { KD = 0, KS = 3, ROUGH = 6, IOR = 7 };

static const struct glint_param ts_params[] = {
	{ "diffuse.r", "diffuse", 0, 0, 1, 0.5 },
	{ "diffuse.g", "diffuse", 1, 0, 1, 0.5 },
	{ "diffuse.b", "diffuse", 2, 0, 1, 0.5 },
	{ "specular.r", "specular", 0, 0, 1, 0.5 },
	{ "specular.g", "specular", 1, 0, 1, 0.5 },
	{ "specular.b", "specular", 2, 0, 1, 0.5 },
	{ "roughness", "roughness", -1, 1e-4, 1, 0.075 },
	{ "ior", "ior", -1, 1, 5, 1.5 },
};

/* The specular lobe without its albedo: D G F / (4 cos_i cos_o). */
static double ts_spec(const double *p, struct vec3 wo, struct vec3 wi)
{
	return glint_beckmann_lobe(p[ROUGH], p[IOR], wo, wi);
}

static void ts_eval(const void *self, struct vec3 wo, struct vec3 wi,
		    double f[3])
{
	const double *p = self;

	if (!(wo.z > 0 && wi.z > 0)) {
		f[0] = f[1] = f[2] = 0;
		return;
	}
	double s = ts_spec(p, wo, wi);

	for (int c = 0; c < 3; c++)
		f[c] = p[KD + c] / M_PI + p[KS + c] * s;
}

/* Probability of sampling the specular lobe for this wo. */
static double spec_prob(const double *p, struct vec3 wo)
{
	double d = rgb_luminance(p[KD], p[KD + 1], p[KD + 2]);
	double s = rgb_luminance(p[KS], p[KS + 1], p[KS + 2]) *
		   glint_fresnel_or_one(wo.z, p[IOR]);

	if (s <= 0)
		return d > 0 ? 0 : 0.5;
	if (d <= 0)
		return 1;
	double ps = s / (s + d);
	return ps < 0.05 ? 0.05 : ps > 0.95 ? 0.95 : ps;
}

static double ts_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	double ps = spec_prob(p, wo);
	return ps * glint_beckmann_pdf(p[ROUGH], wo, wi) +
	       (1 - ps) * wi.z / M_PI;
}

static double ts_sample(const void *self, struct vec3 wo, const double u[3],
			struct vec3 *wi)
{
	const double *p = self;

	if (!(wo.z > 0))
		return 0;
	if (u[0] < spec_prob(p, wo))
		glint_beckmann_sample(p[ROUGH], wo, u + 1, wi);
	else
		glint_sample_cosine(u + 1, wi);
	if (!(wi->z > 0))
		return 0;
	return ts_pdf(p, wo, *wi);
}

static const int ts_lobe_param[2] = { KD, KS };
static const int ts_lobe_varies[2] = { 0, 1 };

static double ts_lobe(const void *self, int j, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	if (j)
		return ts_spec(p, wo, wi);
	return wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
}

static void ts_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		     double *b)
{
	b[0] = ts_lobe(self, 0, wo, wi);
	b[1] = ts_lobe(self, 1, wo, wi);
}

static double ts_pdf_lobe(const void *self, int j, struct vec3 wo,
			  struct vec3 wi)
{
	const double *p = self;

	return glint_lobe_shape_pdf(j ? &glint_microfacet_beckmann : NULL,
				    p[ROUGH], wo, wi);
}

static double ts_sample_lobe(const void *self, int j, struct vec3 wo,
			     const double u[2], struct vec3 *wi)
{
	const double *p = self;

	return glint_lobe_shape_sample(j ? &glint_microfacet_beckmann : NULL,
				       p[ROUGH], wo, u, wi);
}

static double ts_lobe_value_pdf(const double *p, int j, struct vec3 wo,
				struct vec3 wi, double *pdf, double *dlog)
{
	if (j)
		return glint_beckmann_lobe_pdf(p[ROUGH], p[IOR], wo, wi, pdf,
					       dlog);
	double b = wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
	if (pdf)
		*pdf = b * wi.z;
	if (dlog)
		*dlog = 0;
	return b;
}

/* The diffuse lobe's 1 / pi above the surface at n directions. */
static void diffuse_values(struct vec3 wo, int n, const double *z, double *b,
			   double *dlog)
{
	for (int k = 0; k < n; k++)
		b[k] = wo.z > 0 && z[k] > 0 ? 1 / M_PI : 0;
	if (dlog)
		for (int k = 0; k < n; k++)
			dlog[k] = 0;
}

static void ts_lobe_values(const double *p, int j, struct vec3 wo, int n,
			   const double *x, const double *y, const double *z,
			   double *b, double *dlog)
{
	if (j)
		glint_beckmann_lobe_n(p[ROUGH], p[IOR], wo, n, x, y, z, b,
				      dlog);
	else
		diffuse_values(wo, n, z, b, dlog);
}

static double ts_sample_lobe_value(const double *p, int j, struct vec3 wo,
				   const double u[2], struct vec3 *wi,
				   double *bj, double *dlog)
{
	if (j)
		return glint_beckmann_sample_lobe(p[ROUGH], p[IOR], wo, u, wi,
						  bj, dlog);
	double pdf = ts_sample_lobe(p, j, wo, u, wi);
	*bj = pdf > 0 ? 1 / M_PI : 0;
	if (dlog)
		*dlog = 0;
	return pdf;
}

static double ts_lobe_from_geometry(const double *p, int j, const float g[4],
				    double *pdf, double *dlog)
{
	(void)j; /* only the specular lobe varies */
	return glint_beckmann_from_geometry(p[ROUGH], p[IOR], g, pdf, dlog);
}

static double nf_lobe_from_geometry(const double *p, int j, const float g[4],
				    double *pdf, double *dlog)
{
	(void)j;
	return glint_beckmann_from_geometry(p[ROUGH], 0, g, pdf, dlog);
}

static const double *ts_albedo(const void *self, int j)
{
	return (const double *)self + ts_lobe_param[j];
}

/* The specular lobe's samples at once (the diffuse lobe's: one by one,
 * glint_lobe_sample_values()). */
static int ts_sample_values(const double *p, int j, int n,
			    const struct vec3 *wo, const double *u0,
			    const double *u1, double *x, double *y, double *z,
			    double *pdf, double *b, double *dlog)
{
	if (j)
		glint_beckmann_sample_lobe_n(p[ROUGH], p[IOR], n, wo, u0, u1, x,
					     y, z, pdf, b, dlog);
	return j != 0;
}

static const struct glint_bxdf_ops ts_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = ts_eval,
	.sample = ts_sample,
	.pdf = ts_pdf,
	.nlobes = 2,
	.albedo = ts_albedo,
	.eval_lobes = ts_lobes,
	.eval_lobe = ts_lobe,
	.sample_lobe = ts_sample_lobe,
	.pdf_lobe = ts_pdf_lobe,
};

static const int ts_width_param[2] = { -1, ROUGH };

/* Every lobe but the diffuse one (0) carries F(o.h, ior): d log b_j /
 * d ior. */
static double ts_factor_dlog(const double *p, int j, struct vec3 wo,
			     struct vec3 wi)
{
	return j ? glint_fresnel_half_dlog(p[IOR], wo, wi) : 0;
}

static const struct glint_fit_lobes ts_fit = {
	.param = ts_lobe_param,
	.varies = ts_lobe_varies,
	.value_pdf = ts_lobe_value_pdf,
	.sample_value = ts_sample_lobe_value,
	.values = ts_lobe_values,
	.sample_values = ts_sample_values,
	.geometry = glint_beckmann_geometry,
	.from_geometry = ts_lobe_from_geometry,
	.factor_param = IOR,
	.factor_dlog = ts_factor_dlog,
	.roughness_param = ROUGH,
	.microfacet = &glint_microfacet_beckmann,
	.width_param = ts_width_param,
};

const struct glint_model glint_model_torrance_sparrow = {
	.name = "torrance-sparrow",
	.conventions =
		"Torrance-Sparrow: f = diffuse/pi + specular*D*G*F/(4 cos_i "
		"cos_o). D = Beckmann, roughness = RMS microfacet slope m: "
		"D = exp(-tan^2(t_h)/m^2)/(pi m^2 cos^4(t_h)). G = V-cavity "
		"min(1, 2(n.h)(n.o)/(o.h), 2(n.h)(n.i)/(o.h)). F = exact "
		"unpolarised dielectric Fresnel at cos = o.h with index ior.",
	.nparams = 8,
	.params = ts_params,
	.bxdf = &ts_bxdf,
	.lobes = &ts_fit,
};

/*
 * The same without Fresnel variation (F = 1: the specular albedo is the
 * reflectance at every angle): 7 parameters, no ior.  The model selection
 * (fit/select.h) weighs it against the full one.
 */
#define NF_P(q, p)                                                             \
	double q[8];                                                           \
	memcpy(q, p, 7 * sizeof(double));                                      \
	q[IOR] = 0

static void nf_eval(const void *self, struct vec3 wo, struct vec3 wi,
		    double f[3])
{
	const double *p = self;

	NF_P(q, p);
	ts_eval(q, wo, wi, f);
}

static double nf_sample(const void *self, struct vec3 wo, const double u[3],
			struct vec3 *wi)
{
	const double *p = self;

	NF_P(q, p);
	return ts_sample(q, wo, u, wi);
}

static double nf_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	NF_P(q, p);
	return ts_pdf(q, wo, wi);
}

static void nf_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		     double *b)
{
	const double *p = self;

	NF_P(q, p);
	ts_lobes(q, wo, wi, b);
}

static double nf_lobe(const void *self, int j, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	NF_P(q, p);
	return ts_lobe(q, j, wo, wi);
}

static double nf_lobe_value_pdf(const double *p, int j, struct vec3 wo,
				struct vec3 wi, double *pdf, double *dlog)
{
	NF_P(q, p);
	return ts_lobe_value_pdf(q, j, wo, wi, pdf, dlog);
}

static void nf_lobe_values(const double *p, int j, struct vec3 wo, int n,
			   const double *x, const double *y, const double *z,
			   double *b, double *dlog)
{
	if (j)
		glint_beckmann_lobe_n(p[ROUGH], 0, wo, n, x, y, z, b, dlog);
	else
		diffuse_values(wo, n, z, b, dlog);
}

static double nf_sample_lobe_value(const double *p, int j, struct vec3 wo,
				   const double u[2], struct vec3 *wi,
				   double *bj, double *dlog)
{
	NF_P(q, p);
	return ts_sample_lobe_value(q, j, wo, u, wi, bj, dlog);
}

static int nf_sample_values(const double *p, int j, int n,
			    const struct vec3 *wo, const double *u0,
			    const double *u1, double *x, double *y, double *z,
			    double *pdf, double *b, double *dlog)
{
	NF_P(q, p);
	return ts_sample_values(q, j, n, wo, u0, u1, x, y, z, pdf, b, dlog);
}

static const struct glint_bxdf_ops nf_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = nf_eval,
	.sample = nf_sample,
	.pdf = nf_pdf,
	.nlobes = 2,
	.albedo = ts_albedo,
	.eval_lobes = nf_lobes,
	.eval_lobe = nf_lobe,
	.sample_lobe = ts_sample_lobe,
	.pdf_lobe = ts_pdf_lobe,
};

static const struct glint_fit_lobes nf_fit = {
	.param = ts_lobe_param,
	.varies = ts_lobe_varies,
	.value_pdf = nf_lobe_value_pdf,
	.sample_value = nf_sample_lobe_value,
	.values = nf_lobe_values,
	.sample_values = nf_sample_values,
	.geometry = glint_beckmann_geometry,
	.from_geometry = nf_lobe_from_geometry,
	.roughness_param = ROUGH,
	.microfacet = &glint_microfacet_beckmann,
	.width_param = ts_width_param,
};

const struct glint_model glint_model_ts_constant_fresnel = {
	.name = "torrance-sparrow-constant-fresnel",
	.conventions =
		"Torrance-Sparrow without Fresnel variation: f = diffuse/pi + "
		"specular*D*G/(4 cos_i cos_o), D Beckmann with roughness = "
		"RMS microfacet slope, G V-cavity; F = 1 (specular is the "
		"reflectance at every angle).",
	.nparams = 7,
	.params = ts_params,
	.bxdf = &nf_bxdf,
	.lobes = &nf_fit,
};
