/* SPDX-License-Identifier: MIT */
/* Appearance models: Beckmann, Fresnel, shadowing, pdfs, sampling. */
#include "chisq.h"
#include "quadrature.h"
#include "test.h"

#include "core/error.h"
#include "fit/brdf/microfacet.h"
#include "fit/brdf/model.h"
#include "fit/render/sampling.h"
#include "sim/tabulated.h"

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

/* d log F / d n from glint_fresnel_dielectric_dlog(), whose F must be
 * glint_fresnel_dielectric()'s. */
static double fresnel_dlog(double c, double n)
{
	double dlog, f = glint_fresnel_dielectric_dlog(c, n, &dlog);
	CHECK_NEAR(f, glint_fresnel_dielectric(c, n), 1e-15,
		   "F beside its derivative");
	return dlog;
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

	/* d log F / d n against a central difference of F */
	double worst = 0;
	for (int k = 0; k < 4; k++)
		for (int a = 0; a < 90; a += 3) {
			double c = cos(a * M_PI / 180), n = ns[k], h = 1e-6;
			double fd = (glint_fresnel_dielectric(c, n + h) -
				     glint_fresnel_dielectric(c, n - h)) /
				    (2 * h);
			double d = fresnel_dlog(c, n) *
				   glint_fresnel_dielectric(c, n);
			worst = fmax(worst,
				     fabs(d - fd) / fmax(fabs(fd), 1e-3));
		}
	CHECK(worst < 1e-6, "d F / d n off by %g (relative)", worst);
	CHECK_NEAR(fresnel_dlog(0.7, 1.0), 0, 0, "n = 1: F = 0, no scale");
	/* normal incidence: F = ((n-1)/(n+1))^2, d log F / dn =
	 * 4 / ((n - 1)(n + 1)) */
	CHECK_NEAR(fresnel_dlog(1, 1.5), 4 / (0.5 * 2.5), 1e-9,
		   "normal incidence");
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
static double pdf_integral(const struct glint_model *m, const double *p,
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
			sum += m->bxdf->pdf(p, wo,
					    v3(r * cos(ph), r * sin(ph), z)) *
			       dz * (2 * M_PI / np);
		}
	}
	return sum;
}

/* sample() draws from pdf() (chi-square over 20 x 16 bins of cos and
 * phi), pdf() integrates to the accepted fraction, and sample() returns
 * pdf()'s value. */
static void check_sampling(const struct glint_model *m, const double *p)
{
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
			double pdf = m->bxdf->sample(p, wo, u, &wi);
			if (pdf == 0) {
				rejected++;
				continue;
			}
			if (fabs(pdf - m->bxdf->pdf(p, wo, wi)) > 1e-9 * pdf)
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
						acc += m->bxdf->pdf(
							p, wo,
							v3(r * cos(ph),
							   r * sin(ph), z));
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
		      "%s, theta_o %g: pdf integral %g, accepted fraction %g",
		      m->name, angles[k], integral, 1 - (double)rejected / ns);
		CHECK(mismatch == 0, "%s: %d sample pdfs differ from pdf()",
		      m->name, mismatch);
		CHECK(pv > 1e-3, "%s, theta_o %g: chi-square p = %g (dof %d)",
		      m->name, angles[k], pv, dof);
	}
}

/* Every BRDF model, at parameters that give each lobe weight. */
static const struct {
	const struct glint_model *m;
	double p[GLINT_MAX_PARAMS];
} sampled[] = {
	{ &glint_model_lambert, { 0.3, 0.2, 0.1 } },
	{ &glint_model_torrance_sparrow,
	  { 0.3, 0.2, 0.1, 0.5, 0.5, 0.5, 0.2, 1.5 } },
	{ &glint_model_ts_constant_fresnel,
	  { 0.3, 0.2, 0.1, 0.05, 0.05, 0.05, 0.1 } },
	{ &glint_model_ggx, { 0.3, 0.2, 0.1, 0.5, 0.5, 0.5, 0.2, 1.5 } },
	{ &glint_model_oren_nayar,
	  { 0.3, 0.2, 0.1, 0.5, 0.5, 0.5, 0.2, 1.5, 0.6 } },
	{ &glint_model_two_lobe,
	  { 0.3, 0.2, 0.1, 0.5, 0.5, 0.5, 0.12, 1.5, 0.3, 0.3, 0.3, 0.4 } },
};
#define NSAMPLED (int)(sizeof(sampled) / sizeof(sampled[0]))

static void test_pdf_and_sampling(void)
{
	for (int k = 0; k < NSAMPLED; k++)
		check_sampling(sampled[k].m, sampled[k].p);
}

static struct vec3 random_dir(uint64_t s, int k)
{
	double z = glint_u01(glint_hash3(s, k, 11));
	double ph = 2 * M_PI * glint_u01(glint_hash3(s, k, 12));
	double r = sqrt(fmax(0, 1 - z * z));
	return v3(r * cos(ph), r * sin(ph), z);
}

/* f(o, i) = f(i, o), and f is the sum of albedo_j times lobe j. */
static void test_reciprocity_and_lobes(void)
{
	for (int k = 0; k < NSAMPLED; k++) {
		const struct glint_model *m = sampled[k].m;
		const double *p = sampled[k].p;
		int asym = 0, unlike = 0;
		for (int s = 0; s < 5000; s++) {
			struct vec3 o = random_dir(s, 1), i = random_dir(s, 2);
			double f[3], g[3], b[GLINT_MAX_PARAMS];
			m->bxdf->eval(p, o, i, f);
			m->bxdf->eval(p, i, o, g);
			m->bxdf->eval_lobes(p, o, i, b);
			for (int c = 0; c < 3; c++) {
				double sum = 0;
				for (int j = 0; j < m->bxdf->nlobes; j++)
					sum += p[m->lobes->param[j] + c] * b[j];
				asym += fabs(f[c] - g[c]) > 1e-9 * f[c];
				unlike += fabs(f[c] - sum) > 1e-12 * f[c];
			}
		}
		CHECK(asym == 0, "%s: %d values with f(o, i) != f(i, o)",
		      m->name, asym);
		CHECK(unlike == 0, "%s: %d values differ from the lobes' sum",
		      m->name, unlike);
	}
}

/* Lobe j's value at normal incidence, the light theta from the normal
 * (the mirror direction). */
static double lobe_at(const struct glint_model *m, const double *p, int j,
		      double theta)
{
	double b[GLINT_MAX_PARAMS];
	m->bxdf->eval_lobes(p, v3(0, 0, 1), v3(sin(theta), 0, cos(theta)), b);
	return b[j];
}

/* The angle from the mirror direction where lobe j falls to half. */
static double half_max(const struct glint_model *m, const double *p, int j)
{
	double peak = lobe_at(m, p, j, 0), lo = 0, hi = 1;
	for (int it = 0; it < 60; it++) {
		double mid = (lo + hi) / 2;
		if (lobe_at(m, p, j, mid) > peak / 2)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

/*
 * glint_lobe_width() is the standard deviation of the Gaussian with the lobe's
 * half-maximum (a Gaussian halves at 1.1774 sigma), and glint_lobe_widen()
 * convolves a Gaussian of s into it: the widened lobe's width is
 * sqrt(width^2 + s^2) and its half-maximum that of the Gaussian of that
 * width (the footprint integral of shade_cache.c relies on both), for
 * near-mirror lobes (roughness 0.003 to 0.027: small angles).
 */
static void test_lobe_width(void)
{
	int tested = 0;
	for (int k = 0; k < NSAMPLED; k++) {
		const struct glint_model *m = sampled[k].m;
		if (!m->lobes->microfacet)
			continue;
		for (int j = 0; j < m->bxdf->nlobes; j++)
			for (double r = 0.003; r < 0.03; r *= 3) {
				double p[GLINT_MAX_PARAMS],
					pw[GLINT_MAX_PARAMS];
				memcpy(p, sampled[k].p, sizeof(p));
				if (m->lobes->roughness_param >= 0)
					p[m->lobes->roughness_param] = r;
				if (m == &glint_model_two_lobe)
					p[11] = 2 * r;
				double w = glint_lobe_width(m, p, j);
				if (!(w > 0))
					continue;
				tested++;
				double h = half_max(m, p, j);
				CHECK(fabs(h / (1.1774 * w) - 1) < 0.05,
				      "%s lobe %d at %g: half-max %.5f, width "
				      "%.5f (%.3f)",
				      m->name, j, r, h, w, h / (1.1774 * w));
				memcpy(pw, p, sizeof(pw));
				glint_lobe_widen(m, pw, j, 2 * w);
				double ww = glint_lobe_width(m, pw, j);
				CHECK_NEAR(ww, sqrt(5) * w, 1e-9 * w,
					   "widened width");
				double hw = half_max(m, pw, j);
				CHECK(fabs(hw / (1.1774 * ww) - 1) < 0.05,
				      "%s lobe %d widened: half-max %.5f, "
				      "width %.5f",
				      m->name, j, hw, ww);
			}
	}
	CHECK(tested >= 6 * 3, "%d lobes tested", tested);
}

/* The fitter's shared-work lobe ops agree with eval_lobes, pdf_lobe and
 * sample_lobe, and eval_lobe with eval_lobes, at roughnesses from
 * near-mirror to rough. */
/* Draw s's roughness, where m has one: 0.004, 0.05, 0.4 in turn. */
static void set_roughness(const struct glint_model *m, double *p, int s)
{
	if (m->lobes->roughness_param >= 0)
		p[m->lobes->roughness_param] = (s % 3 == 0)   ? 0.004
					       : (s % 3 == 1) ? 0.05
							      : 0.4;
}

static void test_lobe_value_ops(void)
{
	int alone = 0;

	for (int k = 0; k < NSAMPLED; k++) {
		const struct glint_model *m = sampled[k].m;
		double p[GLINT_MAX_PARAMS];
		int bad = 0, checked = 0, geom = 0;
		if (!m->bxdf->nlobes)
			continue;
		memcpy(p, sampled[k].p, sizeof(double) * (size_t)m->nparams);
		for (int s = 0; s < 6000; s++) {
			set_roughness(m, p, s);
			struct vec3 o = random_dir(s, 7), i = random_dir(s, 8);
			if (s % 7 == 0)
				i.z = -i.z; /* below the surface */
			double u[2] = { glint_u01(glint_hash3(s, 9, 1)),
					glint_u01(glint_hash3(s, 9, 2)) };
			for (int j = 0; j < m->bxdf->nlobes; j++) {
				double b[GLINT_MAX_PARAMS], pdf, bj, wb, wpdf;
				struct vec3 wi, wj;
				m->bxdf->eval_lobes(p, o, i, b);
				/* one lobe alone: the same value, bit for
				 * bit (the reference renderer's) */
				if (m->bxdf->eval_lobe) {
					bj = m->bxdf->eval_lobe(p, j, o, i);
					bad += memcmp(&bj, &b[j], sizeof(bj)) !=
					       0;
					alone++;
				}
				wpdf = m->bxdf->pdf_lobe(p, j, o, i);
				/* the ior's d log b_j shared with the value:
				 * factor_dlog's */
				double dl = 0, fdl = 0, *dlp = NULL;
				if (m->lobes->factor_dlog) {
					dlp = &dl;
					fdl = m->lobes->factor_dlog(p, j, o, i);
				}
				bj = glint_lobe_value_pdf(m, p, j, o, i, &pdf,
							  dlp);
				bad += fabs(bj - b[j]) > 1e-9 * fabs(b[j]) ||
				       fabs(pdf - wpdf) > 1e-9 * wpdf;
				bad += bj > 0 &&
				       fabs(dl - fdl) >
					       1e-9 * fabs(fdl) + 1e-12;
				if (m->lobes->geometry && m->lobes->varies[j]) {
					/* Kept in floats: tan^2 to 2^-24,
					 * so D to (tan^2 / m^2) 2^-24. */
					float g[4];
					m->lobes->geometry(o, i, g);
					bj = m->lobes->from_geometry(p, j, g,
								     &pdf, dlp);
					/* o.h kept in a float */
					bad += bj > 0 &&
					       fabs(dl - fdl) >
						       1e-6 * fabs(fdl) + 1e-9;
					double mm =
						p[m->lobes->roughness_param];
					double tol = 1e-6 +
						     1.2e-7 * g[0] / (mm * mm);
					/* (and subnormals aside) */
					bad += fabs(bj - b[j]) >
						       tol * fabs(b[j]) +
							       1e-300 ||
					       fabs(pdf - wpdf) >
						       tol * wpdf + 1e-300;
					geom += b[j] > 0;
				}
				double ps =
					m->bxdf->sample_lobe(p, j, o, u, &wi);
				wb = 0;
				if (ps > 0) {
					m->bxdf->eval_lobes(p, o, wi, b);
					wb = b[j];
				}
				double pf = glint_lobe_sample_value(
					m, p, j, o, u, &wj, &bj, dlp);
				bad += fabs(pf - ps) > 1e-8 * ps ||
				       fabs(bj - wb) > 1e-8 * wb ||
				       (ps > 0 && v3_dot(wi, wj) < 1 - 1e-12);
				if (dlp && bj > 0 && m->lobes->varies[j]) {
					fdl = m->lobes->factor_dlog(p, j, o,
								    wj);
					bad += fabs(dl - fdl) >
					       1e-8 * fabs(fdl) + 1e-12;
				}
				checked += ps > 0 && wb > 0;
			}
		}
		CHECK(bad == 0, "%s: %d lobe values or pdfs differ", m->name,
		      bad);
		CHECK(checked > 1000, "%s: %d sampled lobes checked", m->name,
		      checked);
		CHECK(!m->lobes->geometry || geom > 1000,
		      "%s: %d lobes from geometry checked", m->name, geom);
	}
	CHECK(alone >= 3 * 2 * 6000, "%d lobes alone checked", alone);
}

/* The lobes at many directions in one call (glint_lobe_values(): the
 * vectorised loops of models that have them, else value_pdf per
 * direction) against value_pdf one at a time; and the Beckmann loop
 * beyond the models' bounds (ior 1, below 1, none) and with wo below the
 * surface. */
static void test_lobe_values_batch(void)
{
	enum { N = 257 }; /* odd: the vector loops' remainder too */
	double x[N], y[N], z[N], b[N], dl[N], u0[N], u1[N], pdf[N];
	struct vec3 wos[N];
	int bad = 0, nonzero = 0, sbad = 0, snonzero = 0;

	for (int k = 0; k < NSAMPLED; k++) {
		const struct glint_model *m = sampled[k].m;
		double p[GLINT_MAX_PARAMS];
		if (!m->bxdf->nlobes)
			continue;
		memcpy(p, sampled[k].p, sizeof(double) * (size_t)m->nparams);
		for (int s = 0; s < 30; s++) {
			set_roughness(m, p, s);
			struct vec3 o = random_dir(s, 17);
			for (int i = 0; i < N; i++) {
				struct vec3 w = random_dir(s * N + i, 18);
				if (i % 7 == 0)
					w.z = -w.z;
				if (i % 5 == 0) /* near the mirror direction */
					w = v3_norm(v3_add(v3(-o.x, -o.y, o.z),
							   v3_scale(w, 0.02)));
				x[i] = w.x, y[i] = w.y, z[i] = w.z;
			}
			int d = m->lobes->factor_dlog != NULL;
			for (int j = 0; j < m->bxdf->nlobes; j++) {
				glint_lobe_values(m, p, j, o, N, x, y, z, b,
						  d ? dl : NULL);
				for (int i = 0; i < N; i++) {
					double rd = 0;
					double r = glint_lobe_value_pdf(
						m, p, j, o,
						v3(x[i], y[i], z[i]), NULL,
						d ? &rd : NULL);
					bad += !(fabs(b[i] - r) <=
						 1e-12 * fabs(r) + 1e-300);
					bad += d && !(fabs(dl[i] - rd) <=
						      1e-10 * fabs(rd) + 1e-12);
					nonzero += r > 0;
				}
			}
			/* Sampling in a batch (glint_lobe_sample_values()),
			 * each sample for its own wo (one in 9 below the
			 * surface), against one sample at a time: the same
			 * directions, values, pdfs and dlog (the batch's sin
			 * and cos round a quarter-turn tie the other way:
			 * within 1e-15). */
			for (int i = 0; i < N; i++) {
				wos[i] = random_dir((uint64_t)s * N + i, 21);
				if (i % 9 == 4)
					wos[i].z = -wos[i].z;
				u0[i] = glint_u01(glint_hash3(s, i, 1));
				u1[i] = i % 16 == 0 ? (i / 16 % 8) / 8.0
						    : glint_u01(glint_hash3(
							      s, i, 2));
			}
			u0[0] = 0;
			for (int j = 0; j < m->bxdf->nlobes; j++) {
				glint_lobe_sample_values(m, p, j, N, wos, u0,
							 u1, x, y, z, pdf, b,
							 d ? dl : NULL);
				for (int i = 0; i < N; i++) {
					double u[2] = { u0[i], u1[i] }, rb,
					       rd = 0;
					struct vec3 wi;
					double rp = glint_lobe_sample_value(
						m, p, j, wos[i], u, &wi, &rb,
						d ? &rd : NULL);
					sbad += !(fabs(pdf[i] - rp) <=
						  1e-12 * rp + 1e-300) ||
						!(fabs(b[i] - rb) <=
						  1e-12 * rb + 1e-300);
					if (!(rp > 0 && rb > 0))
						continue;
					sbad += fabs(x[i] - wi.x) > 1e-14 ||
						fabs(y[i] - wi.y) > 1e-14 ||
						fabs(z[i] - wi.z) > 1e-14;
					sbad += d &&
						!(fabs(dl[i] - rd) <=
						  1e-10 * fabs(rd) + 1e-12);
					snonzero++;
				}
			}
		}
	}
	CHECK(bad == 0, "%d batched lobe values differ", bad);
	CHECK(nonzero > 10000, "%d nonzero lobe values checked", nonzero);
	CHECK(sbad == 0, "%d batched lobe samples differ", sbad);
	CHECK(snonzero > 10000, "%d lobe samples checked", snonzero);

	/* glint_beckmann_lobe_n() itself: ior 1, 0.8 (total internal
	 * reflection) and 0 (no Fresnel), wo below the surface */
	static const double iors[] = { 1, 0.8, 0, 1.5 };
	bad = 0;
	for (size_t q = 0; q < sizeof(iors) / sizeof(iors[0]); q++)
		for (int s = 0; s < 20; s++) {
			struct vec3 o = random_dir(s, 19);
			if (s == 19)
				o.z = -o.z;
			for (int i = 0; i < N; i++) {
				struct vec3 w = random_dir(s * N + i, 20);
				x[i] = w.x, y[i] = w.y, z[i] = w.z;
			}
			glint_beckmann_lobe_n(0.2, iors[q], o, N, x, y, z, b,
					      dl);
			for (int i = 0; i < N; i++) {
				double rd = 0,
				       r = glint_beckmann_lobe_pdf(
					       0.2, iors[q], o,
					       v3(x[i], y[i], z[i]), NULL, &rd);
				bad += !(fabs(b[i] - r) <=
					 1e-12 * fabs(r) + 1e-300) ||
				       !(fabs(dl[i] - rd) <=
					 1e-10 * fabs(rd) + 1e-12);
				bad += s == 19 && (b[i] != 0 || dl[i] != 0);
			}
		}
	CHECK(bad == 0, "%d Beckmann batch values differ at the edges", bad);
}

/* Without Fresnel variation: the full model's specular divided by F. */
static void test_constant_fresnel(void)
{
	const struct glint_model *nf = &glint_model_ts_constant_fresnel;
	const struct glint_model *ts = &glint_model_torrance_sparrow;
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
		double pdf = nf->bxdf->sample(p, wo, u, &wi);
		if (pdf == 0)
			continue;
		mismatch += fabs(pdf - nf->bxdf->pdf(p, wo, wi)) > 1e-9 * pdf;
		double fn[3], ft[3];
		nf->bxdf->eval(p, wo, wi, fn);
		ts->bxdf->eval(p, wo, wi, ft);
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
	const struct glint_model *m = &glint_model_lambert;
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
	const struct glint_model *m = &glint_model_torrance_sparrow;
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

/* GGX: D cos integrates to 1 (tan substitution: the tail is long). */
static void test_ggx_normalised(void)
{
	double as[4] = { 0.01, 0.05, 0.2, 0.6 };
	for (int k = 0; k < 4; k++) {
		/* th = atan(a x), x in [0, inf) as x = v / (1 - v). */
		int n = 400000;
		double sum = 0, a = as[k];
		for (int j = 0; j < n; j++) {
			double v = (j + 0.5) / n, x = v / (1 - v);
			double dx = 1 / ((1 - v) * (1 - v)) / n;
			double th = atan(a * x), dth = a / (1 + a * a * x * x);
			sum += glint_ggx_d(cos(th), a) * cos(th) * sin(th) *
			       dth * dx;
		}
		sum *= 2 * M_PI;
		CHECK_NEAR(sum, 1.0, 1e-4, "integral of GGX D cos");
	}
}

/*
 * Smith masking is the one that conserves projected area: for every view
 * o, integral of G1(o) max(0, o.h) D(h) dh = cos(theta_o) (Heitz 2014,
 * eq. 8), G1 = 1 / (1 + Lambda(o)).  Midpoint rule over (theta_h, phi_h).
 */
static void test_ggx_smith_projected_area(void)
{
	double as[3] = { 0.1, 0.3, 0.8 }, ths[4] = { 0, 30, 60, 80 };
	for (int k = 0; k < 3; k++)
		for (int t = 0; t < 4; t++) {
			double a = as[k];
			struct vec3 o = dir_at(ths[t]);
			int nt = 4000, np = 256;
			double sum = 0;
			for (int j = 0; j < nt; j++) {
				double th = (j + 0.5) * (M_PI / 2) / nt;
				double ct = cos(th), st = sin(th);
				for (int i = 0; i < np; i++) {
					double ph = (i + 0.5) * 2 * M_PI / np;
					struct vec3 h = v3(st * cos(ph),
							   st * sin(ph), ct);
					sum += fmax(0, v3_dot(o, h)) *
					       glint_ggx_d(ct, a) * st;
				}
			}
			sum *= (M_PI / 2 / nt) * (2 * M_PI / np);
			double g1 = 1 / (1 + glint_ggx_lambda(o.z, a));
			char what[80];
			snprintf(what, sizeof(what),
				 "G1 x projected area = cos, a %g, theta %g", a,
				 ths[t]);
			CHECK_NEAR(g1 * sum, o.z, 2e-3 * o.z + 1e-4, what);
		}
}

/* Oren-Nayar: Lambert at sigma 0; viewed head-on, its albedo is A. */
static void test_oren_nayar(void)
{
	const struct glint_model *m = &glint_model_oren_nayar;
	double sig[4] = { 0, 0.2, 0.5, 1.0 };
	for (int k = 0; k < 4; k++) {
		double s2 = sig[k] * sig[k], A = 1 - s2 / (2 * (s2 + 0.33));
		double p[9] = { 1, 1, 1, 0, 0, 0, 0.1, 1.5, sig[k] };
		double a[3], worst = 0;
		albedo_quadrature(m, p, dir_at(0), a);
		CHECK_NEAR(a[0], A, 2e-3, "albedo at normal view = A");
		for (int t = 0; t <= 85; t += 5) {
			albedo_quadrature(m, p, dir_at(t), a);
			worst = fmax(worst, a[0]);
		}
		/* The qualitative model is not energy conserving at
		 * grazing view; it stays within 3 % of it here. */
		CHECK(worst <= 1.03, "sigma %g: albedo %g > 1.03", sig[k],
		      worst);
		fprintf(stderr,
			"  oren-nayar sigma %.1f: largest albedo %.4f\n",
			sig[k], worst);
	}
	/* sigma 0 with a specular lobe is torrance-sparrow exactly. */
	double q[9] = { 0.3, 0.2, 0.1, 0.5, 0.4, 0.3, 0.2, 1.5, 0 };
	int bad = 0;
	for (int s = 0; s < 2000; s++) {
		struct vec3 o = random_dir(s, 3), i = random_dir(s, 4);
		double f[3], g[3];
		m->bxdf->eval(q, o, i, f);
		glint_model_torrance_sparrow.bxdf->eval(q, o, i, g);
		for (int c = 0; c < 3; c++)
			bad += fabs(f[c] - g[c]) > 1e-12 * g[c];
	}
	CHECK(bad == 0, "%d values differ from torrance-sparrow's", bad);
	/* Rough diffuse is flatter: brighter back toward the light than
	 * Lambert, darker across it. */
	double r[9] = { 1, 1, 1, 0, 0, 0, 0.1, 1.5, 0.5 }, back[3], across[3];
	m->bxdf->eval(r, dir_at(60), dir_at(60), back);
	m->bxdf->eval(r, dir_at(60), v3(-sin(M_PI / 3), 0, 0.5), across);
	CHECK(back[0] > 1 / M_PI && across[0] < 1 / M_PI,
	      "retro %g, forward %g against Lambert %g", back[0], across[0],
	      1 / M_PI);
}

/* The white furnace for the new lobes: never more than 1. */
static void test_new_models_energy(void)
{
	double rough[3] = { 0.05, 0.2, 0.6 };
	double worst = 0;
	for (int r = 0; r < 3; r++)
		for (int t = 0; t <= 85; t += 17) {
			double g[8] = { 0, 0, 0, 1, 1, 1, rough[r], 5 };
			double h[8] = { 0.5, 0.5, 0.5,	    0.5,
					0.5, 0.5, rough[r], 5 };
			double two[12] = { 0.4,	     0.4, 0.4, 0.3, 0.3, 0.3,
					   rough[r], 5,	  0.3, 0.3, 0.3, 0.5 };
			double a[3];
			albedo_quadrature(&glint_model_ggx, g, dir_at(t), a);
			worst = fmax(worst, a[0]);
			CHECK(a[0] <= 1.0, "ggx: albedo %g (a %g, theta %d)",
			      a[0], rough[r], t);
			albedo_quadrature(&glint_model_ggx, h, dir_at(t), a);
			CHECK(a[0] <= 1.0, "ggx kd=ks=0.5: albedo %g", a[0]);
			albedo_quadrature(&glint_model_two_lobe, two, dir_at(t),
					  a);
			CHECK(a[0] <= 1.0, "two-lobe: albedo %g (theta %d)",
			      a[0], t);
		}
	fprintf(stderr, "  largest GGX specular albedo seen: %.4f\n", worst);
	/* With F = 1 (ior 5 is near it) and a smooth lobe nearly all the
	 * light comes back: the lobe is normalised. */
	double s[8] = { 0, 0, 0, 1, 1, 1, 0.05, 5 }, a[3];
	albedo_quadrature(&glint_model_ggx, s, dir_at(20), a);
	double F = glint_fresnel_dielectric(cos(20 * M_PI / 180), 5);
	CHECK(a[0] > 0.97 * F && a[0] <= 1.0 * F + 0.01,
	      "smooth GGX albedo %g against F %g", a[0], F);
}

/* A two-lobe surface with no second lobe is torrance-sparrow. */
static void test_two_lobe(void)
{
	double q[12] = { 0.3, 0.2, 0.1, 0.5, 0.4, 0.3, 0.2, 1.5, 0, 0, 0, 0.5 };
	double r[12] = { 0, 0, 0, 0, 0, 0, 0.7, 1.5, 0.5, 0.4, 0.3, 0.2 };
	int bad = 0, swapped = 0;
	for (int s = 0; s < 2000; s++) {
		struct vec3 o = random_dir(s, 5), i = random_dir(s, 6);
		double f[3], g[3], t[8] = { 0, 0, 0, 0.5, 0.4, 0.3, 0.2, 1.5 };
		glint_model_two_lobe.bxdf->eval(q, o, i, f);
		glint_model_torrance_sparrow.bxdf->eval(q, o, i, g);
		for (int c = 0; c < 3; c++)
			bad += fabs(f[c] - g[c]) > 1e-12 * g[c];
		/* The lobes are interchangeable: lobe 2 alone is lobe 1. */
		glint_model_two_lobe.bxdf->eval(r, o, i, f);
		glint_model_torrance_sparrow.bxdf->eval(t, o, i, g);
		for (int c = 0; c < 3; c++)
			swapped += fabs(f[c] - g[c]) > 1e-12 * g[c];
	}
	CHECK(bad == 0, "%d values differ from torrance-sparrow's", bad);
	CHECK(swapped == 0, "%d second-lobe values differ", swapped);
}

/* The new models' own keys read and write back; unknown keys refused. */
static void test_new_models_json(void)
{
	const struct glint_model *m;
	double p[GLINT_MAX_PARAMS];
	json_error_t e;
	json_t *o = json_loads("{\"model\": \"two-lobe\", \"specular2\":"
			       " [0.1, 0.2, 0.3], \"roughness2\": 0.4}",
			       0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) == 0, "%s",
	      glint_error_msg());
	CHECK(m == &glint_model_two_lobe && p[9] == 0.2 && p[11] == 0.4 &&
		      p[6] == 0.075,
	      "values %g %g %g", p[9], p[11], p[6]);
	json_t *back = glint_material_to_json(m, p);
	CHECK(json_array_size(json_object_get(back, "specular2")) == 3 &&
		      json_real_value(json_object_get(back, "roughness2")) ==
			      0.4,
	      "to_json lost the second lobe");
	json_decref(back);
	json_decref(o);
	o = json_loads("{\"model\": \"oren-nayar\", \"diffuse_roughness\":"
		       " 1.5}",
		       0, &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "sigma 1.5 accepted");
	CHECK_MSG(glint_error_msg(), "diffuse_roughness");
	json_decref(o);
	o = json_loads("{\"model\": \"ggx\", \"diffuse_roughness\": 0.2}", 0,
		       &e);
	CHECK(glint_material_from_json("m.json", "", o, &m, p) < 0,
	      "ggx took diffuse_roughness");
	json_decref(o);
}

static void test_material_json(void)
{
	const struct glint_model *m;
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
	const struct glint_model *m;
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

/*
 * Every model's BxDF (fit/brdf/bxdf.h) is its lobes' sum, lobe by lobe
 * through the BxDF's albedo hook, and a microfacet lobe is its
 * distribution's (microfacet.h) at the lobe's width parameter; the
 * transparent sphere has neither BRDF nor lobes.
 */
static void test_bxdf_interface(void)
{
	const char *const *names = glint_model_list();
	int opaque = 0, microfacet = 0;

	for (int k = 0; names[k]; k++) {
		const struct glint_model *m = glint_model_find(names[k]);
		double p[GLINT_MAX_PARAMS];
		for (int i = 0; i < m->nparams; i++)
			p[i] = m->params[i].def;
		if (glint_model_is_transparent(m)) {
			CHECK(m->bxdf == NULL && m->lobes == NULL &&
				      glint_model_roughness_param(m) == -1,
			      "%s: transparent with a BRDF", m->name);
			continue;
		}
		opaque++;
		struct glint_bxdf bx = glint_model_bxdf(m, p);
		CHECK(bx.ops->flags & GLINT_BXDF_LOBES, "%s: no lobes",
		      m->name);
		for (int d = 0; d < 50; d++) {
			double u[4];
			for (int i = 0; i < 4; i++)
				u[i] = glint_u01(glint_hash3(k, d, i));
			struct vec3 wo, wi;
			glint_sample_cosine(u, &wo);
			glint_sample_cosine(u + 2, &wi);
			double f[3], b[GLINT_MAX_PARAMS], sum[3] = { 0, 0, 0 };
			glint_bxdf_eval(&bx, wo, wi, f);
			bx.ops->eval_lobes(bx.self, wo, wi, b);
			for (int j = 0; j < bx.ops->nlobes; j++) {
				const double *a = bx.ops->albedo(bx.self, j);
				CHECK(a == p + m->lobes->param[j],
				      "%s: lobe %d's albedo", m->name, j);
				for (int c = 0; c < 3; c++)
					sum[c] += a[c] * b[j];
				int w = m->lobes->microfacet
						? m->lobes->width_param[j]
						: -1;
				if (w < 0 ||
				    m == &glint_model_ts_constant_fresnel)
					continue;
				double ior =
					p[7]; /* every microfacet model's */
				double l = m->lobes->microfacet->lobe(p[w], ior,
								      wo, wi);
				CHECK(fabs(b[j] - l) <= 1e-12 * fabs(l),
				      "%s lobe %d: %g against its "
				      "distribution's %g",
				      m->name, j, b[j], l);
				microfacet += d == 0;
			}
			for (int c = 0; c < 3; c++)
				CHECK(fabs(f[c] - sum[c]) <=
					      1e-12 * fabs(sum[c]),
				      "%s: f %g against its lobes' %g", m->name,
				      f[c], sum[c]);
		}
	}
	CHECK(opaque >= 6 && microfacet >= 5, "%d opaque models, %d lobes",
	      opaque, microfacet);
	CHECK(glint_model_ggx.lobes->microfacet == &glint_microfacet_ggx &&
		      glint_model_torrance_sparrow.lobes->microfacet ==
			      &glint_microfacet_beckmann,
	      "the models name their distributions");
}

/* Measured tables as BxDFs hold their own state: two at once each read
 * their own table. */
static void test_tabulated_instances(void)
{
	struct glint_ashikhmin_shirley red = { 50, { 0.6, 0.1, 0.1 }, 0.05 };
	struct glint_ashikhmin_shirley blue = { 500, { 0.1, 0.1, 0.6 }, 0.2 };
	struct glint_brdf_table *tr = NULL, *tb = NULL;
	struct glint_tabulated a, b;

	CHECK(glint_brdf_table_from(glint_ashikhmin_shirley_eval, &red, &tr) ==
			      0 &&
		      glint_brdf_table_from(glint_ashikhmin_shirley_eval, &blue,
					    &tb) == 0,
	      "tables: %s", glint_error_msg());
	if (!tr || !tb)
		goto out;
	struct glint_bxdf br = glint_tabulated_bxdf(&a, tr, 0.1);
	struct glint_bxdf bb = glint_tabulated_bxdf(&b, tb, 0.05);
	struct vec3 wo = v3(0.3, 0, sqrt(1 - 0.09));
	struct vec3 wi = v3(-0.25, 0.1, sqrt(1 - 0.0725));
	double fr[3], fb[3], tr3[3], tb3[3];
	glint_bxdf_eval(&br, wo, wi, fr);
	glint_bxdf_eval(&bb, wo, wi, fb);
	glint_brdf_table_eval(tr, wo, wi, tr3);
	glint_brdf_table_eval(tb, wo, wi, tb3);
	for (int c = 0; c < 3; c++)
		CHECK(fr[c] == tr3[c] && fb[c] == tb3[c],
		      "channel %d: %g %g against %g %g", c, fr[c], fb[c],
		      tr3[c], tb3[c]);
	CHECK(fr[0] > fr[2] && fb[2] > fb[0], "each its own colour");
	for (int j = 0; j < 3; j++) {
		const double *al = br.ops->albedo(br.self, j);
		CHECK(al[j] == 1 && al[(j + 1) % 3] == 0 &&
			      al[(j + 2) % 3] == 0,
		      "lobe %d's albedo", j);
	}
	CHECK(glint_bxdf_pdf(&br, wo, wi) != glint_bxdf_pdf(&bb, wo, wi),
	      "each its own proposal");
out:
	glint_brdf_table_free(tr);
	glint_brdf_table_free(tb);
}

int main(void)
{
	RUN(test_beckmann_normalised);
	RUN(test_fresnel);
	RUN(test_vcavity);
	RUN(test_pdf_and_sampling);
	RUN(test_reciprocity_and_lobes);
	RUN(test_lobe_value_ops);
	RUN(test_lobe_values_batch);
	RUN(test_lobe_width);
	RUN(test_lambert);
	RUN(test_constant_fresnel);
	RUN(test_ts_energy);
	RUN(test_ggx_normalised);
	RUN(test_ggx_smith_projected_area);
	RUN(test_oren_nayar);
	RUN(test_new_models_energy);
	RUN(test_two_lobe);
	RUN(test_new_models_json);
	RUN(test_material_json);
	RUN(test_paper_table);
	RUN(test_bxdf_interface);
	RUN(test_tabulated_instances);
	return test_result();
}
