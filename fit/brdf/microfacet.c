/* SPDX-License-Identifier: MIT */
#include "microfacet.h"

#include "model.h"

#include "core/fastmath.h"
#include "core/vec.h"

#include <math.h>

double glint_beckmann_d(double cos_h, double m)
{
	if (!(cos_h > 0))
		return 0;
	double c2 = cos_h * cos_h;
	double tan2 = (1 - c2) / c2;
	return glint_fast_exp(-tan2 / (m * m)) / (M_PI * m * m * c2 * c2);
}

double glint_vcavity_g(double nh, double no, double ni, double oh)
{
	if (!(oh > 0))
		return 0;
	double g = 2 * nh * (no < ni ? no : ni) / oh;
	return g < 1 ? (g > 0 ? g : 0) : 1;
}

double glint_ggx_d(double cos_h, double a)
{
	if (!(cos_h > 0))
		return 0;
	double c2 = cos_h * cos_h, a2 = a * a;
	double t = a2 * c2 + (1 - c2); /* cos^2 (a^2 + tan^2) */
	return a2 / (M_PI * t * t);
}

double glint_ggx_lambda(double cos_v, double a)
{
	if (!(cos_v > 0))
		return INFINITY;
	double c2 = cos_v * cos_v;
	double a2t2 = a * a * (1 - c2) / c2;
	/* (sqrt(1 + x) - 1) / 2 without cancellation for small x. */
	return a2t2 / (2 * (sqrt(1 + a2t2) + 1));
}

double glint_ggx_g2(double no, double ni, double a)
{
	if (!(no > 0 && ni > 0))
		return 0;
	return 1 / (1 + glint_ggx_lambda(no, a) + glint_ggx_lambda(ni, a));
}

double glint_oren_nayar(double sigma, struct vec3 wo, struct vec3 wi)
{
	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	double s2 = sigma * sigma;
	double A = 1 - s2 / (2 * (s2 + 0.33)), B = 0.45 * s2 / (s2 + 0.09);
	double so = sqrt(fmax(0, 1 - wo.z * wo.z));
	double si = sqrt(fmax(0, 1 - wi.z * wi.z));
	double cphi = 0;
	if (so > 1e-9 && si > 1e-9)
		cphi = fmax(0, (wo.x * wi.x + wo.y * wi.y) / (so * si));
	/* sin(alpha) tan(beta): alpha the larger polar angle, beta the
	 * smaller (the larger cosine). */
	double sa, tb;
	if (wi.z < wo.z) {
		sa = si;
		tb = so / wo.z;
	} else {
		sa = so;
		tb = si / wi.z;
	}
	return (A + B * cphi * sa * tb) / M_PI;
}

double glint_fresnel_or_one(double c, double ior)
{
	return ior > 0 ? glint_fresnel_dielectric(c, ior) : 1;
}

double glint_fresnel_half_dlog(double ior, struct vec3 wo, struct vec3 wi)
{
	struct vec3 h = v3_add(wo, wi);
	double l = v3_len(h);

	if (!(ior > 0) || !(l > 0))
		return 0;
	double dlog;
	glint_fresnel_dielectric_dlog(v3_dot(wo, h) / l, ior, &dlog);
	return dlog;
}

double glint_beckmann_lobe(double m, double ior, struct vec3 wo, struct vec3 wi)
{
	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double oh = v3_dot(wo, h);
	return glint_beckmann_d(h.z, m) * glint_vcavity_g(h.z, wo.z, wi.z, oh) *
	       glint_fresnel_or_one(oh, ior) / (4 * wi.z * wo.z);
}

/* The pdf of reflecting wo about a normal drawn with density d(h) cos(h). */
static double reflected_pdf(double d_h, struct vec3 h, struct vec3 wo)
{
	double oh = v3_dot(wo, h);
	return oh > 0 ? d_h * h.z / (4 * oh) : 0;
}

double glint_beckmann_pdf(double m, struct vec3 wo, struct vec3 wi)
{
	struct vec3 h = v3_norm(v3_add(wo, wi));
	return reflected_pdf(glint_beckmann_d(h.z, m), h, wo);
}

/* wo reflected about the normal h (unit) at polar tan^2 tan2 and azimuth
 * 2 pi u; returns h. */
static struct vec3 reflect_about(double tan2, double u, struct vec3 wo,
				 struct vec3 *wi)
{
	double ch = 1 / sqrt(1 + tan2), s2 = 1 - ch * ch;
	double sh = sqrt(s2 > 0 ? s2 : 0); /* (fmax() is a call) */
	double sp, cp;
	glint_fast_sincos_2pi(u, &sp, &cp);
	struct vec3 h = v3(sh * cp, sh * sp, ch);
	double oh = v3_dot(wo, h);

	*wi = v3_sub(v3_scale(h, 2 * oh), wo);
	return h;
}

void glint_beckmann_sample(double m, struct vec3 wo, const double u[2],
			   struct vec3 *wi)
{
	reflect_about(-m * m * glint_fast_log(1 - u[0]), u[1], wo, wi);
}

/* F at cosine c for index ior (1 when ior <= 0) and, where dlog is not
 * NULL, d log F / d ior (0 for a constant F). */
static double fresnel_dlog(double c, double ior, double *dlog)
{
	if (!dlog)
		return glint_fresnel_or_one(c, ior);
	*dlog = 0;
	return ior > 0 ? glint_fresnel_dielectric_dlog(c, ior, dlog) : 1;
}

/* D G F / (4 (n.i)(n.o)) and D (n.h) / (4 (o.h)) from D and h. */
static double lobe_and_pdf(double d, struct vec3 h, double ior, struct vec3 wo,
			   struct vec3 wi, double *pdf, double *dlog)
{
	double oh = v3_dot(wo, h);

	if (pdf)
		*pdf = oh > 0 ? d * h.z / (4 * oh) : 0;
	return d * glint_vcavity_g(h.z, wo.z, wi.z, oh) *
	       fresnel_dlog(oh, ior, dlog) / (4 * wi.z * wo.z);
}

double glint_beckmann_lobe_pdf(double m, double ior, struct vec3 wo,
			       struct vec3 wi, double *pdf, double *dlog)
{
	if (!(wo.z > 0 && wi.z > 0)) {
		if (pdf)
			*pdf = 0;
		if (dlog)
			*dlog = 0;
		return 0;
	}
	struct vec3 h = v3_norm(v3_add(wo, wi));
	return lobe_and_pdf(glint_beckmann_d(h.z, m), h, ior, wo, wi, pdf,
			    dlog);
}

double glint_beckmann_sample_lobe(double m, double ior, struct vec3 wo,
				  const double u[2], struct vec3 *wi,
				  double *lobe, double *dlog)
{
	double pdf;

	*lobe = 0;
	if (dlog)
		*dlog = 0;
	if (!(wo.z > 0))
		return 0;
	/* the half vector of wo and wi is the normal drawn (where o.h <= 0
	 * the lobe and pdf are 0 either way) */
	struct vec3 h =
		reflect_about(-m * m * glint_fast_log(1 - u[0]), u[1], wo, wi);
	if (!(wi->z > 0))
		return 0;
	/* exp(-tan^2 / m^2) = 1 - u[0] at the normal drawn. */
	double c2 = h.z * h.z;
	double d = h.z > 0 ? (1 - u[0]) / (M_PI * m * m * c2 * c2) : 0;
	*lobe = lobe_and_pdf(d, h, ior, wo, *wi, &pdf, dlog);
	return pdf;
}

/* glint_fresnel_dielectric_dlog() at o.h in a vector lane, 1 (and dlog
 * 0) for ior <= 0: every step computed, the cases chosen at the end. */
static inline double fresnel_lane(double oh, double ior, double *dl)
{
	double cf = oh < 1 ? oh : 1;
	double n2m1 = ior * ior - 1, g2 = n2m1 + cf * cf;
	double gg = sqrt(g2 > 0 ? g2 : 0);
	double a = (gg - cf) / (gg + cf);
	double nb = cf * (gg + cf) - 1, db = cf * (gg - cf) + 1;
	double bb = nb / db;
	double dlog =
		4 * cf * ior / gg *
		(1 / n2m1 + (1 - cf * cf) * nb / (db * (db * db + nb * nb)));
	*dl = ior > 0 && n2m1 > 0 && cf > 0 && g2 >= 0 ? dlog : 0;
	return ior > 0 && g2 >= 0 ? 0.5 * a * a * (1 + bb * bb) : 1;
}

/* The V-cavity G in a vector lane (glint_vcavity_g() for o.h > 0). */
static inline double vcavity_lane(double nh, double no, double ni, double oh)
{
	double g = 2 * nh * (no < ni ? no : ni) / oh;
	return g < 1 ? (g > 0 ? g : 0) : 1;
}

/* A lane of glint_beckmann_lobe_n(): every step computed, the lanes
 * below the surface or facing away chosen out at the end, never a branch
 * (a division under a condition could trap, which keeps the compiler
 * from vectorising; those lanes' infinities and NaNs are not chosen). */
__attribute__((always_inline)) static inline double
beckmann_lane(double m, double ior, struct vec3 wo, double x, double y,
	      double z, double *dl)
{
	double hx = wo.x + x, hy = wo.y + y, hz = wo.z + z;
	double il = 1.0 / sqrt(hx * hx + hy * hy + hz * hz);
	double c = hz * il, oh = (wo.x * hx + wo.y * hy + wo.z * hz) * il;
	double c2 = c * c;
	double d = glint_fast_exp_neg(-((1 - c2) / c2) / (m * m)) /
		   (M_PI * m * m * c2 * c2);
	double g = vcavity_lane(c, wo.z, z, oh), dlog;
	double f = fresnel_lane(oh, ior, &dlog);
	int on = z > 0 && c > 0 && oh > 0 && wo.z > 0;
	*dl = on ? dlog : 0;
	return on ? d * g * f / (4 * z * wo.z) : 0;
}

void glint_beckmann_lobe_n(double m, double ior, struct vec3 wo, int n,
			   const double *restrict x, const double *restrict y,
			   const double *restrict z, double *restrict b,
			   double *restrict dlog)
{
	/* one loop per case, each without a branch in its body */
	if (dlog)
		for (int k = 0; k < n; k++)
			b[k] = beckmann_lane(m, ior, wo, x[k], y[k], z[k],
					     &dlog[k]);
	else
		for (int k = 0; k < n; k++) {
			double dl;
			b[k] = beckmann_lane(m, ior, wo, x[k], y[k], z[k], &dl);
		}
}

/* A lane of glint_beckmann_sample_lobe_n(): glint_beckmann_sample_lobe()'s
 * steps without a branch. */
__attribute__((always_inline)) static inline double
beckmann_sample_lane(double m, double ior, struct vec3 wo, double u0, double u1,
		     double *x, double *y, double *z, double *lobe, double *dl)
{
	double tan2 = -m * m * glint_fast_log_normal(1 - u0);
	double ch = 1 / sqrt(1 + tan2), s2 = 1 - ch * ch;
	double sh = sqrt(s2 > 0 ? s2 : 0), sp, cp;
	glint_fast_sincos_2pi_nb(u1, &sp, &cp);
	double hx = sh * cp, hy = sh * sp, hz = ch;
	double oh = wo.x * hx + wo.y * hy + wo.z * hz;
	double wx = hx * (2 * oh) - wo.x, wy = hy * (2 * oh) - wo.y;
	double wz = hz * (2 * oh) - wo.z;
	/* exp(-tan^2 / m^2) = 1 - u0 at the normal drawn */
	double c2 = hz * hz;
	double d = (1 - u0) / (M_PI * m * m * c2 * c2), dlog;
	double f = fresnel_lane(oh, ior, &dlog);
	double v = d * vcavity_lane(hz, wo.z, wz, oh) * f / (4 * wz * wo.z);
	int on = wz > 0 && oh > 0 && wo.z > 0;
	*x = wx, *y = wy, *z = wz;
	*lobe = on ? v : 0;
	*dl = on ? dlog : 0;
	return on ? d * hz / (4 * oh) : 0;
}

void glint_beckmann_sample_lobe_n(double m, double ior, int n,
				  const struct vec3 *restrict wo,
				  const double *restrict u0,
				  const double *restrict u1, double *restrict x,
				  double *restrict y, double *restrict z,
				  double *restrict pdf, double *restrict lobe,
				  double *restrict dlog)
{
	if (dlog)
		for (int k = 0; k < n; k++)
			pdf[k] = beckmann_sample_lane(
				m, ior, wo[k], u0[k], u1[k], &x[k], &y[k],
				&z[k], &lobe[k], &dlog[k]);
	else
		for (int k = 0; k < n; k++) {
			double dl;
			pdf[k] = beckmann_sample_lane(m, ior, wo[k], u0[k],
						      u1[k], &x[k], &y[k],
						      &z[k], &lobe[k], &dl);
		}
}

void glint_beckmann_geometry(struct vec3 wo, struct vec3 wi, float g[4])
{
	g[0] = g[1] = g[2] = g[3] = 0;
	if (!(wo.z > 0 && wi.z > 0))
		return;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double c2 = h.z * h.z, oh = v3_dot(wo, h);
	if (!(h.z > 0))
		return;
	double k = 1 / (M_PI * c2 * c2);
	g[0] = (float)((1 - c2) / c2);
	g[1] = (float)oh;
	g[2] = (float)(k * glint_vcavity_g(h.z, wo.z, wi.z, oh) /
		       (4 * wi.z * wo.z));
	g[3] = oh > 0 ? (float)(k * h.z / (4 * oh)) : 0.0f;
}

double glint_beckmann_from_geometry(double m, double ior, const float g[4],
				    double *pdf, double *dlog)
{
	double m2 = m * m;
	double d =
		g[2] > 0 || g[3] > 0 ? glint_fast_exp_neg(-g[0] / m2) / m2 : 0;

	if (pdf)
		*pdf = d * g[3];
	if (dlog)
		*dlog = 0;
	return d > 0 ? d * g[2] * fresnel_dlog(g[1], ior, dlog) : 0;
}

double glint_ggx_lobe(double a, double ior, struct vec3 wo, struct vec3 wi)
{
	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double oh = v3_dot(wo, h);
	return glint_ggx_d(h.z, a) * glint_ggx_g2(wo.z, wi.z, a) *
	       glint_fresnel_or_one(oh, ior) / (4 * wi.z * wo.z);
}

double glint_ggx_pdf(double a, struct vec3 wo, struct vec3 wi)
{
	struct vec3 h = v3_norm(v3_add(wo, wi));
	return reflected_pdf(glint_ggx_d(h.z, a), h, wo);
}

void glint_ggx_sample(double a, struct vec3 wo, const double u[2],
		      struct vec3 *wi)
{
	/* The inverse of the D cos marginal in tan^2: a^2 u / (1 - u). */
	reflect_about(a * a * u[0] / (1 - u[0]), u[1], wo, wi);
}

/* Beckmann D falls below 1e-12 of its peak where tan^2(t_h) > 27.6 m^2;
 * the reflected direction turns by twice the half-vector's angle. */
static double beckmann_extent(double m)
{
	return 2 * glint_fast_atan2(m * sqrt(27.6), 1); /* (to 6e-9 rad) */
}

/* D(t) / D(0) = a^4 / (a^2 cos^2 t + sin^2 t)^2 is below 1e-12 once
 * sin t > 1000 a: a bound only for the smoothest lobes. */
static double ggx_extent(double a)
{
	double s = 1000 * a;
	return s < 1 ? 2 * asin(s) : -1;
}

/* Beckmann's half-vector angle has variance m^2/2 per axis, the mirror
 * direction twice the angle: standard deviation sqrt(2) m. */
const struct glint_microfacet glint_microfacet_beckmann = {
	.name = "beckmann",
	.lobe = glint_beckmann_lobe,
	.sample = glint_beckmann_sample,
	.pdf = glint_beckmann_pdf,
	.extent = beckmann_extent,
	.core = 1.4142135623730951,
	.widen_div = 2,
};

/* GGX's core: D falls to half at tan t_h = a sqrt(sqrt(2) - 1) =
 * 0.6436 a, the mirror direction's angle twice that, which a Gaussian
 * reaches at 1.1774 sigma: sigma = 1.0932 a.  Widening keeps that core
 * (its tails are not widened). */
#define GGX_CORE 1.0932

const struct glint_microfacet glint_microfacet_ggx = {
	.name = "ggx",
	.lobe = glint_ggx_lobe,
	.sample = glint_ggx_sample,
	.pdf = glint_ggx_pdf,
	.extent = ggx_extent,
	.core = GGX_CORE,
	.widen_div = GGX_CORE * GGX_CORE,
};

double glint_lobe_shape_pdf(const struct glint_microfacet *mf, double w,
			    struct vec3 wo, struct vec3 wi)
{
	if (!(wo.z > 0 && wi.z > 0))
		return 0;
	return mf ? mf->pdf(w, wo, wi) : wi.z / M_PI;
}

double glint_lobe_shape_sample(const struct glint_microfacet *mf, double w,
			       struct vec3 wo, const double u[2],
			       struct vec3 *wi)
{
	if (!(wo.z > 0))
		return 0;
	if (mf)
		mf->sample(w, wo, u, wi);
	else
		glint_sample_cosine(u, wi);
	if (!(wi->z > 0))
		return 0;
	return glint_lobe_shape_pdf(mf, w, wo, *wi);
}
