/* SPDX-License-Identifier: MIT */
/* The exports' refits (export/export.h): exact where the target can be. */
#include "test.h"

#include "core/error.h"
#include "fit/brdf/model.h"
#include "export/export.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void test_formats_parse(void)
{
	unsigned f = 0;
	CHECK(glint_export_formats_parse("gltf,pbrt", &f) == 0 &&
		      f == (1u << GLINT_EXPORT_GLTF | 1u << GLINT_EXPORT_PBRT),
	      "f = %#x", f);
	CHECK(glint_export_formats_parse("mitsuba", &f) == 0 &&
		      f == 1u << GLINT_EXPORT_MITSUBA,
	      "f = %#x", f);
	CHECK(glint_export_formats_parse("gltf,mitsuba3", &f) == -EINVAL,
	      "a misspelt name accepted");
	CHECK_MSG(glint_error_msg(), "'mitsuba3'");
	CHECK_MSG(glint_error_msg(), "did you mean 'mitsuba'");
	CHECK(glint_export_formats_parse("", &f) == -EINVAL, "empty list");
	CHECK(glint_export_formats_parse("gltf,", &f) == -EINVAL,
	      "empty name after a comma");
	glint_error_clear();
}

/* glint's GGX model with a grey specular albedo is exactly pbrt's mix of
 * diffuse and a k = 0 conductor (amount = ks, R = kd / (1 - ks), eta =
 * ior): the refit must find it. */
static void test_pbrt_exact(void)
{
	const double p[] = { 0.2, 0.3, 0.4, 0.3, 0.3, 0.3, 0.15, 1.6 };
	struct glint_export e;
	CHECK(glint_export_refit(GLINT_EXPORT_PBRT, &glint_model_ggx, p, NAN,
				 &e) == 0,
	      "%s", glint_error_msg());
	CHECK(e.residual < 1e-4, "residual %g", e.residual);
	CHECK_NEAR(e.x[4], 0.15, 1e-3, "alpha");
	CHECK_NEAR(e.x[3], 0.3, 2e-3, "amount");
	for (int c = 0; c < 3; c++) {
		CHECK_NEAR(e.x[c], p[c] / 0.7, 2e-3, "R");
		CHECK_NEAR(e.x[5 + c], 1.6, 1e-2, "eta");
	}
	/* The residual restated from the parameters alone. */
	CHECK_NEAR(glint_export_residual(&glint_model_ggx, p, &e), e.residual,
		   1e-9, "residual");
}

/* Mitsuba keeps Beckmann and the exact Fresnel term: only Smith's G
 * against the V-cavity's is left, a few percent for a broad lobe; glTF
 * and pbrt (GGX only) leave more. */
static void test_beckmann_targets(void)
{
	const double p[] = { 0.3, 0.2, 0.1, 0.4, 0.4, 0.4, 0.3, 1.5 };
	struct glint_export e[GLINT_EXPORT_NFORMATS];
	for (int k = 0; k < GLINT_EXPORT_NFORMATS; k++)
		CHECK(glint_export_refit((enum glint_export_format)k,
					 &glint_model_torrance_sparrow, p, NAN,
					 &e[k]) == 0,
		      "%s", glint_error_msg());
	fprintf(stderr, "  residuals: gltf %.4f mitsuba %.4f pbrt %.4f\n",
		e[0].residual, e[1].residual, e[2].residual);
	CHECK(e[GLINT_EXPORT_MITSUBA].residual > 1e-4 &&
		      e[GLINT_EXPORT_MITSUBA].residual < 0.05,
	      "mitsuba %g", e[GLINT_EXPORT_MITSUBA].residual);
	CHECK(!e[GLINT_EXPORT_MITSUBA].ggx, "a Beckmann model as GGX");
	CHECK_NEAR(e[GLINT_EXPORT_MITSUBA].x[3], 0.3, 0.05, "alpha");
	CHECK(e[GLINT_EXPORT_GLTF].residual >
			      e[GLINT_EXPORT_MITSUBA].residual &&
		      e[GLINT_EXPORT_PBRT].residual >
			      e[GLINT_EXPORT_MITSUBA].residual,
	      "GGX targets fit a Beckmann lobe better than Beckmann");
	/* Each target's own BRDF, evaluated where glint's is known. */
	double f[3], g[3];
	struct vec3 wo = v3(0.5, 0, sqrt(0.75)), wi = v3(-0.5, 0, sqrt(0.75));
	glint_model_torrance_sparrow.bxdf->eval(p, wo, wi, g);
	glint_export_brdf(&e[GLINT_EXPORT_MITSUBA], wo, wi, f);
	CHECK_NEAR(f[0], g[0], 0.03 * g[0], "mitsuba at the mirror angle");
	glint_export_brdf(&e[GLINT_EXPORT_MITSUBA], wo, v3(0, 0, -1), f);
	CHECK(f[0] == 0 && f[1] == 0 && f[2] == 0, "below the surface");
}

static void test_lambert_exact(void)
{
	const double p[] = { 0.5, 0.4, 0.3 };
	for (int k = 0; k < GLINT_EXPORT_NFORMATS; k++) {
		struct glint_export e;
		CHECK(glint_export_refit((enum glint_export_format)k,
					 &glint_model_lambert, p, NAN, &e) == 0,
		      "%s", glint_error_msg());
		CHECK(e.residual < 1e-6, "%s: residual %g",
		      glint_export_format_names[k], e.residual);
	}
}

/* A transparent sphere carries across: its absorption per metre from
 * the transmission per diameter, and only glTF's Schlick Fresnel leaves a
 * residual. */
static void test_transparent(void)
{
	const double p[] = { 0.6, 0.7, 0.9, 1.55 };
	struct glint_export e;
	CHECK(glint_export_refit(GLINT_EXPORT_MITSUBA, &glint_model_dielectric,
				 p, NAN, &e) == -EINVAL,
	      "a transparent sphere exported without its diameter");
	CHECK_MSG(glint_error_msg(), "needs the sphere's diameter");
	glint_error_clear();
	for (int k = 0; k < GLINT_EXPORT_NFORMATS; k++) {
		CHECK(glint_export_refit((enum glint_export_format)k,
					 &glint_model_dielectric, p, 0.05,
					 &e) == 0,
		      "%s", glint_error_msg());
		CHECK(e.dielectric && e.ior == 1.55, "%s: ior %g",
		      glint_export_format_names[k], e.ior);
		if (k == GLINT_EXPORT_GLTF)
			CHECK(e.residual > 0.01 && e.residual < 0.5,
			      "Schlick's residual %g", e.residual);
		else
			CHECK(e.residual == 0, "%s: residual %g",
			      glint_export_format_names[k], e.residual);
		CHECK_NEAR(
			glint_export_residual(&glint_model_dielectric, p, &e),
			e.residual, 1e-12, "residual restated");
		json_t *j = glint_export_params_json(&e);
		json_t *a = json_object_get(j, "absorption_per_m");
		CHECK_NEAR(json_real_value(json_array_get(a, 0)),
			   -log(0.6) / 0.05, 1e-9, "sigma_a red");
		json_decref(j);
		char *t = glint_export_text(&e, "blue quartz", "params.json",
					    &glint_model_dielectric);
		CHECK(t, "no text");
		static const char *const must[] = {
			"KHR_materials_volume", "<medium type=\"homogeneous\"",
			"\"string type\" \"dielectric\"",
			"ShaderNodeVolumeAbsorption",
			("name=\"transmission_depth\" type=\"float\" "
			 "value=\"0.05\"")
		};
		CHECK(t && strstr(t, must[k]), "%s: no '%s' in\n%s",
		      glint_export_format_names[k], must[k], t ? t : "");
		free(t);
	}
}

/* MaterialX: the layered standard_surface keeps a diffuse under a GGX
 * lobe close to glint's own (the multiple-scattering compensation and
 * the albedo-scaled base are what is left); an Oren-Nayar base carries
 * across; names are MaterialX identifiers. */
static void test_materialx(void)
{
	const double ggx[] = { 0.3, 0.2, 0.1, 0.3, 0.3, 0.3, 0.2, 1.5 };
	struct glint_export e;
	CHECK(glint_export_refit(GLINT_EXPORT_MATERIALX, &glint_model_ggx, ggx,
				 NAN, &e) == 0,
	      "%s", glint_error_msg());
	fprintf(stderr, "  materialx residual for ggx: %.4f\n", e.residual);
	CHECK(e.residual < 0.05, "residual %g", e.residual);
	CHECK_NEAR(e.x[4] * e.x[4], 0.2, 0.03, "GGX alpha");
	char *t = glint_export_text(&e, "7-satin.paint", "params.json",
				    &glint_model_ggx);
	CHECK(t && strstr(t, "<surfacematerial name=\"m_7_satin_paint\""), "%s",
	      t ? t : "NULL");
	free(t);

	double on[GLINT_MAX_PARAMS];
	for (int k = 0; k < glint_model_oren_nayar.nparams; k++)
		on[k] = glint_model_oren_nayar.params[k].def;
	int dr = -1;
	for (int k = 0; k < glint_model_oren_nayar.nparams; k++)
		if (!strcmp(glint_model_oren_nayar.params[k].name,
			    "diffuse_roughness"))
			dr = k;
	CHECK(dr >= 0, "no diffuse_roughness");
	if (dr < 0)
		return;
	/* Without a specular lobe the layered base is exactly Oren-Nayar. */
	on[dr] = 0.4;
	for (int c = 0; c < 3; c++)
		on[glint_model_oren_nayar.lobes->param[1] + c] = 0;
	CHECK(glint_export_refit(GLINT_EXPORT_MATERIALX,
				 &glint_model_oren_nayar, on, NAN, &e) == 0,
	      "%s", glint_error_msg());
	fprintf(stderr, "  materialx residual for oren-nayar: %.4f\n",
		e.residual);
	CHECK(e.residual < 1e-4, "residual %g", e.residual);
	CHECK_NEAR(e.x[3], 0.4, 1e-3, "diffuse_roughness");
}

/* The files: names made safe, Mitsuba's reflectances within [0, 1] and
 * a specular one above 1 marked unbounded. */
static void test_text(void)
{
	const double p[] = { 0.8, 0.8, 0.8, 0.9, 0.9, 0.9, 0.1, 1.5 };
	struct glint_export e;
	CHECK(glint_export_refit(GLINT_EXPORT_MITSUBA,
				 &glint_model_torrance_sparrow, p, NAN,
				 &e) == 0,
	      "%s", glint_error_msg());
	char *t = glint_export_text(&e, "my <paint>", "params.json",
				    &glint_model_torrance_sparrow);
	CHECK(t && strstr(t, "id=\"my__paint_\""), "%s", t ? t : "NULL");
	CHECK(t && strstr(t, "name=\"unbounded\" value=\"true\""), "%s",
	      t ? t : "NULL");
	CHECK(t && strstr(t, "<float name=\"eta\" value=\"1.5\"/>"), "%s",
	      t ? t : "NULL");
	free(t);
	json_t *j = glint_export_params_json(&e);
	json_t *r = json_object_get(j, "reflectance");
	for (int c = 0; c < 3; c++)
		CHECK(json_real_value(json_array_get(r, c)) <= 1 + 1e-12,
		      "diffuse reflectance %g above 1",
		      json_real_value(json_array_get(r, c)));
	json_decref(j);

	e.format = GLINT_EXPORT_PBRT;
	t = glint_export_text(&e, "x\"y", "params.json",
			      &glint_model_torrance_sparrow);
	CHECK(t && strstr(t, "MakeNamedMaterial \"x_y\"") &&
		      strstr(t, "\"string materials\" [ \"x_y.diffuse\" "
				"\"x_y.specular\" ]"),
	      "%s", t ? t : "NULL");
	free(t);
}

int main(void)
{
	RUN(test_formats_parse);
	RUN(test_pbrt_exact);
	RUN(test_beckmann_targets);
	RUN(test_lambert_exact);
	RUN(test_transparent);
	RUN(test_materialx);
	RUN(test_text);
	return test_result();
}
