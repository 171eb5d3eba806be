/* SPDX-License-Identifier: MIT */
/* Appearance models: Beckmann, Fresnel, shadowing, pdfs, sampling. */
#include "chisq.h"
#include "quadrature.h"
#include "test.h"

#include "core/error.h"
#include "fit/brdf/microfacet.h"
#include "fit/brdf/model.h"
#include "fit/render/sampling.h"

static void test_beckmann_normalised(void)
{
	double ms[4] = { 0.005, 0.05, 0.2, 0.6 };
	for (int k = 0; k < 4; k++) {
		/* Integral of D cos over the hemisphere, in theta only. */
		int n = 200000;
		double sum = 0;
		for (int j = 0; j < n; j++) {
			double th = (j + 0.5) * (M_PI / 2) / n;
			sum += glint_beckmann_d(cos(th), ms[k]) * cos(th) *
			       sin(th);
		}
		sum *= 2 * M_PI * (M_PI / 2) / n;
		char what[64];
		snprintf(what, sizeof(what), "integral of D cos, m = %g",
			 ms[k]);
		CHECK_NEAR(sum, 1.0, 1e-4, what);
	}
}

/* Fresnel from Snell's law and the s/p amplitude coefficients. */
static double fresnel_snell(double ci, double n)
{
	double si = sqrt(1 - ci * ci), st = si / n, ct = sqrt(1 - st * st);
	double rs = (ci - n * ct) / (ci + n * ct);
	double rp = (n * ci - ct) / (n * ci + ct);
	return 0.5 * (rs * rs + rp * rp);
}

static void test_fresnel(void)
{
	double ns[4] = { 1.15, 1.5, 2.34, 3.23 };
	for (int k = 0; k < 4; k++) {
		double n = ns[k], f0 = (n - 1) / (n + 1);
		CHECK_NEAR(glint_fresnel_dielectric(1, n), f0 * f0, 1e-12,
			   "normal incidence ((n-1)/(n+1))^2");
		CHECK_NEAR(glint_fresnel_dielectric(1e-9, n), 1, 1e-6,
			   "grazing incidence -> 1");
		for (int a = 1; a < 90; a += 7) {
			double c = cos(a * M_PI / 180);
			CHECK_NEAR(glint_fresnel_dielectric(c, n),
				   fresnel_snell(c, n), 1e-12,
				   "against the Snell form");
		}
	}
	/* Tabulated: glass n = 1.5: 4 % at normal incidence; at Brewster's
	 * angle (56.31 deg) Rp = 0 and Rs = 0.1479, so F = 0.0740. */
	CHECK_NEAR(glint_fresnel_dielectric(1, 1.5), 0.04, 1e-12, "glass R0");
	CHECK_NEAR(glint_fresnel_dielectric(cos(atan(1.5)), 1.5), 0.0740, 1e-4,
		   "glass at Brewster's angle");
	CHECK_NEAR(glint_fresnel_dielectric(1, 1.0), 0, 1e-15, "n = 1");
}

static void test_vcavity(void)
{
	CHECK_NEAR(glint_vcavity_g(1, 1, 1, 1), 1, 0, "normal incidence");
	CHECK(glint_vcavity_g(0.9, 0.05, 0.8, 0.6) < 0.2,
	      "grazing view is masked: %g",
	      glint_vcavity_g(0.9, 0.05, 0.8, 0.6));
}

static struct vec3 dir_at(double theta_deg)
{
	double t = theta_deg * M_PI / 180;
	return v3(sin(t), 0, cos(t));
}

/* Integral of the pdf over the hemisphere, midpoint rule in (cos, phi). */
static double pdf_integral(const struct glint_model_ops *m, const double *p,
			   struct vec3 wo)
{
	int nc = 1500, np = 600;
	double sum = 0;
	for (int j = 0; j < nc; j++) {
		/* Substitute z = 1 - t^2 to refine near the pole. */
		double t = (j + 0.5) / nc, z = 1 - t * t, dz = 2 * t / nc;
		double r = sqrt(fmax(0, 1 - z * z));
		for (int i = 0; i < np; i++) {
			double ph = (i + 0.5) * 2 * M_PI / np;
			sum += m->pdf(p, wo, v3(r * cos(ph), r * sin(ph), z)) *
			       dz * (2 * M_PI / np);
		}
	}
	return sum;
}

static void test_ts_pdf_and_sampling(void)
{
	const struct glint_model_ops *m = &glint_model_torrance_sparrow;
	double p[8] = { 0.3, 0.2, 0.1, 0.5, 0.5, 0.5, 0.2, 1.5 };
	double angles[3] = { 0, 30, 60 };

	for (int k = 0; k < 3; k++) {
		struct vec3 wo = dir_at(angles[k]);
		double integral = pdf_integral(m, p, wo);
		/* Reflected lobe directions below the horizon are rejected
		 * by sample(): the pdf integrates to 1 minus that mass. */
		int ns = 200000, rejected = 0, mismatch = 0;
		int nz = 20, nphi = 16;
		double obs[20 * 16 + 1] = { 0 }, expc[20 * 16 + 1] = { 0 };
		for (int s = 0; s < ns; s++) {
			double u[3] = { glint_u01(glint_hash3(s, k, 1)),
					glint_u01(glint_hash3(s, k, 2)),
					glint_u01(glint_hash3(s, k, 3)) };
			struct vec3 wi;
			double pdf = m->sample(p, wo, u, &wi);
			if (pdf == 0) {
				rejected++;
				continue;
			}
			if (fabs(pdf - m->pdf(p, wo, wi)) > 1e-9 * pdf)
				mismatch++;
			int iz = (int)(wi.z * nz);
			double ph = atan2(wi.y, wi.x);
			int ip = (int)((ph + M_PI) / (2 * M_PI) * nphi);
			iz = iz >= nz ? nz - 1 : iz;
			ip = ip >= nphi ? nphi - 1 : ip;
			obs[iz * nphi + ip] += 1;
		}
		obs[nz * nphi] = rejected;
		double total = 0;
		for (int iz = 0; iz < nz; iz++)
			for (int ip = 0; ip < nphi; ip++) {
				double acc = 0;
				int sub = 24;
				for (int b = 0; b < sub; b++)
					for (int a = 0; a < sub; a++) {
						double z =
							(iz + (b + 0.5) / sub) /
							nz;
						double ph =
							-M_PI +
							(ip + (a + 0.5) / sub) *
								2 * M_PI / nphi;
						double r = sqrt(1 - z * z);
						acc += m->pdf(p, wo,
							      v3(r * cos(ph),
								 r * sin(ph),
								 z));
					}
				double e = ns * acc / (sub * sub) / nz *
					   (2 * M_PI / nphi);
				expc[iz * nphi + ip] = e;
				total += e;
			}
		expc[nz * nphi] = fmax(0, ns - total);
		int dof;
		double pv = chisq_test(obs, expc, nz * nphi + 1, &dof);
		CHECK(integral <= 1 + 2e-3 &&
			      fabs(integral - (1 - (double)rejected / ns)) <
				      5e-3,
		      "theta_o %g: pdf integral %g, accepted fraction %g",
		      angles[k], integral, 1 - (double)rejected / ns);
		CHECK(mismatch == 0, "%d sample pdfs differ from pdf()",
		      mismatch);
		CHECK(pv > 1e-3, "theta_o %g: chi-square p = %g (dof %d)",
		      angles[k], pv, dof);
	}
}

/* Without Fresnel variation: the full model's specular divided by F. */
static void test_constant_fresnel(void)
{
	const struct glint_model_ops *nf = &glint_model_ts_constant_fresnel;
	const struct glint_model_ops *ts = &glint_model_torrance_sparrow;
	double p[8] = { 0, 0, 0, 0.5, 0.4, 0.3, 0.2, 1.5 };
	int bad = 0, mismatch = 0;

	CHECK(nf->nparams == 7 && glint_model_find(nf->name) == nf,
	      "%s: %d parameters", nf->name, nf->nparams);
	for (int s = 0; s < 2000; s++) {
		double u[3] = { glint_u01(glint_hash3(s, 7, 1)),
				glint_u01(glint_hash3(s, 7, 2)),
				glint_u01(glint_hash3(s, 7, 3)) };
		struct vec3 wo = dir_at(70 * glint_u01(glint_hash3(s, 7, 4)));
		struct vec3 wi;
		double pdf = nf->sample(p, wo, u, &wi);
		if (pdf == 0)
			continue;
		mismatch += fabs(pdf - nf->pdf(p, wo, wi)) > 1e-9 * pdf;
		double fn[3], ft[3];
		nf->eval(p, wo, wi, fn);
		ts->eval(p, wo, wi, ft);
		struct vec3 h = v3_norm(v3_add(wo, wi));
		double F = glint_fresnel_dielectric(v3_dot(wo, h), p[7]);
		for (int c = 0; c < 3; c++)
			bad += fabs(fn[c] * F - ft[c]) > 1e-9 * (ft[c] + 1e-30);
	}
	CHECK(bad == 0, "%d values are not the full model's over F", bad);
	CHECK(mismatch == 0, "%d sample pdfs differ from pdf()", mismatch);
}

static void test_lambert(void)
{
	const struct glint_model_ops *m = &glint_model_lambert;
	double p[3] = { 0.2, 0.5, 0.8 }, a[3];
	albedo_quadrature(m, p, dir_at(40), a);
	for (int c = 0; c < 3; c++)
		CHECK_NEAR(a[c], p[c], 2e-3, "Lambert albedo");
	CHECK_NEAR(pdf_integral(m, p, dir_at(10)), 1, 1e-3,
		   "cosine pdf integral");
}

/* A white furnace: the directional albedo never exceeds 1. */
static void test_ts_energy(void)
{
	const struct glint_model_ops *m = &glint_model_torrance_sparrow;
	double rough[4] = { 0.05, 0.1, 0.3, 0.7 }, ior[3] = { 1.5, 2.34, 5 };
	double worst = 0;
	for (int r = 0; r < 4; r++)
		for (int i = 0; i < 3; i++)
			for (int t = 0; t <= 85; t += 17) {
				double p[8] = { 0, 0, 0,	1,
						1, 1, rough[r], ior[i] };
				double a[3];
				albedo_quadrature(m, p, dir_at(t), a);
				worst = fmax(worst, a[0]);
				CHECK(a[0] <= 1.0,
				      "albedo %g > 1 (m %g, n %g, "
				      "theta %d)",
				      a[0], rough[r], ior[i], t);
				/* Diffuse + specular with kd + ks = 1. */
				double q[8] = { 0.5, 0.5, 0.5,	    0.5,
						0.5, 0.5, rough[r], ior[i] };
				albedo_quadrature(m, q, dir_at(t), a);
				CHECK(a[0] <= 1.0, "kd=ks=0.5: albedo %g",
				      a[0]);
			}
	fprintf(stderr, "  largest specular albedo seen: %.4f\n", worst);
}

static void test_material_json(void)
{
	const struct glint_model_ops *m;
	double p[GLINT_MAX_PARAMS];
	json_error_t e;
	json_t *o = json_loads("{\"model\": \"torrance-sparrow\", \"diffuse\":"
			       " [0.1, 0.2, 0.3], \"roughness\": 0.05}",
			       0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) == 0, "%s",
	      glint_error_msg());
	CHECK(m == &glint_model_torrance_sparrow && p[2] == 0.3 &&
		      p[6] == 0.05 && p[7] == 1.5 && p[3] == 0.5,
	      "values %g %g %g %g", p[2], p[6], p[7], p[3]);
	json_t *back = glint_material_to_json(m, p);
	CHECK(json_real_value(json_array_get(json_object_get(back, "diffuse"),
					     1)) == 0.2,
	      "to_json lost diffuse.g");
	json_decref(back);
	json_decref(o);

	o = json_loads("{\"model\": \"torrance-sparrow\", \"ior\": 0.5}", 0,
		       &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "ior 0.5 accepted");
	CHECK_MSG(glint_error_msg(), "m.json: ior = 0.5: expected a number in "
				     "[1, 5]");
	json_decref(o);
	o = json_loads("{\"model\": \"phong\"}", 0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "unknown model accepted");
	CHECK_MSG(glint_error_msg(), "expected one of lambert, "
				     "torrance-sparrow");
	json_decref(o);
	o = json_loads("{\"model\": \"lambert\", \"difuse\": [1,1,1]}", 0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "misspelt key accepted");
	CHECK_MSG(glint_error_msg(), "difuse: unknown key");
	json_decref(o);
	o = json_loads("{\"model\": \"lambert\", \"diffuse\": [1,1]}", 0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "2-element colour accepted");
	CHECK_MSG(glint_error_msg(), "an array of 3 numbers");
	json_decref(o);
}

static void test_paper_table(void)
{
	const struct glint_model_ops *m;
	double p[GLINT_MAX_PARAMS];
	const char *table = GLINT_DATA_DIR "/paper-table1.json";
	CHECK(glint_material_load(table, "copper", &m, p) == 0, "%s",
	      glint_error_msg());
	CHECK(p[3] == 0.713 && p[6] == 0.005 && p[7] == 2.603,
	      "copper read as %g %g %g", p[3], p[6], p[7]);
	CHECK(glint_material_load(table, "unobtainium", &m, p) < 0,
	      "unknown material found");
	CHECK_MSG(glint_error_msg(), "no material named 'unobtainium'");
}

int main(void)
{
	RUN(test_beckmann_normalised);
	RUN(test_fresnel);
	RUN(test_vcavity);
	RUN(test_ts_pdf_and_sampling);
	RUN(test_lambert);
	RUN(test_constant_fresnel);
	RUN(test_ts_energy);
	RUN(test_material_json);
	RUN(test_paper_table);
	return test_result();
}
