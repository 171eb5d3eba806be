/* SPDX-License-Identifier: MIT */
/*
 * fit/optim/uncertainty.c on straight lines with known noise, where the
 * truth is known exactly:
 *   - independent noise: the textbook covariance matches sigma^2
 *     (X^T X)^-1, the block covariance agrees with it, and 95 % intervals
 *     cover the truth in 93-97 % of 2000 trials;
 *   - noise shared within blocks (a misfit that is correlated over
 *     regions): the textbook intervals cover far too rarely and glint's
 *     block intervals within 90-98 %;
 *   - sample sets: residual draws that differ by a known shift give the
 *     Monte Carlo covariance of their mean, and it enters the intervals;
 *   - the model-error jackknife over regions: on a line fitted to a
 *     parabola (a model too simple) it equals the jackknife of exact
 *     refits without each region, and it enters the intervals with its
 *     degrees of freedom; on a true line it stays near the textbook
 *     variance;
 *   - a column of zeros (a parameter the data cannot see) gets an
 *     infinite standard error and its whole bound range;
 *   - the delta method on a product of two parameters;
 *   - the systematic term sized by the light map (fit/discrepancy.c): a
 *     map that is the light, one from a probe of a given resolution (its
 *     roughness term growing with the probe pixel's angle) and one of
 *     unknown resolution;
 *   - what params.json says the photo does not determine: a
 *     Torrance-Sparrow result whose specular albedos and ior correlate
 *     (the trade-off, with specular x F0(ior) and its error), whose
 *     roughness interval lies below the pixel footprint (an upper bound),
 *     and one whose ior interval spans its bounds (not determined); and a
 *     well-determined result that says nothing.
 */
#include "test.h"

#include "fit/brdf/microfacet.h"
#include "fit/internal.h"
#include "fit/job.h"
#include "fit/optim/uncertainty.h"

#include <stdint.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define M  400
#define NB 40

static uint64_t rng = 88172645463325252ull;

static double gauss(void)
{
	double u, v;
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	u = ((rng >> 11) + 0.5) / 9007199254740992.0;
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	v = ((rng >> 11) + 0.5) / 9007199254740992.0;
	return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}

/* The least-squares line through the points of x, y not in region
 * `skip` (-1: all). */
static void line_fit(const double *x, const double *y, const int *region,
		     int skip, double p[2])
{
	double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
	for (int i = 0; i < M; i++) {
		if (region[i] == skip)
			continue;
		n++;
		sx += x[i];
		sy += y[i];
		sxx += x[i] * x[i];
		sxy += x[i] * y[i];
	}
	p[1] = (n * sxy - sx * sy) / (n * sxx - sx * sx);
	p[0] = (sy - p[1] * sx) / n;
}

/* y = a + b x + noise on x in [0, 1); the least-squares line into p and
 * its problem (residuals model - y, Jacobian [1, x]). */
static void line(double sigma, double shared, double *jac, double *r,
		 int *block, double p[2])
{
	double y[M], x[M], blk[NB];

	for (int b = 0; b < NB; b++)
		blk[b] = shared * gauss();
	for (int i = 0; i < M; i++) {
		x[i] = (double)i / M;
		block[i] = i * NB / M;
		y[i] = 1 + 2 * x[i] + sigma * gauss() + blk[block[i]];
	}
	line_fit(x, y, block, -1, p);
	for (int i = 0; i < M; i++) {
		jac[2 * i] = 1;
		jac[2 * i + 1] = x[i];
		r[i] = p[0] + p[1] * x[i] - y[i];
	}
}

/* A Torrance-Sparrow result with independent errors of 1 % of each
 * value, then the given changes. */
static void ts_result(struct glint_fit_result *res)
{
	static const double p[8] = {
		0.3, 0.1, 0.03, 0.3, 0.27, 0.24, 0.04, 1.43
	};
	const struct glint_model *m = glint_model_find("torrance-sparrow");
	struct glint_uncertainty *u = &res->unc;

	memset(res, 0, sizeof(*res));
	res->model = m;
	res->interior = 10000; /* R = 56 px: footprint 0.0177 */
	u->n = 8;
	u->level = 0.95;
	for (int k = 0; k < 8; k++) {
		res->p[k] = p[k];
		res->se[k] = u->se[k] = u->se_textbook[k] = 0.01 * p[k];
		u->cov[k * 8 + k] = u->se[k] * u->se[k];
		u->corr[k * 8 + k] = 1;
		u->lo[k] = p[k] - 0.02 * p[k];
		u->hi[k] = p[k] + 0.02 * p[k];
	}
}

static int has_finding(json_t *unc, const char *what)
{
	size_t i;
	json_t *f;
	json_array_foreach(json_object_get(unc, "findings"), i,
			   f) if (strstr(json_string_value(f), what)) return 1;
	return 0;
}

static void findings(void)
{
	struct glint_fit_result res;
	json_t *unc, *params;

	CHECK(glint_model_find("torrance-sparrow") != NULL, "model");
	if (!glint_model_find("torrance-sparrow"))
		return;
	ts_result(&res);
	unc = glint_fit_uncertainty_json(&res);
	CHECK(json_array_size(json_object_get(unc, "findings")) == 0,
	      "a determined fit says nothing");
	CHECK(!glint_fit_needs_selection(&res), "no selection needed");
	json_decref(unc);

	/* specular.r and ior correlated -0.97 */
	ts_result(&res);
	double c = -0.97 * res.se[3] * res.se[7];
	res.unc.cov[3 * 8 + 7] = res.unc.cov[7 * 8 + 3] = c;
	res.unc.corr[3 * 8 + 7] = res.unc.corr[7 * 8 + 3] = -0.97;
	unc = glint_fit_uncertainty_json(&res);
	CHECK(has_finding(unc, "specular x F0(ior)"), "trade-off named");
	CHECK(glint_fit_needs_selection(&res),
	      "a trade-off asks for selection");
	json_t *comb = json_array_get(json_object_get(unc, "combinations"), 0);
	double f0 = glint_fresnel_dielectric(1, 1.43);
	CHECK(fabs(json_real_value(json_object_get(comb, "value")) - 0.3 * f0) <
		      1e-12,
	      "specular.r x F0 = %g",
	      json_real_value(json_object_get(comb, "value")));
	double g[8] = { 0, 0, 0, f0,
			0, 0, 0, 0.3 * 4 * 0.43 / (2.43 * 2.43 * 2.43) };
	double se = json_real_value(json_object_get(comb, "stderr"));
	CHECK(fabs(se - glint_uncertainty_delta(&res.unc, g)) < 1e-12 && se > 0,
	      "its error %g", se);
	json_decref(unc);

	/* roughness below the footprint, ior over its bounds */
	ts_result(&res);
	res.p[6] = 0.005;
	res.unc.lo[6] = 0.001;
	res.unc.hi[6] = 0.009;
	res.unc.lo[7] = 1;
	res.unc.hi[7] = 5;
	unc = glint_fit_uncertainty_json(&res);
	params = glint_fit_params_json(&res);
	CHECK(has_finding(unc, "upper bound"), "sub-footprint roughness");
	CHECK(has_finding(unc, "ior is not determined"), "ior undetermined");
	CHECK(glint_fit_needs_selection(&res), "undetermined: selection");
	json_t *rough = json_array_get(params, 6),
	       *ior = json_array_get(params, 7);
	CHECK(json_is_real(json_object_get(rough, "upper_bound")) &&
		      fabs(json_real_value(
				   json_object_get(rough, "upper_bound")) -
			   1 / sqrt(10000 / M_PI)) < 1e-9,
	      "upper bound at the footprint");
	CHECK(json_is_false(json_object_get(ior, "determined")),
	      "ior: determined false");
	json_decref(unc);
	json_decref(params);

	/* A joint fit of two photos: the footprint is the finer photo's
	 * (R = 56 px), not that of their pixels together. */
	res.nviews = 2;
	res.interior = 10000 + 2500;
	res.view[0].interior = 2500;
	res.view[1].interior = 10000;
	params = glint_fit_params_json(&res);
	rough = json_array_get(params, 6);
	CHECK(fabs(json_real_value(json_object_get(rough, "upper_bound")) -
		   1 / sqrt(10000 / M_PI)) < 1e-9,
	      "joint fit: upper bound %g at the finer photo's footprint %g",
	      json_real_value(json_object_get(rough, "upper_bound")),
	      1 / sqrt(10000 / M_PI));
	json_decref(params);

	/* An interval that reaches below the footprint (0.0177 here) from
	 * above it: the bound is its top; one wholly above it: a value. */
	res.nviews = 1;
	res.interior = 10000;
	res.unc.lo[6] = 0.01;
	res.unc.hi[6] = 0.03;
	params = glint_fit_params_json(&res);
	rough = json_array_get(params, 6);
	CHECK(fabs(json_real_value(json_object_get(rough, "upper_bound")) -
		   0.03) < 1e-12,
	      "straddling the footprint: upper bound %g, the interval's top",
	      json_real_value(json_object_get(rough, "upper_bound")));
	json_decref(params);
	res.unc.lo[6] = 0.02;
	params = glint_fit_params_json(&res);
	CHECK(!json_object_get(json_array_get(params, 6), "upper_bound"),
	      "an interval above the footprint: no bound");
	json_decref(params);
	unc = glint_fit_uncertainty_json(&res);
	CHECK(!has_finding(unc, "upper bound"), "and no finding");
	json_decref(unc);
}

static const double lo[2] = { -100, -100 }, hi[2] = { 100, 100 };

static void coverage(double sigma, double shared, double *glint,
		     double *textbook)
{
	static double jac[2 * M], r[M];
	static int block[M];
	int in = 0, in_tb = 0, trials = 2000;

	for (int t = 0; t < trials; t++) {
		double p[2];
		struct glint_uncertainty u;
		line(sigma, shared, jac, r, block, p);
		struct glint_unc_problem pr = { 2,  M,	  jac,	r,    block,
						NB, p,	  lo,	hi,   NULL,
						0,  NULL, NULL, 0.95, NULL,
						0,  NULL };
		if (glint_uncertainty_compute(&pr, &u) < 0) {
			CHECK(0, "compute failed");
			return;
		}
		in += fabs(p[1] - 2) <= u.t[1] * u.se[1] && u.lo[1] <= 2 &&
		      u.hi[1] >= 2;
		in_tb += fabs(p[1] - 2) <= 1.96 * u.se_textbook[1];
	}
	*glint = (double)in / trials;
	*textbook = (double)in_tb / trials;
}

/* The regions' jackknife (uncertainty.h, "model error"). */
static void regions(void)
{
	enum { G = 10 };
	static double jac[2 * M], r[M], x[M], y[M];
	static int block[M], region[M];
	struct glint_uncertainty u;
	double p[2], q[G][2], mean[2] = { 0, 0 };

	/* A line through a parabola: the linearised jackknife is exact for
	 * a linear model, so it must equal refits without each region. */
	for (int i = 0; i < M; i++) {
		x[i] = (double)i / M;
		y[i] = 1 + 2 * x[i] + 3 * (x[i] - 0.5) * (x[i] - 0.5) +
		       0.01 * gauss();
		region[i] = i * G / M;
		block[i] = i * NB / M;
	}
	line_fit(x, y, region, -1, p);
	for (int i = 0; i < M; i++) {
		jac[2 * i] = 1;
		jac[2 * i + 1] = x[i];
		r[i] = p[0] + p[1] * x[i] - y[i];
	}
	for (int g = 0; g < G; g++) {
		line_fit(x, y, region, g, q[g]);
		mean[0] += q[g][0] / G;
		mean[1] += q[g][1] / G;
	}
	double v[4] = { 0, 0, 0, 0 };
	for (int g = 0; g < G; g++)
		for (int a = 0; a < 2; a++)
			for (int b = 0; b < 2; b++)
				v[a * 2 + b] += (G - 1.0) / G *
						(q[g][a] - mean[a]) *
						(q[g][b] - mean[b]);
	struct glint_unc_problem pr = { 2,    M,    jac,    r,	  block, NB,
					p,    lo,   hi,	    NULL, 0,	 NULL,
					NULL, 0.95, region, G,	  NULL };
	CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
	CHECK(u.nregions == G, "%d regions", u.nregions);
	for (int k = 0; k < 4; k++)
		CHECK(fabs(u.cov_regions[k] - v[k]) <= 1e-9 * fabs(v[3]),
		      "jackknife element %d: %.9g, refits %.9g", k,
		      u.cov_regions[k], v[k]);
	CHECK(u.cov_regions[3] > 4 * u.cov_textbook[3],
	      "the misfit widens the slope's variance: %g vs textbook %g",
	      u.cov_regions[3], u.cov_textbook[3]);
	CHECK(u.se[1] * u.se[1] >= u.cov_regions[3] * (1 - 1e-9) &&
		      u.dof[1] == G - 1,
	      "it enters the interval: se^2 %g, dof %g", u.se[1] * u.se[1],
	      u.dof[1]);
	pr.nregions = 2;
	CHECK(glint_uncertainty_compute(&pr, &u) == 0 && u.nregions == 0 &&
		      u.cov_regions[3] == 0,
	      "fewer than 3 regions: no jackknife");

	/* A true line with independent noise: the jackknife estimates the
	 * noise's variance, on average a little above the textbook one (as
	 * a jackknife does: dropping an end region, of high leverage, moves
	 * the slope more than its share). */
	double ratio = 0;
	int trials = 500;
	for (int t = 0; t < trials; t++) {
		line(0.1, 0, jac, r, block, p);
		pr.nregions = G;
		CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
		ratio += u.cov_regions[3] / u.cov_textbook[3] / trials;
	}
	printf("true line: jackknife / textbook variance of the slope %.3f "
	       "on average\n",
	       ratio);
	CHECK(ratio > 0.9 && ratio < 1.5, "jackknife/textbook %.3f", ratio);
}

/* The acceptance rule and its verdicts (fit/result.c). */
static void acceptance(void)
{
	struct glint_fit_result res;
	struct glint_fit_verdict v;

	memset(&res, 0, sizeof(res));
	res.rmse = 0.02;
	res.rel_rmse = 0.2;
	res.backdrop_rel_rmse = 0.9;
	res.flat_rel_rmse = 0.5;
	res.noise_rmse = 0.016;
	CHECK(glint_fit_judge(&res, 0, &v) && v.limit == 0.5,
	      "better than both baselines: accepted (limit %g)", v.limit);
	CHECK_MSG(v.verdict, "fits to the noise: the residual is 1.25 times");
	res.noise_rmse = 0.004;
	glint_fit_judge(&res, 0, &v);
	CHECK_MSG(v.verdict, "misfit: the residual is 5.0 times");
	res.noise_rmse = NAN;
	glint_fit_judge(&res, 0, &v);
	CHECK_MSG(v.verdict, "no noise model");
	/* A near-mirror: a large relative RMSE, far below the flat disc. */
	res.rel_rmse = 1.3;
	res.backdrop_rel_rmse = 4;
	res.flat_rel_rmse = 8;
	CHECK(glint_fit_judge(&res, 0, &v), "a near-mirror is accepted");
	CHECK(!glint_fit_judge(&res, 1.0, &v), "--accept-rmse 1 refuses it");
	CHECK_MSG(v.verdict, "above --accept-rmse 1");
	res.backdrop_rel_rmse = 1.1;
	CHECK(!glint_fit_judge(&res, 0, &v), "the backdrop explains it");
	CHECK_MSG(v.verdict, "shows the backdrop, not a sphere");
	res.backdrop_rel_rmse = NAN; /* transparent: no backdrop check */
	res.flat_rel_rmse = 1.2;
	CHECK(!glint_fit_judge(&res, 0, &v), "a flat disc explains it");
	CHECK_MSG(v.verdict, "does not show this scene's sphere");
	CHECK_MSG(v.rule, "than a flat disc");
	json_t *j = glint_fit_verdict_json(&res, &v);
	CHECK(j && json_is_false(json_object_get(j, "accepted")) &&
		      json_is_null(
			      json_object_get(j, "backdrop_relative_rmse")),
	      "acceptance JSON");
	json_decref(j);
}

/*
 * The sampling lean (uncertainty.h) where it is known: y = a x exactly,
 * the model's regressor seen through K = 3 noisy sample sets x + e_s
 * (errors in variables), a fitted where the first set's Jacobian is
 * orthogonal to the mean residual (as fit.c's polish stops).  The
 * slope comes out low by about a sigma^2 / K / (x^2 + sigma^2 / K)
 * (regression dilution); the estimated lean must match that on
 * average and, taken off, leave a within its standard error.
 */
static void lean(void)
{
	enum { K = 3, REPS = 200 };
	static double x[K * M], jac[M], r[M], draws[K * M], jr[NB];
	static int block[M];
	const double a = 2, sigma = 0.3, lo1 = -100, hi1 = 100;
	double sum_err = 0, sum_lean = 0, sum_fixed = 0, sum_fixed2 = 0;
	double sum_se2 = 0, sum_lean2 = 0;

	for (int rep = 0; rep < REPS; rep++) {
		double xt[M], sxy = 0, sxx = 0, ahat;
		for (int i = 0; i < M; i++) {
			xt[i] = 0.5 + (i % 97) / 96.0;
			block[i] = i * NB / M;
			for (int k = 0; k < K; k++)
				x[k * M + i] = xt[i] + sigma * gauss();
		}
		for (int i = 0; i < M; i++) {
			double xm = 0;
			for (int k = 0; k < K; k++)
				xm += x[k * M + i] / K;
			sxy += x[i] * a * xt[i];
			sxx += x[i] * xm;
		}
		ahat = sxy / sxx;
		memset(jr, 0, sizeof(jr));
		for (int i = 0; i < M; i++) {
			double xm = 0;
			for (int k = 0; k < K; k++)
				xm += x[k * M + i] / K;
			r[i] = ahat * xm - a * xt[i];
			jac[i] = x[i];
			for (int k = 0; k < K; k++) {
				draws[k * M + i] =
					ahat * x[k * M + i] - a * xt[i];
				jr[block[i]] += (draws[k * M + i] - r[i]) *
						x[k * M + i];
			}
		}
		struct glint_unc_problem pr = {
			.n = 1,
			.m = M,
			.jac = jac,
			.r = r,
			.block = block,
			.nblocks = NB,
			.p = &ahat,
			.lo = &lo1,
			.hi = &hi1,
			.draws = draws,
			.ndraws = K,
			.draws_jr = jr,
			.level = 0.95,
		};
		struct glint_uncertainty u;
		CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
		sum_err += ahat - a;
		sum_lean += u.lean[0];
		sum_lean2 += u.lean[0] * u.lean[0];
		sum_fixed += ahat - u.lean[0] - a;
		sum_fixed2 += (ahat - u.lean[0] - a) * (ahat - u.lean[0] - a);
		sum_se2 += u.lean_se[0] * u.lean_se[0];
	}
	double ex2 = 0;
	for (int i = 0; i < M; i++) {
		double xi = 0.5 + (i % 97) / 96.0;
		ex2 += xi * xi / M;
	}
	double expect = -a * sigma * sigma / K / (ex2 + sigma * sigma / K);
	double err = sum_err / REPS, ln = sum_lean / REPS,
	       fixed = sum_fixed / REPS;
	double sd = sqrt(sum_fixed2 / REPS - fixed * fixed);
	printf("  slope's lean %.4f on average (expected %.4f), estimated "
	       "%.4f; taken off: %.4f +- %.4f\n",
	       err, expect, ln, fixed, sd / sqrt(REPS));
	CHECK(fabs(err - expect) < 0.15 * fabs(expect), "lean %.4f vs %.4f",
	      err, expect);
	CHECK(fabs(ln - err) < 0.15 * fabs(expect),
	      "estimated lean %.4f, actual %.4f", ln, err);
	/* First order: the rest is a lean's share of the lean (8 % here). */
	CHECK(fabs(fixed) < 0.15 * fabs(expect),
	      "taken off, the slope is off by %.4f (+- %.4f)", fixed,
	      sd / sqrt(REPS));
	/* The estimate's standard error against its spread over the
	 * repetitions: the blocks' spread sees the covariance's noise, not
	 * that of the slope and A it is scaled by (here 20 % below). */
	double lsd = sqrt(sum_lean2 / REPS - ln * ln),
	       lse = sqrt(sum_se2 / REPS);
	printf("  the estimate's spread %.4f, its standard error %.4f\n", lsd,
	       lse);
	CHECK(lse > 0.7 * lsd && lse < 2 * lsd,
	      "standard error %.4f, spread %.4f", lse, lsd);
}

/* fit_systematic() per map: the fast render's own accuracy under a map
 * that is the light; the probe's blur added to roughness, growing with
 * its pixel's angle; 4.1 % where the probe does not say; under a probe
 * the diffuse albedos a share of the specular's. */
static void systematic_by_map(void)
{
	static const double p[8] = {
		0.3, 0.1, 0.03, 0.3, 0.27, 0.24, 0.04, 1.43
	};
	const struct glint_model *m = glint_model_find("torrance-sparrow");
	double given[8], rig[8], coarse[8], unknown[8];
	fit_systematic(m, p, 0, 0, given, NULL);
	fit_systematic(m, p, 1.69, 0, rig, NULL);
	fit_systematic(m, p, 2.70, 0, coarse, NULL);
	fit_systematic(m, p, -1, 0, unknown, NULL);
	CHECK(fabs(given[6] / p[6] - 0.013) < 1e-9,
	      "roughness under the true map: %g %%", 100 * given[6] / p[6]);
	CHECK(fabs(rig[6] / p[6] - 0.0273) < 0.0005,
	      "roughness at 1.69 degrees a pixel: %g %%", 100 * rig[6] / p[6]);
	/* at 2.70 degrees the floor in m^2 (systematic_coarse()) passes the
	 * relative 6.27 % on a lobe this narrow */
	double pix = 2.70 * M_PI / 180;
	CHECK(fabs(coarse[6] -
		   fmax(0.0627 * p[6], hypot(p[6], 8 * pix * pix) - p[6])) <
		      0.0005 * p[6],
	      "roughness at 2.70 degrees a pixel: %g %%",
	      100 * coarse[6] / p[6]);
	CHECK(fabs(unknown[6] / p[6] - hypot(0.013, 0.041)) < 1e-9,
	      "roughness from a probe of unknown resolution: %g %%",
	      100 * unknown[6] / p[6]);
	CHECK(fabs(given[3] - hypot(0.005 * p[3], 0.0002)) < 1e-12 &&
		      fabs(rig[3] - hypot(0.007 * p[3], 0.0002)) < 1e-12,
	      "specular: %g under the map, %g from a probe", given[3], rig[3]);
	/* under a probe the diffuse albedo takes up 0.25 % of the specular
	 * lobe's mean albedo (0.27 here) */
	double cross = 0.0025 * (p[3] + p[4] + p[5]) / 3;
	CHECK(fabs(given[0] - hypot(0.001 * p[0], 0.0002)) < 1e-12 &&
		      fabs(rig[0] - hypot(hypot(0.001 * p[0], 0.0002), cross)) <
			      1e-12 &&
		      rig[0] == coarse[0],
	      "diffuse: %g under the map, %g from a probe", given[0], rig[0]);
	CHECK(fabs(given[7] - 0.002 * p[7]) < 1e-12 && given[7] == rig[7],
	      "ior: %g, %g", given[7], rig[7]);
}

/* fit_systematic() on coarse photos: a roughness that collapsed under a
 * probe 48 px in radius (3.37 degrees a pixel) keeps an absolute floor,
 * m^2 known to (8 p^2)^2; the specular albedos and ior grow as R^-4 on a
 * sphere 39 px in radius, together along the specular/ior ridge, and a
 * sphere 81 px in radius (the shipped rig's) is all but untouched. */
static void systematic_coarse(void)
{
	double p[8] = { 0.3, 0.1, 0.03, 0.3, 0.27, 0.24, 0.001, 1.43 };
	const struct glint_model *m = glint_model_find("torrance-sparrow");
	double fine[8], coarse[8], small[8], rig[8], big[8];
	double pix = 3.37 * M_PI / 180;

	fit_systematic(m, p, 1.69, 0, fine, NULL);
	fit_systematic(m, p, 3.37, 0, coarse, NULL);
	CHECK(fabs(coarse[6] - (hypot(p[6], 8 * pix * pix) - p[6])) < 1e-12 &&
		      coarse[6] > 0.025 && fine[6] < 0.4 * coarse[6],
	      "collapsed roughness %g: %g at 3.37 degrees a pixel, %g at "
	      "1.69",
	      p[6], coarse[6], fine[6]);
	p[6] = 0.2; /* a broad lobe keeps its relative term */
	fit_systematic(m, p, 3.37, 0, coarse, NULL);
	CHECK(fabs(coarse[6] / p[6] - hypot(0.013, 0.024 * 4)) < 0.002,
	      "roughness 0.2 at 3.37 degrees a pixel: %g %%",
	      100 * coarse[6] / p[6]);
	fit_systematic(m, p, 1.69, 39, small, NULL);
	fit_systematic(m, p, 1.69, 81, rig, NULL);
	fit_systematic(m, p, 1.69, 0, big, NULL);
	double rel = 2.2e5 / pow(39, 4);
	CHECK(fabs(small[3] - hypot(hypot(0.007, rel) * p[3], 0.0002)) <
			      1e-12 &&
		      small[3] > 10 * big[3] && rig[3] < 1.3 * big[3],
	      "specular: %g on a sphere 39 px in radius, %g at 81 px, %g "
	      "large",
	      small[3], rig[3], big[3]);
	CHECK(fabs(small[7] -
		   hypot(0.002 * p[7], rel * (p[7] * p[7] - 1) / 4)) < 1e-12 &&
		      rig[7] < 1.3 * big[7] && small[0] == big[0],
	      "ior %g at 39 px, %g at 81 px; diffuse %g, %g", small[7], rig[7],
	      small[0], big[0]);

	/* Split, the small sphere's term is one source along the ridge:
	 * specular x F0(ior) stays where it was, to first order. */
	double own[8], shared[8];
	fit_systematic(m, p, 1.69, 39, own, shared);
	double f0 = glint_fresnel_dielectric(1, p[7]),
	       moved = (p[3] + shared[3]) *
		       glint_fresnel_dielectric(1, p[7] + shared[7]);
	CHECK(fabs(shared[3] - rel * p[3]) < 1e-12 && shared[7] < 0 &&
		      fabs(own[3] - big[3]) < 1e-12 &&
		      fabs(own[7] - big[7]) < 1e-12 && shared[0] == 0 &&
		      shared[6] == 0,
	      "shared: specular %g, ior %g; own specular %g, ior %g", shared[3],
	      shared[7], own[3], own[7]);
	CHECK(fabs(moved / (p[3] * f0) - 1) < 0.1 * rel,
	      "specular x F0 along the shared source: %+.4f %% (the source "
	      "%.2f %%)",
	      100 * (moved / (p[3] * f0) - 1), 100 * rel);
}

/* fit_samples_factor(): when the fit raises its samples and by how much.
 * Each measure alone raises them; the lean's (aluminium bronze under the
 * overcast class: 1.12 of the noise at 8 + 8) to the power of two that
 * brings it under 0.5; the cap holds. */
static void samples_factor(void)
{
	CHECK(fit_samples_factor(0.9, 0.2, 0.4, 8, 64) == 1,
	      "every measure under its limit: %d",
	      fit_samples_factor(0.9, 0.2, 0.4, 8, 64));
	CHECK(fit_samples_factor(0.97, 0.05, 1.12, 8, 64) == 4,
	      "bronze's lean 1.12: %d",
	      fit_samples_factor(0.97, 0.05, 1.12, 8, 64));
	CHECK(fit_samples_factor(0.1, 0.01, 0.6, 8, 64) == 2,
	      "a lean of 0.6 alone: %d",
	      fit_samples_factor(0.1, 0.01, 0.6, 8, 64));
	CHECK(fit_samples_factor(3.0, 0.01, 0.1, 8, 64) == 4 &&
		      fit_samples_factor(0.1, 1.5, 0.1, 8, 64) == 8,
	      "per parameter 3: %d; per value 1.5: %d",
	      fit_samples_factor(3.0, 0.01, 0.1, 8, 64),
	      fit_samples_factor(0.1, 1.5, 0.1, 8, 64));
	CHECK(fit_samples_factor(0.1, 0.01, 40, 8, 64) == 8 &&
		      fit_samples_factor(0.1, 0.01, 40, 64, 64) == 1 &&
		      fit_samples_factor(NAN, NAN, NAN, 8, 64) == 1,
	      "cap: %d from 8, %d from 64; NaN: %d",
	      fit_samples_factor(0.1, 0.01, 40, 8, 64),
	      fit_samples_factor(0.1, 0.01, 40, 64, 64),
	      fit_samples_factor(NAN, NAN, NAN, 8, 64));
}

int main(void)
{
	RUN(acceptance);
	RUN(systematic_by_map);
	RUN(systematic_coarse);
	RUN(lean);
	RUN(samples_factor);
	static double jac[2 * M], r[M], draws[4 * M];
	static int block[M];
	double p[2], c, ctb;
	struct glint_uncertainty u;

	/* The textbook covariance of a line. */
	line(0.1, 0, jac, r, block, p);
	struct glint_unc_problem pr = { 2,    M,    jac,  r,	block, NB,
					p,    lo,   hi,	  NULL, 0,     NULL,
					NULL, 0.95, NULL, 0,	NULL };
	CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
	double sx = 0, sxx = 0, s2 = 0;
	for (int i = 0; i < M; i++) {
		sx += jac[2 * i + 1];
		sxx += jac[2 * i + 1] * jac[2 * i + 1];
		s2 += r[i] * r[i] / (M - 2);
	}
	double vb = s2 * M / (M * sxx - sx * sx);
	CHECK(fabs(u.cov_textbook[3] / vb - 1) < 1e-9,
	      "slope variance %.6g, expected %.6g", u.cov_textbook[3], vb);
	CHECK(fabs(u.chi2_dof / s2 - 1) < 1e-9, "chi2/dof %g vs %g", u.chi2_dof,
	      s2);
	CHECK(u.nblocks == NB, "%d blocks", u.nblocks);
	CHECK(u.se[1] >= u.se_textbook[1], "never below the textbook");

	coverage(0.1, 0, &c, &ctb);
	printf("independent noise: coverage %.3f (textbook %.3f)\n", c, ctb);
	CHECK(c >= 0.93 && c <= 0.97, "coverage %.3f", c);
	CHECK(ctb >= 0.93 && ctb <= 0.97, "textbook coverage %.3f", ctb);
	coverage(0.02, 0.05, &c, &ctb);
	printf("block-correlated noise: coverage %.3f (textbook %.3f)\n", c,
	       ctb);
	CHECK(c >= 0.90 && c <= 0.98, "coverage %.3f", c);
	CHECK(ctb < 0.6, "textbook coverage %.3f: expected far too low", ctb);

	/* Sample sets: four residual draws, r +- d x on the slope's column
	 * (each a Gauss-Newton step of -+ d on the slope). */
	line(0.1, 0, jac, r, block, p);
	const double d = 0.05, sign[4] = { 1, -1, 1, -1 };
	for (int k = 0; k < 4; k++)
		for (int i = 0; i < M; i++)
			draws[k * M + i] = r[i] + sign[k] * d * jac[2 * i + 1];
	struct glint_unc_problem pm = { 2,    M,    jac,  r,	 block, NB,
					p,    lo,   hi,	  draws, 4,	NULL,
					NULL, 0.95, NULL, 0,	 NULL };
	CHECK(glint_uncertainty_compute(&pm, &u) == 0, "compute");
	/* steps -+d: sample variance 4/3 d^2, over K = 4 */
	double vmc = 4.0 / 3 * d * d / 4;
	CHECK(fabs(u.cov_mc[3] / vmc - 1) < 1e-6, "MC variance %.6g vs %.6g",
	      u.cov_mc[3], vmc);
	CHECK(fabs(u.cov_mc[0]) < 1e-12, "MC variance of the intercept %g",
	      u.cov_mc[0]);
	CHECK(u.se[1] * u.se[1] >= vmc, "the MC part enters");

	/* A systematic term adds to the variance. */
	double sys[2] = { 0, 0.03 }, se_before = u.se[1];
	pm.sys = sys;
	CHECK(glint_uncertainty_compute(&pm, &u) == 0, "compute");
	CHECK(fabs(u.se[1] * u.se[1] - se_before * se_before - 0.03 * 0.03) <
		      1e-12,
	      "systematic: se %g from %g", u.se[1], se_before);
	pm.sys = NULL;

	/* A shared source adds its whole outer product: the variances as a
	 * systematic term does, and the covariance a ridge needs. */
	double cov0[4], shared[2] = { 0.02, -0.03 };
	CHECK(glint_uncertainty_compute(&pm, &u) == 0, "compute");
	memcpy(cov0, u.cov, sizeof(cov0));
	double corr0 = u.corr[1];
	pm.sys_shared = shared;
	CHECK(glint_uncertainty_compute(&pm, &u) == 0, "compute");
	CHECK(fabs(u.cov[0] - cov0[0] - 0.02 * 0.02) < 1e-12 &&
		      fabs(u.cov[3] - cov0[3] - 0.03 * 0.03) < 1e-12 &&
		      fabs(u.cov[1] - cov0[1] + 0.02 * 0.03) < 1e-12 &&
		      u.cov[1] == u.cov[2] && fabs(u.sys[1] - 0.03) < 1e-12,
	      "shared: cov %g %g %g from %g %g %g", u.cov[0], u.cov[1],
	      u.cov[3], cov0[0], cov0[1], cov0[3]);
	CHECK(u.corr[1] < 0 &&
		      fabs(u.corr[1] - u.cov[1] / (u.se[0] * u.se[1])) < 1e-12,
	      "shared: corr %g", u.corr[1]);
	CHECK(fabs(glint_uncertainty_corr_without_shared(&u, 0, 1) - corr0) <
			      1e-9 &&
		      fabs(u.corr[1] - corr0) > 0.05,
	      "without the shared source: corr %g, %g without it, %g with",
	      glint_uncertainty_corr_without_shared(&u, 0, 1), corr0,
	      u.corr[1]);
	pm.sys_shared = NULL;

	/* A parameter the data cannot see. */
	for (int i = 0; i < M; i++)
		jac[2 * i + 1] = 0;
	CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
	CHECK(isinf(u.se[1]) && u.lo[1] == lo[1] && u.hi[1] == hi[1],
	      "unseen: se %g, interval %g .. %g", u.se[1], u.lo[1], u.hi[1]);
	CHECK(isfinite(u.se[0]), "the intercept is still seen: %g", u.se[0]);

	/* Delta method: f = a b, grad (b, a). */
	line(0.1, 0, jac, r, block, p);
	CHECK(glint_uncertainty_compute(&pr, &u) == 0, "compute");
	double g[2] = { p[1], p[0] };
	double v = p[1] * p[1] * u.cov[0] + 2 * p[0] * p[1] * u.cov[1] +
		   p[0] * p[0] * u.cov[3];
	CHECK(fabs(glint_uncertainty_delta(&u, g) / sqrt(v) - 1) < 1e-12,
	      "delta method");

	findings();
	RUN(regions);

	/* Bad sizes. */
	struct glint_unc_problem bad = pr;
	bad.m = 1;
	CHECK(glint_uncertainty_compute(&bad, &u) < 0, "m <= n refused");
	return test_result();
}
