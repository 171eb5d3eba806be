/* SPDX-License-Identifier: MIT */
/*
 * Coverage of the fit's intervals: do the nominal 95 % intervals contain
 * the truth 95 % of the time?  Photos from the independent reference
 * renderer (sim/reference.c), Table-1 materials under real maps, at random
 * map rotations and sphere placements, noise-free (the reference's own
 * Monte Carlo noise only) and through the simulated sensor at two light
 * levels; each photo fitted with glint's defaults and the sensor's weights.
 * Counted per parameter group (diffuse albedos, specular albedos,
 * roughness, ior) and noise level, for glint's intervals and, beside them,
 * for the textbook ones (s^2 (J^T J)^-1, what glint reported before).
 * Parameters the photo does not determine (an interval over the whole
 * bound range, or no interval) are counted apart: their coverage is
 * trivial; so is roughness glint reports as an upper bound (below the
 * pixel footprint), with whether the bound holds.
 *   test_coverage slice|quick|full [MAP...]
 * slice: 2 materials (yellow plastic, teflon) x 2 placements x 3 noise
 * levels (12 fits) per map, the sim suite's share;
 * quick: 4 materials x 2 placements x 3 noise levels (24 fits) per map;
 * full: all 11 opaque Table-1 materials x 3 placements x 3 levels per map.
 * Prints the table and, per group, whether the 90-98 % target is met;
 * asserts what is reached: no group below the textbook intervals, and
 * floors (0.7; roughness 0.5) under which a change is a regression.
 * For the studies behind docs/fitting.md: COVERAGE_ONLY=MATERIAL fits
 * that material's cases only, COVERAGE_SAMPLES=N fits with N + N samples
 * per set, COVERAGE_SETS=K on K sample sets (1: one fixed set, no
 * polish), COVERAGE_SPP=N with N primary samples per pixel,
 * COVERAGE_REF_SAMPLES=N photos with N samples per technique (256),
 * COVERAGE_REF_NOISE=R each pixel rendered again until its relative
 * standard error is under R (0.01; 0: one round),
 * COVERAGE_VERBOSE=1 prints each fit's value and error parts,
 * COVERAGE_NO_MODEL_ERROR=1 leaves out the model-error jackknife (and with
 * it the model discrepancy), COVERAGE_NO_DISCREPANCY=1 the discrepancy alone,
 * COVERAGE_POLISH=N gives the polish on the sample sets N iterations,
 * COVERAGE_DUMP=FILE appends one JSON line a fitted value (the truth, the
 * fit, its standard error and the parts of it, the interval) to FILE, for
 * studies of the error's parts that need no refit (bench/coverage_terms.py).
 */
#include "test.h"

#include "core/error.h"
#include "fit/fit.h"
#include "fit/internal.h"
#include "fit/job.h"
#include "sim/reference.h"
#include "sim/sensor.h"
#include "sim_scene.h"

#define NGROUP 4
#define NLEVEL 3

static const char *const group_names[NGROUP] = { "diffuse", "specular",
						 "roughness", "ior" };
static const char *const level_names[NLEVEL] = { "noise-free", "10k e-",
						 "1k e-" };

struct tally {
	int n, in, in_textbook, in_stat, undetermined;
	int bounded, bound_holds; /* roughness reported as an upper bound */
	double relerr[512];	  /* |fit - truth| / truth of each value */
	double z[512];		  /* |fit - truth| / standard error */
};

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static int group_of(int k)
{
	return k < 3 ? 0 : k < 6 ? 1 : k == 6 ? 2 : 3;
}

static uint64_t rng_state = 0x853c49e6748fea9bull;

static double urand(void)
{
	rng_state ^= rng_state << 13;
	rng_state ^= rng_state >> 7;
	rng_state ^= rng_state << 17;
	return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* The photo through the sensor at `full_well` electrons for the brightest
 * pixel (0: noise-free), and its weights (NULL: the fit's default). */
static int expose(const struct glint_image *clean, double full_well,
		  uint64_t seed, struct glint_image **photo,
		  struct glint_image **weight)
{
	struct glint_sensor s;
	int w = clean->width, h = clean->height;
	double peak = 0;

	*photo = glint_image_new(w, h);
	*weight = NULL;
	if (!*photo)
		return -ENOMEM;
	if (full_well <= 0) {
		memcpy((*photo)->data, clean->data,
		       sizeof(float) * 3 * (size_t)w * h);
		return 0;
	}
	for (size_t i = 0; i < 3 * (size_t)w * h; i++)
		peak = fmax(peak, clean->data[i]);
	glint_sensor_default(&s);
	s.full_well_e = full_well;
	s.gain = 4095.0 / full_well;
	s.seed = seed;
	s.exposure_s = glint_sensor_exposure_for(&s, peak, 0.9);
	struct glint_image *dn = glint_image_new(w, h);
	*weight = glint_image_new(w, h);
	int ret = dn && *weight ? glint_sensor_capture(&s, clean, dn) : -ENOMEM;
	if (ret == 0)
		ret = glint_sensor_to_radiance(&s, dn, *photo, *weight);
	glint_image_free(dn);
	return ret;
}

/* COVERAGE_DUMP: one line a value, what sizes its interval: the truth,
 * the fit, its standard error and interval, the parts of it (the blocks',
 * the sample sets', the systematic in all and the fast render's terms in
 * it: the fixed one, fit_systematic(), and the gain term,
 * fit/render_gain.c, beside that term at a factor of 1),
 * null where not finite. */
static void dump_num(FILE *f, const char *name, double x)
{
	if (isfinite(x))
		fprintf(f, ", \"%s\": %.9g", name, x);
	else
		fprintf(f, ", \"%s\": null", name);
}

static void dump(const char *material, const char *map, const char *rot, int lv,
		 const struct glint_model *m, const double *truth,
		 const struct glint_fit_opts *o,
		 const struct glint_fit_result *res)
{
	const char *path = getenv("COVERAGE_DUMP");
	FILE *f = path ? fopen(path, "a") : NULL;
	double fixed[GLINT_MAX_PARAMS];
	int n = res->unc.n;

	if (!f) {
		if (path)
			fprintf(stderr, "COVERAGE_DUMP %s: %s\n", path,
				strerror(errno));
		return;
	}
	/* the study's camera does not blur: no small sphere's term
	 * (fit_blurred_sphere_px()) */
	fit_systematic(m, res->p, o->map_pixel_deg, 0, fixed, NULL);
	for (int k = 0; k < m->nparams; k++) {
		double render = hypot(fixed[k], res->render_gain_stderr[k]);
		double bound = k == m->lobes->roughness_param
				       ? glint_fit_roughness_bound(res)
				       : NAN;
		fprintf(f,
			"{\"material\": \"%s\", \"map\": \"%s\", "
			"\"rot\": %s, \"level\": \"%s\", \"param\": \"%s\", "
			"\"group\": \"%s\", \"k\": %d",
			material, strrchr(map, '/') + 1, rot, level_names[lv],
			m->params[k].name, group_names[group_of(k)], k);
		dump_num(f, "truth", truth[k]);
		dump_num(f, "fit", res->p[k]);
		dump_num(f, "se", res->se[k]);
		dump_num(f, "sys", res->unc.sys[k]);
		dump_num(f, "sys_render", render);
		dump_num(f, "sys_fixed", fixed[k]);
		dump_num(f, "gain_term", res->render_gain_stderr[k]);
		dump_num(f, "blocks", sqrt(res->unc.cov_blocks[k * n + k]));
		dump_num(f, "mc", sqrt(res->unc.cov_mc[k * n + k]));
		dump_num(f, "textbook", res->unc.se_textbook[k]);
		dump_num(f, "gain_unit", res->render_gain[k]);
		dump_num(f, "t", res->unc.t[k]);
		dump_num(f, "lo", res->unc.lo[k]);
		dump_num(f, "hi", res->unc.hi[k]);
		dump_num(f, "bound", bound);
		dump_num(f, "range", m->params[k].hi - m->params[k].lo);
		fprintf(f, ", \"truths\": [");
		for (int j = 0; j < m->nparams; j++)
			fprintf(f, "%s%.9g", j ? ", " : "", truth[j]);
		fprintf(f, "]}\n");
	}
	fclose(f);
}

static void one_case(const char *map, const char *material, int placement,
		     struct tally t[NLEVEL][NGROUP])
{
	static const double wells[NLEVEL] = { 0, 10000, 1000 };
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	double rot = 360 * urand();
	char rots[32];

	snprintf(rots, sizeof(rots), "%.1f", rot);

	sim_scene_192(&sc, map, rot);
	if (getenv("COVERAGE_SPP"))
		sc.spp = atoi(getenv("COVERAGE_SPP"));
	/* Anywhere in the frame's middle: +- 2 cm (20 px) each way. */
	sc.sphere_centre.x = 0.04 * (urand() - 0.5);
	sc.sphere_centre.y = 0.04 * (urand() - 0.5);
	/* COVERAGE_ONLY=MATERIAL: that material's cases only (the random
	 * placements stay those of the whole run). */
	if (getenv("COVERAGE_ONLY") &&
	    strcmp(getenv("COVERAGE_ONLY"), material))
		return;
	CHECK(glint_material_load(GLINT_DATA_DIR "/paper-table1.json", material,
				  &m, truth) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return;
	struct glint_image *clean =
		glint_image_new(sc.cam.width, sc.cam.height);
	struct glint_reference_opts ro;
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	/* 256 samples per technique: at 64 the photo's own Monte Carlo
	 * noise (heavy-tailed in the highlight) moved yellow plastic's
	 * roughness from 0.040 to 0.045 at one placement (docs/fitting.md). */
	ro.samples = getenv("COVERAGE_REF_SAMPLES")
			     ? atoi(getenv("COVERAGE_REF_SAMPLES"))
			     : 256;
	ro.seed = (uint32_t)(1000 * placement + 17);
	long rounds = 0;
	ro.rounds = &rounds;
	/* and each pixel until its relative standard error is under 1 %:
	 * at 256 samples alone the highlight's heavy tail moved yellow
	 * plastic's roughness by -4 to +4 % noise-free (0.3 % and -0.8 %
	 * adaptive), which sized the systematic term rather than the fast
	 * render's own accuracy */
	ro.rel_noise = getenv("COVERAGE_REF_NOISE")
			       ? atof(getenv("COVERAGE_REF_NOISE"))
			       : 0.01;
	CHECK(clean && glint_reference_render(&r.scene, r.env, m, truth, &ro,
					      clean) == 0,
	      "%s", glint_error_msg());
	if (getenv("COVERAGE_VERBOSE"))
		printf("    reference: %.2f rounds of %d samples a pixel\n",
		       (double)rounds / ((double)sc.cam.width * sc.cam.height),
		       ro.spp);
	for (int lv = 0; lv < NLEVEL && !test_failures; lv++) {
		struct glint_image *photo, *weight;
		struct glint_fit_opts o;
		struct glint_fit_result res;
		CHECK(expose(clean, wells[lv], 7 + placement * 31 + lv, &photo,
			     &weight) == 0,
		      "sensor");
		glint_fit_default_opts(&o);
		if (getenv("COVERAGE_SETS"))
			o.mc_draws = atoi(getenv("COVERAGE_SETS")) - 1;
		if (getenv("COVERAGE_START_TRUTH"))
			o.start = truth;
		o.no_model_error = getenv("COVERAGE_NO_MODEL_ERROR") != NULL;
		o.no_discrepancy = getenv("COVERAGE_NO_DISCREPANCY") != NULL;
		if (getenv("COVERAGE_POLISH"))
			o.polish_iter = atoi(getenv("COVERAGE_POLISH"));
		if (getenv("COVERAGE_SAMPLES"))
			o.light_samples = o.lobe_samples =
				atoi(getenv("COVERAGE_SAMPLES"));
		CHECK(glint_fit(&r, m, photo, weight, &o, &res) == 0,
		      "%s %s %s: %s", material, map, level_names[lv],
		      glint_error_msg());
		struct glint_fit_result at_truth = { 0 };
		if (getenv("COVERAGE_VERBOSE")) {
			/* The truth on the fit's own objective. */
			o.weights_at = res.p;
			CHECK(glint_fit_evaluate(&r, m, photo, weight, &o,
						 truth, &at_truth) == 0,
			      "%s", glint_error_msg());
			for (int q = 0; getenv("COVERAGE_LINE") && q <= 10;
			     q++) {
				double pq[GLINT_MAX_PARAMS];
				struct glint_fit_result e = { 0 };
				for (int k = 0; k < m->nparams; k++)
					pq[k] = res.p[k] +
						q / 10.0 *
							(truth[k] - res.p[k]);
				glint_fit_evaluate(&r, m, photo, weight, &o, pq,
						   &e);
				printf("    line %.1f rough %.4f cost %.6g\n",
				       q / 10.0, pq[6], e.wcost);
			}
		}
		glint_image_free(photo);
		glint_image_free(weight);
		if (test_failures)
			break;
		dump(material, map, rots, lv, m, truth, &o, &res);
		printf("%-16s %-18s rot %5s %-10s", material,
		       strrchr(map, '/') + 1, rots, level_names[lv]);
		for (int k = 0; k < m->nparams; k++) {
			struct tally *g = &t[lv][group_of(k)];
			const struct glint_param *pi = &m->params[k];
			double lo = res.unc.lo[k], hi = res.unc.hi[k];
			int undet = !isfinite(res.se[k]) ||
				    hi - lo >= 0.5 * (pi->hi - pi->lo);
			double tb = 1.96 * res.unc.se_textbook[k];
			int in = truth[k] >= lo && truth[k] <= hi;
			if (undet) {
				g->undetermined++;
				printf(" %s:undet", pi->name);
				continue;
			}
			/* Roughness below the pixel footprint: glint reports
			 * an upper bound, not a value (fit/job.h); counted
			 * apart, with whether the bound holds. */
			double bound = k == m->lobes->roughness_param
					       ? glint_fit_roughness_bound(&res)
					       : NAN;
			if (isfinite(bound)) {
				g->bounded++;
				g->bound_holds += truth[k] <= bound;
				if (truth[k] > bound)
					printf(" %s:%.4f>bound %.4f", pi->name,
					       truth[k], bound);
				continue;
			}
			if (g->n < 512) {
				g->relerr[g->n] = fabs(res.p[k] - truth[k]) /
						  fmax(fabs(truth[k]), 1e-3);
				g->z[g->n] =
					fabs(res.p[k] - truth[k]) / res.se[k];
			}
			g->n++;
			g->in += in;
			g->in_textbook += fabs(truth[k] - res.p[k]) <= tb;
			/* without the systematic term: noise and sample sets */
			double vs = res.se[k] * res.se[k] -
				    res.unc.sys[k] * res.unc.sys[k];
			g->in_stat += fabs(truth[k] - res.p[k]) <=
				      res.unc.t[k] * sqrt(fmax(0, vs));
			if (!in)
				printf(" %s:%.4f[%.4f,%.4f]", pi->name,
				       truth[k], lo, hi);
		}
		if (getenv("COVERAGE_VERBOSE"))
			printf("\n    cost %.6g, at the truth %.6g; %d + %d "
			       "samples; model-error regions %d",
			       res.wcost, at_truth.wcost, res.light_samples,
			       res.lobe_samples, res.unc.nregions);
		for (int q = 0; getenv("COVERAGE_VERBOSE") && q < res.npasses;
		     q++)
			printf("\n    pass %-16s %5d px %3d it %9.6g -> %9.6g",
			       res.passes[q].name, res.passes[q].pixels,
			       res.passes[q].iterations, res.passes[q].cost0,
			       res.passes[q].cost);
		if (getenv("COVERAGE_VERBOSE"))
			for (int k = 0; k < m->nparams; k++) {
				int n = res.unc.n;
				printf("\n    %-10s %.4f fit %.4f se %.5f = "
				       "blocks %.5f + mc %.5f (textbook %.5f, "
				       "regions %.5f) t %.2f",
				       m->params[k].name, truth[k], res.p[k],
				       res.se[k],
				       sqrt(res.unc.cov_blocks[k * n + k]),
				       sqrt(res.unc.cov_mc[k * n + k]),
				       res.unc.se_textbook[k],
				       sqrt(res.unc.cov_regions[k * n + k]),
				       res.unc.t[k]);
			}
		printf("\n");
	}
	glint_image_free(clean);
	glint_renderer_release(&r);
}

int main(int argc, char **argv)
{
	static const char *const quick_mats[] = { "yellow-plastic", "teflon",
						  "silver", "satin-paint" };
	static const char *const all_mats[] = {
		"satin-paint",	  "semi-gloss-paint", "matte-paint",
		"yellow-plastic", "teflon",	      "nylon",
		"silver",	  "green-acrylic",    "aluminium-bronze",
		"copper",	  "nickel",
	};
	struct tally t[NLEVEL][NGROUP] = { { { 0 } } };

	int slice = argc >= 3 && !strcmp(argv[1], "slice");
	int quick = slice || (argc >= 3 && !strcmp(argv[1], "quick"));
	if (argc < 3 || (!quick && strcmp(argv[1], "full"))) {
		fprintf(stderr, "usage: %s slice|quick|full MAP...\n", argv[0]);
		return 2;
	}
	const char *const *mats = quick ? quick_mats : all_mats;
	int nmats = slice ? 2 : quick ? 4 : 11, nplace = quick ? 2 : 3;
	for (int a = 2; a < argc && !test_failures; a++)
		for (int i = 0; i < nmats && !test_failures; i++)
			for (int pl = 0; pl < nplace && !test_failures; pl++)
				one_case(argv[a], mats[(i + a) % nmats], pl, t);
	if (test_failures)
		return test_result();

	printf("\nrelative error |fit - truth| / truth: 68th and 95th "
	       "percentile (for the systematic term, fit.c)\n");
	for (int lv = 0; lv < NLEVEL; lv++)
		for (int g = 0; g < NGROUP; g++) {
			struct tally *x = &t[lv][g];
			int n = x->n < 512 ? x->n : 512;
			qsort(x->relerr, (size_t)n, sizeof(double), cmp_double);
			if (n)
				printf("%-11s %-10s %6.3f %6.3f\n",
				       level_names[lv], group_names[g],
				       x->relerr[(int)(0.68 * (n - 1))],
				       x->relerr[(int)(0.95 * (n - 1))]);
		}
	printf("\nnominal 95 %% intervals: fraction containing the truth\n");
	printf("(median |error| / standard error: about 0.67 for an interval "
	       "as wide as the errors need)\n");
	printf("%-11s %-10s %6s %8s %9s %9s %9s %7s %s\n", "noise", "parameter",
	       "cases", "glint", "med.|e|/se", "no sys.", "textbook", "undet.",
	       "bound (holds)");
	for (int lv = 0; lv < NLEVEL; lv++)
		for (int g = 0; g < NGROUP; g++) {
			struct tally *x = &t[lv][g];
			double c = x->n ? (double)x->in / x->n : NAN;
			double cb = x->n ? (double)x->in_textbook / x->n : NAN;
			double cs = x->n ? (double)x->in_stat / x->n : NAN;
			int nz = x->n < 512 ? x->n : 512;
			qsort(x->z, (size_t)nz, sizeof(double), cmp_double);
			double mz = nz ? x->z[(nz - 1) / 2] : NAN;
			printf("%-11s %-10s %6d %7.1f%% %9.2f %8.1f%% %8.1f%% "
			       "%7d %d (%d)\n",
			       level_names[lv], group_names[g], x->n, 100 * c,
			       mz, 100 * cs, 100 * cb, x->undetermined,
			       x->bounded, x->bound_holds);
			if (!x->n)
				continue;
			/* The target, 90-98 %, is printed; what is asserted
			 * is what is reached (docs/tests.md, "Uncertainty"):
			 * never below the textbook intervals, and floors under
			 * the coverage measured (quick, Venice: 62-100 %), so a
			 * change that loses coverage fails. */
			double floor = g == 2 ? 0.5 : 0.7;
			printf("%-11s %-10s target 90-98 %%: %s\n", "",
			       group_names[g],
			       c < 0.9	  ? "MISSED (below)"
			       : c > 0.98 ? "MISSED (above: too wide)"
					  : "met");
			CHECK(c >= cb, "%s %s: %.2f below the textbook %.2f",
			      level_names[lv], group_names[g], c, cb);
			/* slice: 4 cases a level are too few for a floor;
			 * it is checked on the levels pooled, below. */
			CHECK(slice || c >= floor,
			      "%s %s: coverage %.2f below %.2f",
			      level_names[lv], group_names[g], c, floor);
		}
	for (int g = 0; g < NGROUP; g++) {
		int n = 0, in = 0;
		for (int lv = 0; lv < NLEVEL; lv++)
			n += t[lv][g].n, in += t[lv][g].in;
		double c = n ? (double)in / n : 1, floor = g == 2 ? 0.5 : 0.7;
		printf("all levels  %-10s %6d %7.1f%%\n", group_names[g], n,
		       100 * c);
		CHECK(c >= floor,
		      "%s over all levels: coverage %.2f below %.2f",
		      group_names[g], c, floor);
	}
	return test_result();
}
