/* SPDX-License-Identifier: MIT */
/*
 * Where the naive single pass fails and the paper's three passes succeed:
 * silver (roughness 0.138) under Blender's studio map, fitted at full
 * resolution (no coarse-to-fine, whose safeguards would rescue both).
 * From the paper's initial values with every parameter free, the naive
 * pass ends in a wrong valley, the lobe all but gone and the diffuse
 * taking its light (cost 567 against three-pass's 9.17, specular red
 * 0.076, true 0.676); three-pass fits the diffuse albedo first on the
 * diffuse mask, then the lobe on the specular mask, and ends with a
 * roughness near the truth (0.139).  The test checks the naive pass is
 * far above in cost and far off in specular, not where it stops.
 * On aluminium bronze (roughness 0.023) the naive pass escapes (cost
 * 3.567, as three-pass's), since the lobe samples spread over the pixel
 * from a lobe of two turns of its mirror direction
 * (fit/render/shade_cache_internal.h: SPREAD_FROM): silver is where it
 * still fails.
 * The naive pass is run as the paper describes it, LM straight from the
 * initial values (no_start_scan); glint's naive method, which starts LM
 * from the best of a roughness and ior scan (fit.c, scan_start), must
 * reach three-pass's cost.
 */
#include "test.h"

#include "core/error.h"
#include "fit/fit.h"
#include "sim/reference.h"
#include "sim_scene.h"

int main(void)
{
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	struct glint_fit_result res[3];

	sim_scene_192(&sc, GLINT_TEST_DATA "/studio_dwab.exr", 0);
	CHECK(glint_material_load(GLINT_DATA_DIR "/paper-table1.json", "silver",
				  &m, truth) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return test_result();
	struct glint_image *photo = sim_photo(&r, m, truth);
	CHECK(photo != NULL, "%s", glint_error_msg());
	if (!photo)
		return test_result();
	for (int k = 0; k < 3; k++) {
		struct glint_fit_opts o;
		glint_fit_default_opts(&o);
		/* The configuration the collapse was seen in (--no-coarse
		 * --samples 16); with 8 samples the naive pass happens to
		 * escape it on this photo. */
		o.coarse_to_fine = 0;
		o.light_samples = o.lobe_samples = 16;
		o.method = k == 1 ? GLINT_FIT_THREE_PASS : GLINT_FIT_NAIVE;
		o.no_start_scan = k == 0;
		/* The methods as such: no final polish on several sample
		 * sets (which would take the collapsed naive fit on). */
		o.mc_draws = 0;
		CHECK(glint_fit(&r, m, photo, NULL, &o, &res[k]) == 0, "%s",
		      glint_error_msg());
		printf("%-10s%s cost %9.4f  roughness %.4f (true %.4f)  "
		       "specular.r %.3f (true %.3f)\n",
		       glint_fit_method_name(o.method),
		       k == 0	? " (paper)"
		       : k == 2 ? " (scan) "
				: "        ",
		       res[k].wcost, res[k].p[6], truth[6], res[k].p[3],
		       truth[3]);
	}
	CHECK(res[0].wcost > 2 * res[1].wcost,
	      "naive cost %.4g should be far above three-pass %.4g",
	      res[0].wcost, res[1].wcost);
	CHECK(fabs(res[0].p[3] / truth[3] - 1) > 0.5,
	      "naive roughness %.4f, specular red %.3f: expected it stuck "
	      "in a wrong valley, its specular far off",
	      res[0].p[6], res[0].p[3]);
	CHECK(res[2].wcost < 1.01 * res[1].wcost,
	      "naive with the start scan: cost %.4g, three-pass %.4g",
	      res[2].wcost, res[1].wcost);
	CHECK(fabs(res[1].p[6] / truth[6] - 1) < 0.25,
	      "three-pass roughness %.4f, true %.4f", res[1].p[6], truth[6]);
	glint_image_free(photo);
	glint_renderer_release(&r);
	return test_result();
}
