/* SPDX-License-Identifier: MIT */
/*
 * Model selection by BIC (fit/select.h) on photos from the independent
 * reference renderer under the Venice map, through one sensor exposure:
 *   satin paint     Table 1 gives it a grey specular: grey must win;
 *   copper          a coloured specular: the full RGB model must win;
 *   a matte sphere  (lambert, satin paint's diffuse): lambert must win;
 *   no Fresnel      copper's parameters rendered with F = 1: the
 *                   constant-Fresnel model must win.
 * And the chosen model's parameters must match the truth's (albedos 0.02).
 *   test_select [CASE...]   (names or parts of them; all without)
 */
#include "test.h"

#include "bench/captures.h"
#include "core/error.h"
#include "core/log.h"
#include "fit/select.h"
#include "sim_scene.h"

struct scase {
	const char *name, *material;
	const struct glint_model_ops *render_model;
	int expect;
};

static int run(const struct scase *cs)
{
	const struct glint_model_ops *m;
	double truth[GLINT_MAX_PARAMS];
	struct glint_scene sc;
	struct glint_renderer r;
	struct glint_image *weight = NULL;
	struct glint_selection sel;

	sim_scene_192(&sc, GLINT_DATA_DIR "/env/venice_sunset_1k.hdr", -114);
	if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
				cs->material, &m, truth) < 0 ||
	    glint_renderer_init(&r, &sc, 0, NULL) < 0)
		return -1;
	struct glint_image *photo = sim_photo(&r, cs->render_model, truth);
	int ret = photo ? bench_add_noise(photo, &weight, 0.1) : -1;
	struct glint_fit_opts o;
	glint_fit_default_opts(&o);
	if (!ret)
		ret = glint_select_model(&r, photo, weight, &o, &sel);
	glint_image_free(photo);
	glint_image_free(weight);
	glint_renderer_release(&r);
	if (ret < 0)
		return ret;
	printf("%s: %s\n", cs->name, sel.why);
	for (int k = 0; k < GLINT_SEL_N; k++)
		printf("  %-36s k %d  cost %12.2f  BIC %12.1f  AIC %12.1f\n",
		       sel.c[k].name, sel.c[k].k, sel.c[k].cost, sel.c[k].bic,
		       sel.c[k].aic);
	CHECK(sel.chosen == cs->expect, "%s: chose %s, expected %s", cs->name,
	      sel.c[sel.chosen].name, sel.c[cs->expect].name);
	const struct glint_select_candidate *c = &sel.c[sel.chosen];
	for (int k = 0; k < 3; k++)
		CHECK(fabs(c->p[k] - truth[k]) < 0.02,
		      "%s: diffuse[%d] %.4f, true %.4f", cs->name, k, c->p[k],
		      truth[k]);
	if (sel.chosen != GLINT_SEL_LAMBERT)
		for (int k = 3; k < 6; k++)
			CHECK(fabs(c->p[k] - truth[k]) < 0.05,
			      "%s: specular[%d] %.4f, true %.4f", cs->name,
			      k - 3, c->p[k], truth[k]);
	/* The report names every candidate and finite criteria. */
	for (int k = 0; k < GLINT_SEL_N; k++)
		CHECK(isfinite(sel.c[k].bic) && isfinite(sel.c[k].aic),
		      "%s: %s BIC %g", cs->name, sel.c[k].name, sel.c[k].bic);
	return 0;
}

int main(int argc, char **argv)
{
	static const struct scase cases[] = {
		{ "satin paint", "satin-paint", &glint_model_torrance_sparrow,
		  GLINT_SEL_GREY },
		{ "copper", "copper", &glint_model_torrance_sparrow,
		  GLINT_SEL_RGB },
		{ "matte", "satin-paint", &glint_model_lambert,
		  GLINT_SEL_LAMBERT },
		{ "no Fresnel", "nickel", &glint_model_ts_constant_fresnel,
		  GLINT_SEL_CONST_FRESNEL },
	};
	glint_log_set_mode(GLINT_LOG_QUIET);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		int want = argc < 2;
		for (int a = 1; a < argc; a++)
			want |= strstr(cases[i].name, argv[a]) != NULL;
		if (want)
			CHECK(run(&cases[i]) == 0, "%s: %s", cases[i].name,
			      glint_error_msg());
	}
	return test_result();
}
