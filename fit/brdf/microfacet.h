/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_BRDF_MICROFACET_H
#define GLINT_FIT_BRDF_MICROFACET_H

/*
 * Pieces of the microfacet and rough-diffuse models, exposed for tests.
 *
 * Errors: none (pure functions).  Threads: re-entrant; the descriptors are
 * static.  Who frees: nothing.
 */

#include "core/optics.h"
#include "core/vec.h"

/*
 * Beckmann distribution of microfacet normals with RMS slope m:
 * D(h) = exp(-tan^2(t) / m^2) / (pi m^2 cos^4(t)), t the angle between h
 * and the normal; integral of D(h) cos(t) over the hemisphere is 1.
 */
double glint_beckmann_d(double cos_h, double m);

/*
 * Torrance-Sparrow V-cavity shadowing and masking:
 * G = min(1, 2 (n.h)(n.o) / (o.h), 2 (n.h)(n.i) / (o.h)).
 */
double glint_vcavity_g(double nh, double no, double ni, double oh);

/* F at cosine c for index ior, or 1 when ior <= 0 (constant Fresnel). */
double glint_fresnel_or_one(double c, double ior);
/* d log F / d ior for the lobes' Fresnel factor at cos = o.h, h the half
 * vector of wo and wi (glint_fresnel_dielectric_dlog()): how the
 * lobe's value scales with ior at those directions. */
double glint_fresnel_half_dlog(double ior, struct vec3 wo, struct vec3 wi);

/*
 * A microfacet lobe without its albedo, D G F / (4 (n.i)(n.o)), 0 below
 * the surface; ior <= 0 for F = 1.  Beckmann D with RMS slope m and the
 * V-cavity G (Torrance-Sparrow), or GGX D with width a and its
 * height-correlated Smith G.
 */
double glint_beckmann_lobe(double m, double ior, struct vec3 wo,
			   struct vec3 wi);
double glint_ggx_lobe(double a, double ior, struct vec3 wo, struct vec3 wi);

/*
 * Reflect wo about a microfacet normal drawn with density D(h) cos(h) from
 * two uniforms (smooth in the roughness for fixed u: common random numbers
 * for the fitter); wi may come out below the surface.  The _pdf functions
 * give its solid-angle density at wi, D(h) (n.h) / (4 (o.h)).
 */
void glint_beckmann_sample(double m, struct vec3 wo, const double u[2],
			   struct vec3 *wi);
double glint_beckmann_pdf(double m, struct vec3 wo, struct vec3 wi);
void glint_ggx_sample(double a, struct vec3 wo, const double u[2],
		      struct vec3 *wi);
double glint_ggx_pdf(double a, struct vec3 wo, struct vec3 wi);

/*
 * The Beckmann lobe's value and its sampling pdf together, sharing the
 * half vector and D (the fitter's inner loop): _lobe_pdf at wi (both 0
 * below the surface; pdf may be NULL), _sample_lobe draws wi as
 * glint_beckmann_sample() does and returns its pdf, D from the uniform
 * without an exp (0 and *lobe = 0 when wi falls below the surface).
 * dlog (may be NULL) gets d log lobe / d ior (glint_fresnel_half_dlog()).
 */
double glint_beckmann_lobe_pdf(double m, double ior, struct vec3 wo,
			       struct vec3 wi, double *pdf, double *dlog);
double glint_beckmann_sample_lobe(double m, double ior, struct vec3 wo,
				  const double u[2], struct vec3 *wi,
				  double *lobe, double *dlog);
/*
 * _lobe_pdf's lobe (and d log lobe / d ior into dlog[], unless NULL) at n
 * directions wi = (x[k], y[k], z[k]) for one wo, without the pdf: a loop
 * without branches, that the compiler vectorises (the hot texels'
 * quadrature, ~100 fixed directions a hit).  Within 1e-12 of _lobe_pdf's
 * values (its exp is glint_fast_exp_neg()); 0 where wo or wi is below
 * the surface.
 */
void glint_beckmann_lobe_n(double m, double ior, struct vec3 wo, int n,
			   const double *restrict x, const double *restrict y,
			   const double *restrict z, double *restrict b,
			   double *restrict dlog);
/*
 * _sample_lobe at n uniform pairs (u0[k], u1[k]), each for its own wo[k]
 * (the hits of a pixel's footprint differ): the directions into x, y, z,
 * the lobe into lobe[], d log lobe / d ior into dlog[] (unless NULL), the
 * pdfs into pdf[] (pdf and lobe 0 where wo or the direction is below the
 * surface); one loop without branches that the compiler vectorises (the
 * lobe samples, 8 at a time).
 */
void glint_beckmann_sample_lobe_n(double m, double ior, int n,
				  const struct vec3 *restrict wo,
				  const double *restrict u0,
				  const double *restrict u1, double *restrict x,
				  double *restrict y, double *restrict z,
				  double *restrict pdf, double *restrict lobe,
				  double *restrict dlog);
/*
 * The same at a fixed wo, wi, in two steps: what depends on neither m nor
 * ior (tan^2 of the half vector, o.h, G / (4 (n.i)(n.o) pi cos^4) and
 * (n.h) / (4 (o.h) pi cos^4); all 0 below the surface), then the lobe and
 * pdf for m and ior from it.
 */
void glint_beckmann_geometry(struct vec3 wo, struct vec3 wi, float g[4]);
double glint_beckmann_from_geometry(double m, double ior, const float g[4],
				    double *pdf, double *dlog);

/*
 * A microfacet distribution as data: the lobe without its albedo and its
 * sampling (above), with the lobe's extent and core width as functions
 * of the distribution's width parameter w.  The microfacet models
 * (torrance_sparrow.c, ggx.c, two_lobe.c, oren_nayar.c) name theirs in
 * their struct glint_fit_lobes; the exports read which one a model uses.
 */
struct glint_microfacet {
	const char *name; /* "beckmann", "ggx" */
	double (*lobe)(double w, double ior, struct vec3 wo, struct vec3 wi);
	void (*sample)(double w, struct vec3 wo, const double u[2],
		       struct vec3 *wi);
	double (*pdf)(double w, struct vec3 wo, struct vec3 wi);
	/* Angle (radians) from the mirror direction beyond which the lobe
	 * is below 1e-12 of its peak, or <= 0 when it has no such bound. */
	double (*extent)(double w);
	/* The lobe's core: the standard deviation of its reflected
	 * directions about the mirror direction is core * w; widening it by
	 * a Gaussian of s makes w sqrt(w^2 + s^2 / widen_div). */
	double core, widen_div;
};

extern const struct glint_microfacet glint_microfacet_beckmann;
extern const struct glint_microfacet glint_microfacet_ggx;

/*
 * How a lobe is sampled: cosine-weighted (mf NULL: diffuse lobes), or by
 * reflecting about a normal of distribution mf with width w.  _sample
 * returns the pdf at the direction drawn, 0 when it falls below the
 * surface; both are 0 for wo below it.  The pdf_lobe/sample_lobe of the
 * models.
 */
double glint_lobe_shape_pdf(const struct glint_microfacet *mf, double w,
			    struct vec3 wo, struct vec3 wi);
double glint_lobe_shape_sample(const struct glint_microfacet *mf, double w,
			       struct vec3 wo, const double u[2],
			       struct vec3 *wi);

/*
 * Trowbridge-Reitz (GGX) distribution with width a (Walter et al. 2007):
 * D(h) = a^2 / (pi cos^4(t) (a^2 + tan^2(t))^2); its integral of D cos
 * over the hemisphere is 1.  The slopes have no finite variance: a is a
 * width, not an RMS slope (Beckmann's m and a agree near the peak).
 */
double glint_ggx_d(double cos_h, double a);

/* Smith's Lambda for GGX, (sqrt(1 + a^2 tan^2(t_v)) - 1) / 2. */
double glint_ggx_lambda(double cos_v, double a);

/* Height-correlated Smith masking-shadowing, 1 / (1 + L(o) + L(i))
 * (Heitz 2014, eq. 99). */
double glint_ggx_g2(double no, double ni, double a);

/*
 * The Oren-Nayar (1994) qualitative rough-diffuse factor, per unit albedo:
 * (A + B max(0, cos(phi_i - phi_o)) sin(alpha) tan(beta)) / pi with
 * A = 1 - s^2 / (2 (s^2 + 0.33)), B = 0.45 s^2 / (s^2 + 0.09),
 * alpha = max(theta_i, theta_o), beta = min(...), s = sigma the standard
 * deviation of the facets' slope angle in radians.  sigma = 0 is Lambert.
 * wo, wi in the shading frame; 0 below the surface.
 */
double glint_oren_nayar(double sigma, struct vec3 wo, struct vec3 wi);

#endif
