/* SPDX-License-Identifier: MIT */
/*
 * One material fitted to several photos of it (glint_fit_views(), issue
 * 15): teflon photographed by the independent reference renderer under a
 * small disc light (0.5 degrees, with a faint uniform sky), once near the
 * camera ("front": 20 degrees from the view) and once behind the sphere
 * ("rim": 140 degrees), through the simulated sensor.
 *
 * Under one distant light every pixel sees Fresnel at the same angle (half
 * the angle between light and view), so one photo fixes specular x F(ior)
 * and not the two apart; two lights at different angles do.
 *   1. the same photo twice: the single fit's answer, its textbook
 *      errors narrower by sqrt(2) (the objective is the single one
 *      doubled); where specular and ior trade off, the same specular x
 *      F0(ior) (along the ridge either fit may end anywhere);
 *   2. front alone: glint says specular and ior trade off, or ior is not
 *      determined;
 *   3. front + rim: ior determined, within tolerance (0.05), its interval
 *      holding the truth and narrower than front alone's, the photos'
 *      own correlation of specular and ior off the ridge; every albedo
 *      and roughness within their intervals;
 *   4. per-photo statistics: each photo's pixels, and a fit better than
 *      its bare backdrop and a flat disc;
 *   5. what cannot be fitted jointly is refused by name: no photos, a
 *      transparent model, --faithful, a photo of the wrong size (its
 *      number in the message);
 *   6. model selection (glint_select_model_views(), what --select-model
 *      and the automatic choice run): on front alone the BIC cannot
 *      prefer a Fresnel with an ior to a constant one by much; front +
 *      rim choose a model with an ior, by a clear margin;
 *   7. per light (glint_fit_per_light(), what a joint glint fit reports):
 *      front + rim of the same teflon drift in no parameter; front of
 *      teflon + rim of a teflon half again as rough drift in roughness,
 *      and the verdict says so.
 */
#include "test.h"

#include "sim/fixtures.h"
#include "core/error.h"
#include "core/log.h"
#include "fit/brdf/microfacet.h"
#include "fit/brdf/model.h"
#include "fit/fit.h"
#include "fit/per_light.h"
#include "fit/select.h"
#include "sim_scene.h"

struct shot {
	struct glint_renderer r;
	struct glint_image *photo, *weight;
};

/* The sphere lit from `deg` degrees off the view axis (about y). */
static int shoot(double deg, const struct glint_model *m, const double *truth,
		 struct shot *s)
{
	struct glint_scene sc;
	struct glint_envmap *env = NULL;
	double a = deg * M_PI / 180;
	struct glint_image *map =
		fixture_disc_map(v3(sin(a), 0, cos(a)), 1024, 0.5, 0.01);

	memset(s, 0, sizeof(*s));
	sim_scene_192(&sc, "disc light", 0);
	if (!map ||
	    glint_envmap_new(map, sc.env_rotation, 1, "disc light", &env) < 0 ||
	    glint_renderer_init_env(&s->r, &sc, env, 0, NULL) < 0)
		return -1;
	/* 256 samples per technique, and more rounds for a pixel whose
	 * relative standard error is over 1 %: at sim_photo()'s 64 the
	 * photo's own Monte Carlo noise is above the sensor's (the weights'
	 * chi2 per value 2.9 at the truth), and at 256 alone its highlight
	 * put the joint specular 4.4 % low and ior's interval off the truth
	 * (no camera has that noise) */
	struct glint_reference_opts ro;
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	ro.samples = 256;
	ro.rel_noise = 0.01;
	s->photo = glint_image_new(sc.cam.width, sc.cam.height);
	if (!s->photo || glint_reference_render(&s->r.scene, s->r.env, m, truth,
						&ro, s->photo) < 0)
		return -1;
	return fixture_add_noise(s->photo, &s->weight, 0.1);
}

static void shot_free(struct shot *s)
{
	glint_renderer_release(&s->r);
	glint_image_free(s->photo);
	glint_image_free(s->weight);
}

static int fit(struct shot **shots, int n, const struct glint_model *m,
	       struct glint_fit_result *res)
{
	struct glint_fit_view v[4];
	struct glint_fit_opts o;

	glint_fit_default_opts(&o);
	for (int k = 0; k < n; k++)
		v[k] = (struct glint_fit_view){ &shots[k]->r, shots[k]->photo,
						shots[k]->weight };
	int ret = glint_fit_views(v, n, m, &o, res);
	if (ret < 0)
		fprintf(stderr, "fit: %s\n", glint_error_msg());
	return ret;
}

/* 7. Per light: the joint fit of shots a and b, each alone, and the
 * drift of every parameter with the light's angle. */
static int per_light(struct shot *a, struct shot *b,
		     const struct glint_model *m,
		     const struct glint_fit_result *known,
		     struct glint_per_light *pl)
{
	struct shot *ab[] = { a, b };
	struct glint_fit_result *joint = known ? NULL : malloc(sizeof(*joint));
	struct glint_fit_view v[2] = { { &a->r, a->photo, a->weight },
				       { &b->r, b->photo, b->weight } };
	struct glint_fit_opts o;
	glint_fit_default_opts(&o);
	int ret = known ? 0 : joint ? fit(ab, 2, m, joint) : -1;
	if (ret == 0)
		ret = glint_fit_per_light(v, 2, m, &o, known ? known : joint,
					  pl);
	if (ret < 0)
		fprintf(stderr, "per light: %s\n", glint_error_msg());
	free(joint);
	if (ret == 0) {
		for (int k = 0; k < m->nparams; k++)
			printf("  %-10s %8.4f (%6.1f deg) %8.4f (%6.1f deg): "
			       "slope %+.4f per 10 deg, z %+.2f\n",
			       m->params[k].name, pl->p[0][k], pl->angle_deg[0],
			       pl->p[1][k], pl->angle_deg[1], pl->slope[k],
			       pl->z[k]);
		printf("  %s\n", pl->verdict);
	}
	return ret;
}

/* The photos' own correlation of parameters i and j: from the textbook
 * covariance, without the systematic terms (the small sphere's runs along
 * the specular/ior ridge itself: fit/discrepancy.c). */
static double photo_corr(const struct glint_fit_result *r, int i, int j)
{
	int n = r->unc.n;
	const double *c = r->unc.cov_textbook;

	return c[i * n + j] / sqrt(c[i * n + i] * c[j * n + j]);
}

static void print(const char *what, const struct glint_fit_result *r)
{
	const struct glint_model *m = r->model;

	printf("%-14s", what);
	for (int k = 0; k < m->nparams; k++)
		printf(" %s %.4f+-%.4f", m->params[k].name, r->p[k], r->se[k]);
	printf("\n%14s corr(specular, ior) %.3f (the photos' %.3f), rel. "
	       "RMSE %.4f over %d photos:",
	       "", r->unc.corr[3 * m->nparams + 7], photo_corr(r, 3, 7),
	       r->rel_rmse, r->nviews);
	for (int v = 0; v < r->nviews; v++)
		printf(" %.4f (%d px)", r->view[v].rel_rmse, r->view[v].pixels);
	printf("\n");
}

/* Does r hold the truth in every 95 % interval? Counts the misses. */
static int misses(const struct glint_fit_result *r, const double *truth)
{
	int miss = 0;

	for (int k = 0; k < r->model->nparams; k++)
		if (truth[k] < r->unc.lo[k] || truth[k] > r->unc.hi[k]) {
			printf("  %s: truth %.4f outside [%.4f, %.4f]\n",
			       r->model->params[k].name, truth[k], r->unc.lo[k],
			       r->unc.hi[k]);
			miss++;
		}
	return miss;
}

static void refusals(struct shot *front, const struct glint_model *m)
{
	struct glint_fit_result res;
	struct glint_fit_opts o;
	struct glint_fit_view v[2] = {
		{ &front->r, front->photo, front->weight },
		{ &front->r, front->photo, front->weight },
	};
	struct glint_image *small = glint_image_new(64, 64);

	glint_fit_default_opts(&o);
	CHECK(glint_fit_views(v, 0, m, &o, &res) == -EINVAL, "no photos");
	CHECK_MSG(glint_error_msg(), "0 photos");
	CHECK(glint_fit_views(v, 2, &glint_model_dielectric, &o, &res) ==
		      -EINVAL,
	      "transparent");
	CHECK_MSG(glint_error_msg(), "transparent");
	o.faithful = 1;
	CHECK(glint_fit_views(v, 2, m, &o, &res) == -EINVAL, "faithful");
	CHECK_MSG(glint_error_msg(), "--faithful");
	o.faithful = 0;
	v[1].photo = small;
	v[1].weight = NULL;
	CHECK(small && glint_fit_views(v, 2, m, &o, &res) == -EINVAL,
	      "wrong size");
	CHECK_MSG(glint_error_msg(), "photo 2 of 2");
	CHECK_MSG(glint_error_msg(), "64x64");
	glint_image_free(small);
}

int main(void)
{
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	struct shot front, rim;
	struct glint_fit_result one, twice, joint;
	int ior_k = 7;

	glint_log_set_mode(GLINT_LOG_QUIET);
	if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json", "teflon",
				&m, truth) < 0 ||
	    shoot(20, m, truth, &front) < 0 || shoot(140, m, truth, &rim) < 0) {
		fprintf(stderr, "set-up: %s\n", glint_error_msg());
		return 1;
	}
	struct shot *a[] = { &front }, *aa[] = { &front, &front },
		    *ab[] = { &front, &rim };
	if (fit(a, 1, m, &one) < 0 || fit(aa, 2, m, &twice) < 0 ||
	    fit(ab, 2, m, &joint) < 0)
		return 1;
	print("front", &one);
	print("front twice", &twice);
	print("front + rim", &joint);

	/* 1. The same photo twice: the same optimum; the textbook errors
	 * (s^2 (J'J)^-1: J'J doubled, s^2 the same) shrink by sqrt(2).  The
	 * reported ones need not: their systematic part (the fast render
	 * against the reference renderer) is the same for every photo. */
	/* Where specular and ior trade off (|correlation| >= 0.95: glint
	 * says the photo does not tell them apart), the fit can end
	 * anywhere along the ridge; what must agree is the combination the
	 * photo determines, specular x F0(ior), below. */
	int n = m->nparams;
	for (int k = 0; k < n; k++) {
		int ridge =
			(k >= 3 && k < 6 &&
			 fabs(one.unc.corr[k * n + ior_k]) >= 0.95) ||
			(k == ior_k && fabs(one.unc.corr[3 * n + k]) >= 0.95);
		if (ridge) {
			printf("%s: on the specular/ior ridge (twice %.5f, "
			       "once %.5f)\n",
			       m->params[k].name, twice.p[k], one.p[k]);
			continue;
		}
		CHECK(fabs(twice.p[k] - one.p[k]) <= 0.25 * one.se[k] + 1e-6,
		      "%s: twice %.5f, once %.5f +- %.5f", m->params[k].name,
		      twice.p[k], one.p[k], one.se[k]);
		double ratio =
			twice.unc.se_textbook[k] / one.unc.se_textbook[k];
		CHECK(fabs(ratio - sqrt(0.5)) < 0.03,
		      "%s: textbook error twice / once %.4f, expected 0.707",
		      m->params[k].name, ratio);
	}
	for (int k = 3; k < 6; k++) {
		double n1 = one.p[ior_k], f1 = glint_fresnel_dielectric(1, n1),
		       f2 = glint_fresnel_dielectric(1, twice.p[ior_k]);
		double g[GLINT_MAX_PARAMS] = { 0 };
		g[k] = f1;
		g[ior_k] = one.p[k] * 4 * (n1 - 1) / pow(n1 + 1, 3);
		double se = glint_uncertainty_delta(&one.unc, g);
		CHECK(fabs(twice.p[k] * f2 - one.p[k] * f1) <= 0.25 * se + 1e-6,
		      "%s x F0(ior): twice %.5f, once %.5f +- %.5f",
		      m->params[k].name, twice.p[k] * f2, one.p[k] * f1, se);
	}
	CHECK(twice.nviews == 2 && twice.view[0].pixels == one.pixels &&
		      twice.view[1].pixels == one.pixels,
	      "twice: %d photos, %d and %d pixels (once %d)", twice.nviews,
	      twice.view[0].pixels, twice.view[1].pixels, one.pixels);

	/* 2. One light: specular and ior not apart. */
	double c = one.unc.corr[3 * m->nparams + ior_k];
	double half = 0.5 * (m->params[ior_k].hi - m->params[ior_k].lo);
	CHECK(fabs(c) >= 0.95 || one.unc.hi[ior_k] - one.unc.lo[ior_k] > half,
	      "front alone: corr(specular R, ior) %.3f, ior interval "
	      "[%.3f, %.3f]",
	      c, one.unc.lo[ior_k], one.unc.hi[ior_k]);

	/* 3. Two lights: ior pinned. */
	CHECK_NEAR(joint.p[ior_k], truth[ior_k], 0.05, "joint ior");
	CHECK(joint.unc.hi[ior_k] - joint.unc.lo[ior_k] <
		      0.5 * (one.unc.hi[ior_k] - one.unc.lo[ior_k]),
	      "joint ior interval [%.3f, %.3f], front alone [%.3f, %.3f]",
	      joint.unc.lo[ior_k], joint.unc.hi[ior_k], one.unc.lo[ior_k],
	      one.unc.hi[ior_k]);
	CHECK(misses(&joint, truth) == 0, "joint: intervals miss the truth");
	CHECK(fabs(photo_corr(&joint, 3, ior_k)) < 0.95,
	      "joint: the photos' corr(specular R, ior) %.3f",
	      photo_corr(&joint, 3, ior_k));

	/* 4. Per photo. */
	CHECK(joint.nviews == 2, "%d photos", joint.nviews);
	for (int v = 0; v < 2; v++)
		CHECK(joint.view[v].pixels > 1000 &&
			      joint.view[v].rel_rmse <
				      joint.view[v].flat_rel_rmse &&
			      joint.view[v].rel_rmse <
				      joint.view[v].backdrop_rel_rmse,
		      "photo %d: %d pixels, rel. RMSE %.4f (flat disc %.4f, "
		      "backdrop %.4f)",
		      v + 1, joint.view[v].pixels, joint.view[v].rel_rmse,
		      joint.view[v].flat_rel_rmse,
		      joint.view[v].backdrop_rel_rmse);
	CHECK(joint.pixels == joint.view[0].pixels + joint.view[1].pixels,
	      "pixels %d", joint.pixels);

	/* 6. Model selection over both photos. */
	struct glint_selection *sel1 = calloc(1, sizeof(*sel1)),
			       *sel2 = calloc(1, sizeof(*sel2));
	struct glint_fit_view v2[2] = {
		{ &front.r, front.photo, front.weight },
		{ &rim.r, rim.photo, rim.weight },
	};
	struct glint_fit_opts o;
	glint_fit_default_opts(&o);
	CHECK(sel1 && sel2 &&
		      glint_select_model_views(v2, 1, &o, 0, sel1) == 0 &&
		      glint_select_model_views(v2, 2, &o, 0, sel2) == 0,
	      "select: %s", glint_error_msg());
	if (sel1 && sel2 && !test_failures) {
		const struct glint_selection *ss[2] = { sel1, sel2 };
		double gap[2];
		for (int k = 0; k < 2; k++) {
			/* BIC of constant Fresnel above the better of the
			 * two with an ior */
			double with = fmin(ss[k]->c[GLINT_SEL_RGB].bic,
					   ss[k]->c[GLINT_SEL_GREY].bic);
			gap[k] = ss[k]->c[GLINT_SEL_CONST_FRESNEL].bic - with;
			printf("select %-9s chosen %s; constant Fresnel's BIC "
			       "%+.1f above the best with an ior\n  %s\n",
			       k ? "front+rim" : "front",
			       ss[k]->c[ss[k]->chosen].name, gap[k],
			       ss[k]->why);
		}
		CHECK(sel2->chosen == GLINT_SEL_RGB ||
			      sel2->chosen == GLINT_SEL_GREY,
		      "front + rim chose %s", sel2->c[sel2->chosen].name);
		CHECK(gap[1] > 10 && gap[1] > 3 * fabs(gap[0]),
		      "front + rim: constant Fresnel only %+.1f above (front "
		      "alone %+.1f)",
		      gap[1], gap[0]);
		CHECK(sel2->has_fit[GLINT_SEL_RGB] &&
			      sel2->fit[GLINT_SEL_RGB].nviews == 2,
		      "the candidates are fitted to both photos");
	}
	free(sel1);
	free(sel2);

	/* 7. Per light. */
	struct glint_per_light *pl = malloc(sizeof(*pl));
	struct shot rough;
	double other[GLINT_MAX_PARAMS];
	memcpy(other, truth, sizeof(other));
	other[6] *= 1.5;
	CHECK(pl && per_light(&front, &rim, m, &joint, pl) == 0, "per light");
	if (pl && !test_failures)
		CHECK(pl->ndrift == 0 && strstr(pl->verdict, "explains every"),
		      "front + rim of one teflon: %s", pl->verdict);
	CHECK(shoot(140, m, other, &rough) == 0, "%s", glint_error_msg());
	CHECK(pl && per_light(&front, &rough, m, NULL, pl) == 0, "per light");
	if (pl && !test_failures)
		CHECK(pl->drifts[6] && strstr(pl->verdict, "roughness drifts"),
		      "front of teflon + rim of a rougher one: roughness z "
		      "%.2f: %s",
		      pl->z[6], pl->verdict);
	/* the same light twice: nothing to test, nothing fitted */
	CHECK(pl && per_light(&front, &front, m, &twice, pl) == 0 &&
		      strstr(pl->verdict, "no trend to test") &&
		      isnan(pl->p[0][6]),
	      "front twice: %s", pl ? pl->verdict : "");
	shot_free(&rough);
	free(pl);

	/* 5. Refusals. */
	refusals(&front, m);
	shot_free(&front);
	shot_free(&rim);
	printf("%d checks, %d failed\n", test_checks, test_failures);
	return test_failures ? 1 : 0;
}
