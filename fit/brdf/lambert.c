/* SPDX-License-Identifier: MIT */
/* Lambertian reflection: f = albedo / pi. */
#include "model.h"

static const struct glint_param lambert_params[] = {
	{ "diffuse.r", "diffuse", 0, 0, 1, 0.5 },
	{ "diffuse.g", "diffuse", 1, 0, 1, 0.5 },
	{ "diffuse.b", "diffuse", 2, 0, 1, 0.5 },
};

static void lambert_eval(const void *self, struct vec3 wo, struct vec3 wi,
			 double f[3])
{
	const double *p = self;

	int up = wo.z > 0 && wi.z > 0;

	for (int c = 0; c < 3; c++)
		f[c] = up ? p[c] / M_PI : 0;
}

double glint_sample_cosine(const double u[2], struct vec3 *wi)
{
	double r = sqrt(u[0]), phi = 2 * M_PI * u[1];
	double z = sqrt(fmax(0, 1 - u[0]));

	*wi = v3(r * cos(phi), r * sin(phi), z);
	return z / M_PI;
}

static double lambert_sample(const void *self, struct vec3 wo,
			     const double u[3], struct vec3 *wi)
{
	const double *p = self;

	(void)p;
	if (!(wo.z > 0))
		return 0;
	return glint_sample_cosine(u + 1, wi);
}

static double lambert_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	const double *p = self;

	(void)p;
	return wo.z > 0 && wi.z > 0 ? wi.z / M_PI : 0;
}

static const int lambert_lobe_param[1] = { 0 };
static const int lambert_lobe_varies[1] = { 0 };

static void lambert_lobes(const void *self, struct vec3 wo, struct vec3 wi,
			  double *b)
{
	const double *p = self;

	(void)p;
	b[0] = wo.z > 0 && wi.z > 0 ? 1 / M_PI : 0;
}

static double lambert_sample_lobe(const void *self, int j, struct vec3 wo,
				  const double u[2], struct vec3 *wi)
{
	const double *p = self;

	(void)p;
	(void)j;
	if (!(wo.z > 0))
		return 0;
	return glint_sample_cosine(u, wi);
}

static double lambert_pdf_lobe(const void *self, int j, struct vec3 wo,
			       struct vec3 wi)
{
	const double *p = self;

	(void)j;
	return lambert_pdf(p, wo, wi);
}

static const double *lambert_albedo(const void *self, int j)
{
	return (const double *)self + lambert_lobe_param[j];
}

static const struct glint_bxdf_ops lambert_bxdf = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE | GLINT_BXDF_LOBES,
	.eval = lambert_eval,
	.sample = lambert_sample,
	.pdf = lambert_pdf,
	.nlobes = 1,
	.albedo = lambert_albedo,
	.eval_lobes = lambert_lobes,
	.sample_lobe = lambert_sample_lobe,
	.pdf_lobe = lambert_pdf_lobe,
};

static const struct glint_fit_lobes lambert_fit = {
	.param = lambert_lobe_param,
	.varies = lambert_lobe_varies,
	.roughness_param = -1,
};

const struct glint_model glint_model_lambert = {
	.name = "lambert",
	.conventions = "Lambertian: f = diffuse / pi per channel; diffuse is "
		       "the hemispherical albedo in [0, 1].",
	.nparams = 3,
	.params = lambert_params,
	.bxdf = &lambert_bxdf,
	.lobes = &lambert_fit,
};
