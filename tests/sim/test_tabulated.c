/* SPDX-License-Identifier: MIT */
/*
 * Spheres of a measured (tabulated) BRDF that is none of glint's models
 *: an Ashikhmin-Shirley material (its coupled diffuse
 * falls off toward grazing, its Blinn-Phong lobe has Schlick's Fresnel)
 * sampled into the MERL database's table layout (sim/tabulated.h), written
 * and read back as a MERL .binary, photographed by the reference renderer
 * under each map given, through the simulated sensor, and fitted as a user
 * would: with --select-model's candidates and with the default model.
 *
 *   test_tabulated [--quick] MAP...
 * --quick (the sim suite's): reference photos at 32 samples per
 * technique instead of 128, and --select-model without its three richer
 * candidates.
 *
 * Checks: the MERL file round trip and its refusals (truncated, other
 * dimensions, missing); the table against the analytic BRDF; per map, the
 * fit is accepted (not refused); and across maps, the default model's
 * parameters agree within their intervals (the same material must get the
 * same answer under different light): what the photos determine, so
 * specular x F0(ior) in place of specular and ior where glint reports that
 * a photo determines only their product.  Prints per map the relative RMSE,
 * the chosen model and why.
 */
#include "test.h"

#include "sim/fixtures.h"
#include "core/error.h"
#include "core/log.h"
#include "fit/job.h"
#include "fit/select.h"
#include "sim/tabulated.h"
#include "sim_scene.h"

#include <sys/stat.h>

static struct vec3 random_dir(unsigned *s)
{
	*s = *s * 1664525u + 1013904223u;
	double u1 = (*s >> 8) / 16777216.0;
	*s = *s * 1664525u + 1013904223u;
	double u2 = (*s >> 8) / 16777216.0;
	double r = sqrt(u1), a = 2 * M_PI * u2;
	return v3(r * cos(a), r * sin(a), sqrt(fmax(0, 1 - u1)));
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void file_checks(struct glint_brdf_table *t,
			struct glint_ashikhmin_shirley *as, const char *dir)
{
	char path[512], bad[512];
	struct glint_brdf_table *back = NULL;

	snprintf(path, sizeof(path), "%s/as.binary", dir);
	CHECK(glint_brdf_table_write(path, t) == 0, "write: %s",
	      glint_error_msg());
	CHECK(glint_brdf_table_read(path, &back) == 0, "read: %s",
	      glint_error_msg());
	unsigned s = 7;
	double rel[2000];
	int same = 1;
	for (int i = 0; back && i < 2000; i++) {
		struct vec3 wo = random_dir(&s), wi = random_dir(&s);
		double a[3], b[3], f[3];
		glint_brdf_table_eval(t, wo, wi, a);
		glint_brdf_table_eval(back, wo, wi, b);
		glint_ashikhmin_shirley_eval(as, wo, wi, f);
		for (int c = 0; c < 3; c++)
			same &= fabs(a[c] - b[c]) <= 1e-6 * fabs(a[c]);
		rel[i] = fabs(a[1] - f[1]) / f[1];
	}
	CHECK(same, "the table read back differs from the one written");
	qsort(rel, 2000, sizeof(double), cmp_double);
	printf("table against the analytic BRDF (nearest bin, green): median "
	       "%.4f, 90th percentile %.4f relative\n",
	       rel[1000], rel[1800]);
	CHECK(rel[1000] < 0.03, "median relative error %.4f", rel[1000]);
	glint_brdf_table_free(back);

	/* Refusals, each naming what was wrong. */
	FILE *f = fopen(path, "rb"), *g;
	snprintf(bad, sizeof(bad), "%s/short.binary", dir);
	g = fopen(bad, "wb");
	char buf[4096];
	size_t n = f ? fread(buf, 1, sizeof(buf), f) : 0;
	if (g) {
		fwrite(buf, 1, n, g);
		fclose(g);
	}
	CHECK(glint_brdf_table_read(bad, &back) == -EINVAL && !back,
	      "truncated file read");
	CHECK_MSG(glint_error_msg(), "4096 bytes");
	int32_t dims[3] = { 90, 90, 360 };
	memcpy(buf, dims, sizeof(dims));
	snprintf(bad, sizeof(bad), "%s/dims.binary", dir);
	g = fopen(bad, "wb");
	if (g) {
		fwrite(buf, 1, n, g);
		fclose(g);
	}
	CHECK(glint_brdf_table_read(bad, &back) == -EINVAL, "dims");
	CHECK_MSG(glint_error_msg(), "90 x 90 x 360");
	snprintf(bad, sizeof(bad), "%s/none.binary", dir);
	CHECK(glint_brdf_table_read(bad, &back) < 0, "missing file");
	CHECK_MSG(glint_error_msg(), "none.binary");
	if (f)
		fclose(f);
}

struct map_fit {
	struct glint_renderer r; /* kept for the joint fit */
	int inited;
	struct glint_image *photo, *weight;
	struct glint_fit_result ts, chosen_fit;
	int has_chosen;
	const char *chosen;
	double rel;
	int accepted;
};

static int quick;

/* Values x and y (standard errors sx, sy) further apart than 1.96 x
 * their combined standard error: printed, 1. */
static int apart(const char *model, const char *name, double x, double sx,
		 int i, double y, double sy, int j)
{
	if (!(fabs(x - y) > 1.96 * hypot(sx, sy)))
		return 0;
	printf("  %s %s: %.4f +- %.4f under map %d, %.4f +- %.4f under map "
	       "%d\n",
	       model, name, x, sx, i + 1, y, sy, j + 1);
	return 1;
}

/* Parameter pairs (maps i < j) further apart than 1.96 x their combined
 * standard error, printed; of the default fit or of BIC's choice.  What
 * is compared is what the photos determine: where either fit of the pair
 * determines specular x F0(ior) rather than each (glint says so: they
 * trade off, or ior is undetermined), that product per channel in place
 * of the specular albedos and ior (*combined counts those pairs). */
static int disagreements(const struct map_fit *fits, int nmaps, int chosen,
			 int *combined)
{
	int off = 0;

	for (int i = 0; i < nmaps; i++)
		for (int j = i + 1; j < nmaps; j++) {
			const struct glint_fit_result *a =
				chosen ? &fits[i].chosen_fit : &fits[i].ts;
			const struct glint_fit_result *b =
				chosen ? &fits[j].chosen_fit : &fits[j].ts;
			double va[3], sa[3], vb[3], sb[3], ca, cb;
			int fa = glint_fit_specular_f0(a, va, sa, &ca),
			    fb = glint_fit_specular_f0(b, vb, sb, &cb);
			int product = fa >= 0 && fb >= 0 && (fa || fb);
			for (int c = 0; product && c < 3; c++)
				if (isfinite(va[c]) && isfinite(vb[c]))
					off += apart(a->model->name,
						     "specular x F0(ior)",
						     va[c], sa[c], i, vb[c],
						     sb[c], j);
			*combined += product;
			for (int k = 0; k < a->model->nparams; k++) {
				const char *name = a->model->params[k].name;
				if (product && (!strcmp(name, "ior") ||
						!strncmp(name, "specular.", 9)))
					continue;
				off += apart(a->model->name, name, a->p[k],
					     a->se[k], i, b->p[k], b->se[k], j);
			}
		}
	return off;
}

static int fit_map(const char *map, const struct glint_bxdf *tm,
		   struct map_fit *out)
{
	struct glint_scene sc;
	struct glint_renderer *rr = &out->r;
	struct glint_reference_opts ro;
	struct glint_selection *sel = calloc(1, sizeof(*sel));
	int ret;

	sim_scene_192(&sc, map, -114);
	if (!sel || glint_renderer_init(rr, &sc, 0, NULL) < 0) {
		free(sel);
		return -1;
	}
	out->inited = 1;
	struct glint_image *photo = out->photo = glint_image_new(192, 192);
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	ro.samples = quick ? 32 : 128;
	ret = photo ? glint_reference_render_bxdf(&rr->scene, rr->env, tm, &ro,
						  photo)
		    : -1;
	if (!ret)
		ret = fixture_add_noise(photo, &out->weight, 0.1);
	struct glint_fit_opts o;
	glint_fit_default_opts(&o);
	if (!ret)
		ret = glint_select_model(rr, photo, out->weight, &o, !quick,
					 sel);
	if (!ret)
		ret = glint_fit(rr, &glint_model_torrance_sparrow, photo,
				out->weight, &o, &out->ts);
	if (!ret) {
		struct glint_fit_verdict v;
		out->accepted = glint_fit_judge(&out->ts, 0, &v);
		out->chosen = sel->c[sel->chosen].name;
		out->has_chosen = sel->has_fit[sel->chosen];
		if (out->has_chosen)
			out->chosen_fit = sel->fit[sel->chosen];
		out->rel = out->ts.rel_rmse;
		printf("%s: torrance-sparrow relative RMSE %.4f (%s); "
		       "--select-model: %s\n  %s\n  ",
		       map, out->rel, v.verdict, out->chosen, sel->why);
		for (int k = 0; k < 8; k++)
			printf(" %s %.4f+-%.4f",
			       glint_model_torrance_sparrow.params[k].name,
			       out->ts.p[k], out->ts.se[k]);
		printf("\n   structure's share of the signal %.4f; model "
		       "discrepancy:",
		       out->ts.misfit_share);
		for (int k = 0; k < 8; k++)
			printf(" %.4f", out->ts.discrepancy[k]);
		printf("\n   model-error jackknife over %d regions:",
		       out->ts.unc.nregions);
		for (int k = 0; out->ts.unc.nregions && k < 8; k++)
			printf(" %.4f",
			       sqrt(out->ts.unc.cov_regions[k * 8 + k]));
		printf("\n");
	} else {
		fprintf(stderr, "%s: %s\n", map, glint_error_msg());
	}
	free(sel);
	return ret;
}

/* One torrance-sparrow material from every map's photo at once: each
 * map's residual under it, and how far each map's own fit sits from it. */
static void joint_fit(struct map_fit *fits, int nmaps)
{
	struct glint_fit_view v[8];
	struct glint_fit_opts o;
	struct glint_fit_result *res = malloc(sizeof(*res));
	const struct glint_model *m = &glint_model_torrance_sparrow;

	for (int i = 0; i < nmaps; i++)
		v[i] = (struct glint_fit_view){ &fits[i].r, fits[i].photo,
						fits[i].weight };
	glint_fit_default_opts(&o);
	int ret = res ? glint_fit_views(v, nmaps, m, &o, res) : -ENOMEM;
	CHECK(ret == 0, "joint fit: %s", glint_error_msg());
	if (ret) {
		free(res);
		return;
	}
	printf("joint fit of the %d maps' photos: relative RMSE %.4f; per "
	       "map",
	       nmaps, res->rel_rmse);
	for (int i = 0; i < nmaps; i++) {
		struct glint_fit_verdict vd;
		struct glint_fit_result *one = malloc(sizeof(*one));
		if (!one)
			break;
		glint_fit_result_view(res, i, one);
		int ok = glint_fit_judge(one, 0, &vd);
		free(one);
		printf(" %.4f (alone %.4f)", res->view[i].rel_rmse,
		       fits[i].rel);
		CHECK(ok, "joint fit refused on map %d: %s", i + 1, vd.verdict);
	}
	printf("\n  ");
	for (int k = 0; k < m->nparams; k++)
		printf(" %s %.4f+-%.4f", m->params[k].name, res->p[k],
		       res->se[k]);
	printf("\n");
	free(res);
}

int main(int argc, char **argv)
{
	struct glint_ashikhmin_shirley as = { 200, { 0.30, 0.12, 0.05 }, 0.05 };
	struct glint_brdf_table *t = NULL;
	static struct map_fit fits[8];
	char dir[] = "/tmp/glint-tabulated-XXXXXX";
	quick = argc > 1 && !strcmp(argv[1], "--quick");
	argv += quick;
	argc -= quick;
	int nmaps = argc - 1 < 8 ? argc - 1 : 8;

	glint_log_set_mode(GLINT_LOG_QUIET);
	for (int i = 0; i < nmaps; i++) {
		struct stat st;
		if (stat(argv[1 + i], &st) < 0) {
			printf("%s absent: skipped\n", argv[1 + i]);
			return 77;
		}
	}
	if (!mkdtemp(dir) ||
	    glint_brdf_table_from(glint_ashikhmin_shirley_eval, &as, &t) < 0) {
		fprintf(stderr, "set-up: %s\n", glint_error_msg());
		return 1;
	}
	file_checks(t, &as, dir);
	struct glint_tabulated tab;
	struct glint_bxdf tm = glint_tabulated_bxdf(&tab, t, 0.1);
	for (int i = 0; i < nmaps; i++) {
		CHECK(fit_map(argv[1 + i], &tm, &fits[i]) == 0, "%s",
		      argv[1 + i]);
		CHECK(fits[i].accepted, "%s: refused", argv[1 + i]);
	}
	/* The same material under every map: each parameter's values
	 * within their combined intervals, pairwise: for the default model,
	 * and for the model BIC chose when it chose the same everywhere. */
	int same = nmaps > 1;
	for (int i = 1; i < nmaps; i++)
		same &= fits[i].has_chosen && fits[0].has_chosen &&
			fits[i].chosen_fit.model == fits[0].chosen_fit.model;
	int comb_ts = 0, comb_chosen = 0;
	int off_ts = disagreements(fits, nmaps, 0, &comb_ts);
	int off_chosen =
		same ? disagreements(fits, nmaps, 1, &comb_chosen) : -1;
	printf("across %d maps: %d pairs of what the photos determine outside "
	       "their combined 95 %% intervals for torrance-sparrow (%d pairs "
	       "of maps compared on specular x F0(ior)), %d for the model "
	       "BIC chose (-1: it chose differently)\n",
	       nmaps, off_ts, comb_ts, off_chosen);
	CHECK(nmaps < 2 || off_ts == 0 || off_chosen == 0,
	      "neither the default model (%d pairs apart) nor the chosen one "
	      "(%d) gives the same material under every map",
	      off_ts, off_chosen);
	if (nmaps > 1)
		joint_fit(fits, nmaps);
	for (int i = 0; i < nmaps; i++) {
		if (fits[i].inited)
			glint_renderer_release(&fits[i].r);
		glint_image_free(fits[i].photo);
		glint_image_free(fits[i].weight);
	}
	glint_brdf_table_free(t);
	/* What file_checks() wrote, then the folder. */
	static const char *const made[] = { "as.binary", "short.binary",
					    "dims.binary" };
	int left = 0;
	for (size_t k = 0; k < sizeof(made) / sizeof(*made); k++) {
		char path[600];
		snprintf(path, sizeof(path), "%s/%s", dir, made[k]);
		left |= unlink(path) < 0 && errno != ENOENT;
	}
	if (left || rmdir(dir) < 0)
		fprintf(stderr, "could not remove %s\n", dir);
	printf("%d checks, %d failed\n", test_checks, test_failures);
	return test_failures ? 1 : 0;
}
