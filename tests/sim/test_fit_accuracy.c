/* SPDX-License-Identifier: MIT */
/*
 * Accuracy on the simulated rig: a Table-1 material photographed by the
 * independent reference renderer (sim/reference.c: its own ray casting,
 * pseudo-random sampling, power heuristic; no shared sample sets) under a
 * real environment map, noise-free, then fitted with the paper's three-pass
 * method.  The targets: albedos 0.01 absolute, roughness 5 %
 * relative, ior 0.05.  Reached at 192 px (docs/tests.md, "Fit accuracy"):
 * diffuse within 0.01 everywhere; roughness within 5 % in most cases and within
 * 7.5 % in all (yellow plastic and teflon under Venice are the misses,
 * with a fitted cost *below* the truth's: the fast model's own optimum
 * sits there, so more pixels, not more iterations, would close it; at
 * 512 px yellow plastic comes out within 0.2 %).  The test asserts what is
 * reached and prints whether the target is met.  Where the image cannot
 * determine a parameter the test says so and checks what it does:
 *   - roughness below the pixel footprint (a lobe narrower than one pixel's
 *     span of reflected directions, 2/R radians for a sphere R pixels in
 *     radius) is not identifiable: the fit must find a lobe at least that
 *     sharp, and a render error no worse than the truth's;
 *   - specular albedo and ior enter the image mostly as their product
 *     specular * F(ior): when they trade off, the normal-incidence
 *     reflectance specular * F0(ior) must match within 10 % (target 5 %),
 *     for lobes below the pixel footprint too (within 20 % until the
 *     fitter integrated their pixels' footprints and their photos did:
 *     docs/fitting.md, "A near-mirror's sun").
 * And always: the fit's cost is within 1 % of the truth's or below it
 * (else it stopped short of the minimum).
 * Through a lens (F_NUMBER: a 100 mm lens at that f-number focused on the
 * sphere's front) the same must hold: the pixel footprint's integral is
 * off there (fit_data.c), as a lens spreads a pixel's hits over its
 * circle of confusion, which the footprint does not model.
 * "dark" in F_NUMBER's place: the photo through the sensor model
 * exposed so that the whole frame's mean sits at 0.1 % of the ADC range
 * (about 10 electrons a pixel), fitted without a weight image, as a
 * user's own dark HDR photo would be: glint's default variance (signal
 * proportional, its scale unknown) must be evaluated at the fit's
 * prediction, not at the photo's own noisy values, which would give a
 * dark pixel more weight and leave every albedo 20 % low with intervals
 * that miss (bench/accuracy's ACCURACY_NO_WEIGHTS=1 shows it on the
 * studio's aluminium bronze).  Checked: the diffuse albedos
 * within 0.01 and the truth no dearer than the fit on its own
 * objective.
 *   test_fit_accuracy MATERIAL MAP ROTATION_Y [F_NUMBER | dark]
 */
#include "test.h"

#include "sim/fixtures.h"
#include "core/error.h"
#include "fit/fit.h"
#include "fit/job.h"
#include "fit/brdf/microfacet.h"
#include "sim/reference.h"
#include "sim_scene.h"

int main(int argc, char **argv)
{
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];

	if (argc != 4 && argc != 5) {
		fprintf(stderr,
			"usage: %s MATERIAL MAP ROTATION_Y [F_NUMBER]\n",
			argv[0]);
		return 2;
	}
	int dark = argc == 5 && !strcmp(argv[4], "dark");
	sim_scene_192(&sc, argv[2], atof(argv[3]));
	if (argc == 5 &&
	    !dark) /* a 100 mm lens focused on the sphere's front */
		CHECK(glint_pinhole_init(&sc.cam, 192, 192, 0.1, 0.036 / 192,
					 atof(argv[4]), 0.45, v3(0, 0, 0),
					 v3(0, 0, -1), v3(0, 1, 0)) == 0,
		      "%s", glint_error_msg());
	CHECK(glint_material_load(GLINT_DATA_DIR "/paper-table1.json", argv[1],
				  &m, truth) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return test_result();
	double radius_px = sc.cam.fpx * 0.05 / 0.5;
	double footprint = 1 / radius_px; /* roughness a pixel resolves */
	/* A camera's pixel integrates its area: a near-mirror's reflection
	 * of a sun or a softbox's edge covers part of a pixel, which 4
	 * samples alias into a photo no camera takes (its truth then
	 * leaves a relative RMSE above 100 % in the fitter).  Below the
	 * footprint, 16 samples per pixel (at 64 per technique). */
	struct glint_image *photo =
		truth[6] < footprint ? sim_photo_spp(&r, m, truth, 16, 64)
				     : sim_photo(&r, m, truth);
	CHECK(photo != NULL, "%s", glint_error_msg());
	if (!photo)
		return test_result();
	if (dark) {
		struct glint_image *w = NULL;
		CHECK(fixture_add_noise(photo, &w, 0.001) == 0, "%s",
		      glint_error_msg());
		glint_image_free(w); /* fitted as a photo without weights */
		if (test_failures)
			return test_result();
	}

	struct glint_fit_opts o;
	struct glint_fit_result res, at_truth;
	glint_fit_default_opts(&o);
	/* The defaults: 8 + 8 samples, raised by the fit itself where its
	 * sample sets disagree by more than the noise (at 192 px, 8 + 8
	 * left yellow plastic under the studio's softboxes 13 % off in
	 * roughness). */
	CHECK(glint_fit(&r, m, photo, NULL, &o, &res) == 0, "%s",
	      glint_error_msg());
	/* A correct photo is never refused. */
	struct glint_fit_verdict v;
	CHECK(test_failures || glint_fit_judge(&res, 0, &v), "refused: %s",
	      v.verdict);
	/* The truth on the fit's own objective: weights at the fit's
	 * prediction (fit_data.h, the noise model). */
	o.weights_at = res.p;
	CHECK(glint_fit_evaluate(&r, m, photo, NULL, &o, truth, &at_truth) == 0,
	      "%s", glint_error_msg());
	if (test_failures)
		return test_result();

	printf("%s under %s (rotated %s deg): fit in %.2f s with %d + %d "
	       "samples, relative RMSE %.4f (truth %.4f), cost %.6g (truth "
	       "%.6g)\n",
	       argv[1], strrchr(argv[2], '/') + 1, argv[3], res.seconds,
	       res.light_samples, res.lobe_samples, res.rel_rmse,
	       at_truth.rel_rmse, res.wcost, at_truth.wcost);
	printf("  %-11s %9s %9s %9s %9s\n", "parameter", "true", "fitted",
	       "error", "stderr");
	for (int k = 0; k < m->nparams; k++)
		printf("  %-11s %9.4f %9.4f %+9.4f %9.4f%s\n",
		       m->params[k].name, truth[k], res.p[k],
		       res.p[k] - truth[k], res.se[k],
		       res.at_bound[k] ? " (at bound)" : "");

	for (int c = 0; c < 3; c++)
		CHECK(fabs(res.p[c] - truth[c]) <= 0.01,
		      "diffuse[%d] %.4f, true %.4f", c, res.p[c], truth[c]);
	/* The fit minimises the weighted cost: it must not end above the
	 * truth's (else it stopped short of the minimum).  On a dark photo
	 * the weights move with the prediction (about 10 electrons a
	 * pixel), and the fit's own cost is on the weights before its last
	 * polish: both are evaluated here at the fit's weights (the fit's
	 * cost was 7 % above its evaluation at its own parameters). */
	if (dark) {
		struct glint_fit_result at_fit;
		CHECK(glint_fit_evaluate(&r, m, photo, NULL, &o, res.p,
					 &at_fit) == 0,
		      "%s", glint_error_msg());
		printf("  on the fit's weights: cost %.6g, the truth's %.6g\n",
		       at_fit.wcost, at_truth.wcost);
		res.wcost = at_fit.wcost;
	}
	CHECK(res.wcost <= at_truth.wcost * 1.01, "cost %.6g, truth's %.6g",
	      res.wcost, at_truth.wcost);
	if (dark) { /* the rest is the noise's, not the weights' */
		glint_image_free(photo);
		glint_renderer_release(&r);
		return test_result();
	}
	double mt = truth[6], mf = res.p[6];
	int resolved = mt >= footprint;
	if (resolved) {
		printf("  roughness error %.1f %%: target 5 %% %s\n",
		       100 * fabs(mf / mt - 1),
		       fabs(mf / mt - 1) <= 0.05 ? "met" : "MISSED");
		CHECK(fabs(mf / mt - 1) <= 0.075, "roughness %.4f, true %.4f",
		      mf, mt);
	} else {
		printf("  roughness %.4f is below this image's footprint %.4f: "
		       "not identifiable; checking the fit is that sharp\n",
		       mt, footprint);
		CHECK(mf <= footprint, "roughness %.4f: expected <= %.4f", mf,
		      footprint);
		/* said so: an upper bound over the truth, and the interval
		 * from the model's smoothest to it */
		double bound = glint_fit_roughness_bound(&res);
		printf("  reported: roughness < %.4f, interval [%.4f, %.4f]\n",
		       bound, res.unc.lo[6], res.unc.hi[6]);
		CHECK(isfinite(bound) && mt <= bound &&
			      res.unc.lo[6] == m->params[6].lo &&
			      res.unc.hi[6] == bound,
		      "roughness %.4f: bound %g, interval [%g, %g]", mt, bound,
		      res.unc.lo[6], res.unc.hi[6]);
	}
	int ks_ok = 1;
	for (int c = 0; c < 3; c++)
		ks_ok &= fabs(res.p[3 + c] - truth[3 + c]) <= 0.01;
	int ior_ok = fabs(res.p[7] - truth[7]) <= 0.05;
	if (!(ks_ok && ior_ok)) {
		printf("  specular and ior trade off here; checking specular "
		       "x F0(ior)\n");
		double f0t = glint_fresnel_dielectric(1, truth[7]);
		double f0f = glint_fresnel_dielectric(1, res.p[7]);
		double tol = 0.10, worst = 0;
		for (int c = 0; c < 3; c++) {
			double a = truth[3 + c] * f0t, b = res.p[3 + c] * f0f;
			worst = fmax(worst, fabs(b / a - 1));
			CHECK(fabs(b / a - 1) <= tol,
			      "specular[%d] x F0: %.5f, true %.5f", c, b, a);
		}
		printf("  specular x F0 error %.1f %%: target 5 %% %s\n",
		       100 * worst, worst <= 0.05 ? "met" : "MISSED");
	}
	glint_image_free(photo);
	glint_renderer_release(&r);
	return test_result();
}
