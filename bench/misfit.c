/* SPDX-License-Identifier: MIT */
/*
 * How far a misfit answer moves with the light: the calibration of the
 * model-discrepancy term (fit/fit.c, discrepancy()).
 *
 * Materials that are none of glint's models (a Phong lobe about the
 * mirror direction, Ward's isotropic lobe, a GGX lobe over a Lambertian
 * base, a coloured Blinn-Phong metal with Schlick's Fresnel, Oren-Nayar's
 * rough diffuse under a Blinn-Phong lobe, Burley's diffuse under GGX:
 * the last two not Lambertian, as paints and plastics are not) sampled into
 * MERL tables (sim/tabulated.h), photographed by the reference renderer
 * at 192 px through the sensor model under four maps (the royal
 * esplanade, the quarry, Grace Cathedral, the Uffizi), each turned to
 * ROTATIONS headings about the vertical (-114, -24, 66, 156 degrees by
 * default: the brightest light on either side, behind, in front), and
 * fitted with Torrance-Sparrow at glint's defaults without the term
 * (no_discrepancy).  Per material, pair of lights and parameter: the two
 * answers, their standard errors and each fit's misfit share f (the
 * structure's part of the relative RMSE; 0 when the residual is not
 * structured).  A class's coefficient c (diffuse albedo, specular
 * albedo, roughness, ior) is, per material, the 95th percentile over its
 * pairs of the c that just puts the pair within its combined 95 % interval
 * when each fit's variance gains (c f s)^2, s the parameter's scale
 * (glint_fit_discrepancy_scale()); then the largest over the materials,
 * so that each material's pairs are covered 95 %.  Judged
 * leave-one-material-out (each
 * material with the others' c) and on a held-out material under held-out
 * maps: Ashikhmin-Shirley, as tests/sim/test_tabulated.c has it, under
 * Venice, Blender's studio and courtyard.
 *
 *   bench/misfit [ROTATIONS]     (1 to 8; 4 unless given)
 * Prints a line per fit, the coefficients and the pairs within; writes
 * bench-out/misfit.csv.  About 15 minutes here at 4 rotations.
 */
#define _DEFAULT_SOURCE
#include "bench.h"
#include "sim/fixtures.h"

#include "core/error.h"
#include "core/log.h"
#include "fit/fit.h"
#include "fit/job.h"
#include "sim/tabulated.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_LIGHTS 32
#define NP	   8

struct material {
	const char *name;
	void (*eval)(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3]);
	double kd[3], ks[3], shape;
	double aux; /* the diffuse's own roughness, where it has one */
	void *ctx;  /* eval's, when not the material itself */
};

static double schlick(double f0, double c)
{
	return f0 + (1 - f0) * pow(1 - c, 5);
}

/* Lambert + modified Phong about the mirror direction. */
static void phong(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	struct vec3 r = v3(-wo.x, -wo.y, wo.z);
	double c = fmax(0, v3_dot(r, wi));
	double s = (m->shape + 2) / (2 * M_PI) * pow(c, m->shape);
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI + m->ks[k] * s;
}

/* Lambert + Ward's isotropic lobe, roughness `shape`. */
static void ward(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double a2 = m->shape * m->shape, t2 = (1 - h.z * h.z) / (h.z * h.z);
	double s = exp(-t2 / a2) / (4 * M_PI * a2 * sqrt(wi.z * wo.z));
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI + m->ks[k] * s;
}

static double smith_ggx(double a2, double c)
{
	return 2 * c / (c + sqrt(a2 + (1 - a2) * c * c));
}

/* Lambert + GGX (Smith's shadowing, Schlick's Fresnel from ks). */
static void ggx(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double a2 = m->shape * m->shape, d = h.z * h.z * (a2 - 1) + 1;
	double dd = a2 / (M_PI * d * d);
	double g = smith_ggx(a2, wi.z) * smith_ggx(a2, wo.z);
	double hk = v3_dot(h, wi);
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI +
			 dd * g * schlick(m->ks[k], hk) / (4 * wi.z * wo.z);
}

/* A metal: normalised Blinn-Phong, the V-cavity shadowing, Schlick's
 * Fresnel from the coloured ks, a faint Lambertian base. */
static void metal(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double hk = v3_dot(h, wi);
	double d = (m->shape + 2) / (2 * M_PI) * pow(h.z, m->shape);
	double g = fmin(
		1, fmin(2 * h.z * wo.z / v3_dot(wo, h), 2 * h.z * wi.z / hk));
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI +
			 d * g * schlick(m->ks[k], hk) / (4 * wi.z * wo.z);
}

/* Oren-Nayar's rough diffuse (their qualitative model, slope deviation
 * `aux` radians: flatter than Lambert, brighter back toward the light) +
 * Blinn-Phong's lobe, normalised as (n + 8) / 8 pi, without Fresnel. */
static void oren(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	double s2 = m->aux * m->aux;
	double a = 1 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
	double ti = acos(fmin(1, wi.z)), to = acos(fmin(1, wo.z));
	double pi = hypot(wi.x, wi.y), po = hypot(wo.x, wo.y);
	double cphi =
		pi > 0 && po > 0 ? (wi.x * wo.x + wi.y * wo.y) / (pi * po) : 0;
	double on =
		a + b * fmax(0, cphi) * sin(fmax(ti, to)) * tan(fmin(ti, to));
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double s = (m->shape + 8) / (8 * M_PI) * pow(h.z, m->shape);
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI * on + m->ks[k] * s;
}

/* Burley's (Disney's) diffuse, its retro-reflection and grazing fall-off
 * set by the roughness `aux` (F_D90 = 0.5 + 2 aux cos^2 theta_d), + GGX
 * with Smith's shadowing and Schlick's Fresnel from ks. */
static void burley(void *ctx, struct vec3 wo, struct vec3 wi, double rgb[3])
{
	const struct material *m = ctx;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double hk = v3_dot(h, wi);
	double fd90 = 0.5 + 2 * m->aux * hk * hk;
	double fd = (1 + (fd90 - 1) * pow(1 - wi.z, 5)) *
		    (1 + (fd90 - 1) * pow(1 - wo.z, 5));
	double a2 = m->shape * m->shape, d = h.z * h.z * (a2 - 1) + 1;
	double dd = a2 / (M_PI * d * d);
	double g = smith_ggx(a2, wi.z) * smith_ggx(a2, wo.z);
	for (int k = 0; k < 3; k++)
		rgb[k] = m->kd[k] / M_PI * fd +
			 dd * g * schlick(m->ks[k], hk) / (4 * wi.z * wo.z);
}

static struct material materials[] = {
	{ .name = "phong",
	  .eval = phong,
	  .kd = { 0.45, 0.25, 0.10 },
	  .ks = { 0.05, 0.05, 0.05 },
	  .shape = 120 },
	{ .name = "ward",
	  .eval = ward,
	  .kd = { 0.15, 0.30, 0.45 },
	  .ks = { 0.08, 0.08, 0.08 },
	  .shape = 0.12 },
	{ .name = "ggx",
	  .eval = ggx,
	  .kd = { 0.30, 0.30, 0.30 },
	  .ks = { 0.04, 0.04, 0.04 },
	  .shape = 0.15 },
	{ .name = "metal",
	  .eval = metal,
	  .kd = { 0.02, 0.02, 0.02 },
	  .ks = { 0.90, 0.60, 0.40 },
	  .shape = 400 },
	{ .name = "oren",
	  .eval = oren,
	  .kd = { 0.35, 0.30, 0.20 },
	  .ks = { 0.06, 0.06, 0.06 },
	  .shape = 150,
	  .aux = 0.4 },
	{ .name = "burley",
	  .eval = burley,
	  .kd = { 0.25, 0.30, 0.45 },
	  .ks = { 0.04, 0.04, 0.04 },
	  .shape = 0.10,
	  .aux = 0.2 },
};
#define NMAT (int)(sizeof(materials) / sizeof(*materials))

struct one_fit {
	double p[NP], se[NP], f, ratio;
	int ok;
};

static struct one_fit fits[NMAT][MAX_LIGHTS];

static const char *const class_name[4] = { "diffuse", "specular", "roughness",
					   "ior" };

static const char *base(const char *path)
{
	const char *s = path ? strrchr(path, '/') : NULL;
	return s ? s + 1 : path ? path : "(none)";
}

static int fit_one(const char *map, double rot, const struct glint_bxdf *tm,
		   struct one_fit *out)
{
	struct glint_scene sc;
	struct glint_renderer r;
	struct glint_reference_opts ro;
	struct glint_image *weight = NULL;
	struct glint_fit_result *res = calloc(1, sizeof(*res));
	int ret;

	fixture_scene(&sc, 192, map);
	sc.env_rotation[1] = rot;
	if (!res || glint_renderer_init(&r, &sc, 0, NULL) < 0) {
		free(res);
		return -1;
	}
	struct glint_image *photo = glint_image_new(192, 192);
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	ro.samples = 128;
	ret = photo ? glint_reference_render_bxdf(&r.scene, r.env, tm, &ro,
						  photo)
		    : -1;
	if (!ret)
		ret = fixture_add_noise(photo, &weight, 0.1);
	struct glint_fit_opts o;
	glint_fit_default_opts(&o);
	o.no_discrepancy = 1;
	if (!ret)
		ret = glint_fit(&r, &glint_model_torrance_sparrow, photo,
				weight, &o, res);
	if (!ret) {
		struct glint_fit_verdict v;
		glint_fit_judge(res, 0, &v);
		memcpy(out->p, res->p, sizeof(out->p));
		memcpy(out->se, res->se, sizeof(out->se));
		out->ratio = v.ratio;
		out->f = res->misfit_share;
		out->ok = 1;
	}
	glint_image_free(photo);
	glint_image_free(weight);
	glint_renderer_release(&r);
	free(res);
	return ret;
}

/* Parameter k's class and its discrepancy scale in fit f (fit.c). */
static double scale_of(const struct one_fit *f, int k, int *cl)
{
	return glint_fit_discrepancy_scale(&glint_model_torrance_sparrow, f->p,
					   k, cl);
}

/* Parameter k's class alone (it does not depend on the values). */
static int class_of(int k)
{
	static const double p[NP];
	int cl;
	glint_fit_discrepancy_scale(&glint_model_torrance_sparrow, p, k, &cl);
	return cl;
}

/* The c that just puts the pair (a, b) within its combined 95 % interval
 * for parameter k: 0 when it is already, INFINITY when neither fit has
 * a misfit share. */
static double c_needed(const struct one_fit *a, const struct one_fit *b, int k)
{
	int cl;
	double d = a->p[k] - b->p[k], z = 1.96;
	double left =
		d * d / (z * z) - a->se[k] * a->se[k] - b->se[k] * b->se[k];
	double ga = a->f * scale_of(a, k, &cl), gb = b->f * scale_of(b, k, &cl);
	if (left <= 0)
		return 0;
	if (ga * ga + gb * gb <= 0)
		return INFINITY;
	return sqrt(left / (ga * ga + gb * gb));
}

/* Per class, the 95th percentile of c_needed over material m's pairs. */
static void material_c(int m, int nmaps, double c[4])
{
	for (int cl = 0; cl < 4; cl++) {
		static double v[MAX_LIGHTS * MAX_LIGHTS * NP];
		int n = 0;
		for (int i = 0; i < nmaps; i++)
			for (int j = i + 1; j < nmaps; j++)
				for (int k = 0; k < NP; k++)
					if (fits[m][i].ok && fits[m][j].ok &&
					    class_of(k) == cl)
						v[n++] = c_needed(&fits[m][i],
								  &fits[m][j],
								  k);
		qsort(v, n, sizeof(double), bench_cmp);
		c[cl] = n ? v[(int)ceil(0.95 * n) - 1] : 0;
	}
}

/* The coefficients: per class the largest over the materials other than
 * `skip` (-1: all) of material_c(), so that each gets its 95 %. */
static void coefficients(int nmaps, int skip, double c[4])
{
	memset(c, 0, 4 * sizeof(double));
	for (int m = 0; m < NMAT; m++) {
		double cm[4];
		if (m == skip)
			continue;
		material_c(m, nmaps, cm);
		for (int cl = 0; cl < 4; cl++)
			c[cl] = fmax(c[cl], cm[cl]);
	}
}

/* Pairs of material m within their combined 95 % interval with c. */
static int covered(const struct one_fit *f, int nmaps, const double c[4],
		   int *total)
{
	int in = 0;
	for (int i = 0; i < nmaps; i++)
		for (int j = i + 1; j < nmaps; j++)
			for (int k = 0; k < NP; k++) {
				const struct one_fit *a = &f[i], *b = &f[j];
				if (!a->ok || !b->ok)
					continue;
				int cl;
				double ca = a->f * scale_of(a, k, &cl),
				       cb = b->f * scale_of(b, k, &cl);
				ca *= c[cl];
				cb *= c[cl];
				double s = sqrt(a->se[k] * a->se[k] +
						b->se[k] * b->se[k] + ca * ca +
						cb * cb);
				in += fabs(a->p[k] - b->p[k]) <= 1.96 * s;
				++*total;
			}
	return in;
}

static int run(struct material *mat, const char *const *maps, int nmaps,
	       int nrot, struct one_fit *out, FILE *csv)
{
	struct glint_brdf_table *t = NULL;

	if (glint_brdf_table_from(mat->eval, mat->ctx ? mat->ctx : mat, &t) <
	    0) {
		fprintf(stderr, "%s: %s\n", mat->name, glint_error_msg());
		return -1;
	}
	struct glint_tabulated tab;
	struct glint_bxdf tm = glint_tabulated_bxdf(&tab, t, 0.1);
	for (int i = 0; i < nmaps * nrot; i++) {
		const char *map = maps[i / nrot];
		double rot = -114 + 90 * (i % nrot);
		struct one_fit *o = &out[i];
		if (fit_one(map, rot, &tm, o) < 0) {
			printf("%-6s %s %4.0f: %s\n", mat->name, base(map), rot,
			       glint_error_msg());
			continue;
		}
		printf("%-6s %-24s %4.0f ratio %5.2f share %.4f:", mat->name,
		       base(map), rot, o->ratio, o->f);
		fprintf(csv, "%s,%s,%.0f,%.4f,%.5f", mat->name, base(map), rot,
			o->ratio, o->f);
		for (int k = 0; k < NP; k++) {
			printf(" %.4f+-%.4f", o->p[k], o->se[k]);
			fprintf(csv, ",%.6f,%.6f", o->p[k], o->se[k]);
		}
		printf("\n");
		fprintf(csv, "\n");
		fflush(stdout);
	}
	glint_brdf_table_free(t);
	return 0;
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/misfit [ROTATIONS]";
	bench_help(argc, argv, usage);
	static const char *const train[] = {
		GLINT_SHARED_DATA "/probes/polyhaven_1k/royal_esplanade_1k.hdr",
		GLINT_SHARED_DATA "/probes/polyhaven_1k/quarry_01_1k.hdr",
		GLINT_SHARED_DATA "/probes/probulator_small/grace.hdr",
		GLINT_SHARED_DATA "/probes/probulator_small/uffizi.hdr",
	};
	static const char *const held[] = {
		GLINT_DATA_DIR "/env/venice_sunset_1k.hdr",
		GLINT_SHARED_DATA "/probes/blender_studiolights/studio.exr",
		GLINT_SHARED_DATA "/probes/blender_studiolights/courtyard.exr",
	};
	/* tests/sim/test_tabulated.c's material. */
	static struct glint_ashikhmin_shirley as_brdf = { 200,
							  { 0.30, 0.12, 0.05 },
							  0.05 };
	static struct material as = { .name = "a-s",
				      .eval = glint_ashikhmin_shirley_eval,
				      .ctx = &as_brdf };
	static struct one_fit held_fits[MAX_LIGHTS];
	int nrot = argc > 1 ? bench_count(argv[1], 1, MAX_LIGHTS / 4) : 4;

	if (nrot < 0 || argc > 2)
		bench_refuse(argv[nrot < 0 ? 1 : 2], usage);
	glint_log_set_mode(GLINT_LOG_QUIET);
	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/misfit.csv", "w");
	if (!csv) {
		perror("bench-out/misfit.csv");
		return 1;
	}
	fprintf(csv, "material,map,rotation,ratio,share");
	for (int k = 0; k < NP; k++)
		fprintf(csv, ",p%d,se%d", k, k);
	fprintf(csv, "\n");
	int nl = 4 * nrot;
	for (int m = 0; m < NMAT; m++)
		if (run(&materials[m], train, 4, nrot, fits[m], csv) < 0)
			return 1;
	if (run(&as, held, 3, 1, held_fits, csv) < 0)
		return 1;
	fclose(csv);
	double c[4], none[4] = { 0, 0, 0, 0 };
	coefficients(nl, -1, c);
	for (int m = 0; m < NMAT; m++) {
		double cm[4];
		material_c(m, nl, cm);
		printf("%-6s 95th percentile of its pairs' c:",
		       materials[m].name);
		for (int cl = 0; cl < 4; cl++)
			printf(" %s %.3f", class_name[cl], cm[cl]);
		printf("\n");
	}
	printf("coefficients (per class the largest of those):");
	for (int cl = 0; cl < 4; cl++)
		printf(" %s %.3f", class_name[cl], c[cl]);
	printf("\n");
	for (int m = 0; m < NMAT; m++) {
		double cm[4];
		int t0 = 0, t1 = 0, t2 = 0;
		coefficients(nl, m, cm);
		int before = covered(fits[m], nl, none, &t0);
		int in = covered(fits[m], nl, cm, &t1);
		int all = covered(fits[m], nl, c, &t2);
		printf("%-6s pairs within: %d/%d without the term, %d/%d with "
		       "the others' c (%.3f %.3f %.3f %.3f), %d/%d with all\n",
		       materials[m].name, before, t0, in, t1, cm[0], cm[1],
		       cm[2], cm[3], all, t2);
	}
	int h0 = 0, h1 = 0;
	int before = covered(held_fits, 3, none, &h0);
	int after = covered(held_fits, 3, c, &h1);
	printf("held out (Ashikhmin-Shirley under Venice, studio, courtyard): "
	       "%d/%d pairs within without the term, %d/%d with it\n",
	       before, h0, after, h1);
	return 0;
}
