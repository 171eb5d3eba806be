/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_FASTMATH_H
#define GLINT_CORE_FASTMATH_H

/*
 * The transcendental functions the fit's inner loop calls per lobe
 * sample, as polynomials: the map's (u, v) of a direction (atan2, acos),
 * a microfacet normal's azimuth (sin and cos of 2 pi u) and radius (log),
 * and the Beckmann distribution (exp); floor and a clamp without libm's
 * calls.  glibc's versions are correctly rounded and take 45-140
 * instructions a call with their special cases; at 13-20 million calls
 * each in the default fit they were a sixth of its instructions.  These
 * are accurate to 6e-9 rad (atan2), 2e-9 rad (acos), 8e-16 (sin, cos)
 * and 3 ulp (exp, log): a map's texel is 6e-3 rad, so a lookup moves by
 * a millionth of a texel.  atan2 and acos take finite arguments (a NaN
 * gives an unspecified value); exp and log hand libm what they do not
 * cover.  tests/unit/test_fastmath.c measures the errors against libm.
 *
 * The coefficients of atan and acos are minimax fits on [0, 1]
 * (relative-error weighted iterative least squares): atan(a) = a P(a^2),
 * acos(t) = sqrt(1 - t) Q(t) (the form of Abramowitz and Stegun 4.4.45,
 * to degree 8); sin, cos and exp are Taylor series after reduction to a
 * quarter turn and to |r| <= ln 2 / 2, log the series of 2 atanh(s).
 *
 * Errors: none.  Threads: re-entrant.  Who frees: nothing.
 */

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* c[0] x^(n-1) + ... + c[n-1] (n <= 16) by Estrin's scheme: pairs of
 * terms, then pairs of pairs in x^2, x^4, ..., so that the additions of
 * a level are independent and the chain of dependent operations is
 * log2(n) long instead of Horner's n (unrolled: n is a constant). */
static inline double glint_poly(double x, const double *c, int n)
{
	double a[16];
#pragma GCC unroll 16
	for (int i = 0; i < n; i++)
		a[i] = c[n - 1 - i];
	/* four levels hold n <= 16; a fixed count, so that the loops unroll
	 * completely before the vectoriser sees a loop that calls this */
	int m = n;
#pragma GCC unroll 4
	for (int level = 0; level < 4; level++) {
#pragma GCC unroll 8
		for (int j = 0; j < m / 2; j++)
			a[j] = a[2 * j] + a[2 * j + 1] * x;
		if (m % 2)
			a[m / 2] = a[m - 1];
		m = (m + 1) / 2;
		x *= x;
	}
	return a[0];
}

/* x clamped to [lo, hi], without fmin()'s and fmax()'s calls (whose NaN
 * rules need them on x86-64); a NaN x gives lo, as fmin(fmax(x, lo), hi)
 * does, so that an index made from it stays in range. */
static inline double glint_clamp(double x, double lo, double hi)
{
	return x > lo ? (x < hi ? x : hi) : lo;
}

/* floor(x) for |x| < 2^62, without a call (x86-64's baseline has no
 * rounding instruction). */
static inline double glint_floor(double x)
{
	long long i = (long long)x;
	return (double)(i - (x < (double)i));
}

/* floor(x) for |x| < 2^51 in doubles alone (round to even by the
 * 1.5 x 2^52 shift, less 1 where that rounded up): a loop of it
 * vectorises, where glint_floor()'s 64-bit conversion does not. */
static inline double glint_floor_nb(double x)
{
	double r = (x + 6755399441055744.0) - 6755399441055744.0;
	return r > x ? r - 1 : r;
}

/* exp(x - k ln 2) for the integer k nearest x / ln 2: r = x - k ln 2 in
 * two parts, |r| <= ln 2 / 2, and Taylor to r^13 (4e-18 at |r| = ln 2 /
 * 2, from r^2 on here), 1 + r apart: the polynomial's rounding scaled by
 * r^2. */
static inline double glint_exp_reduced(double x, double k)
{
	double r = (x - k * 6.93147180369123816490e-01) -
		   k * 1.90821492927058770002e-10;
	static const double c[] = {
		1.0 / 6227020800, 1.0 / 479001600, 1.0 / 39916800,
		1.0 / 3628800,	  1.0 / 362880,	   1.0 / 40320,
		1.0 / 5040,	  1.0 / 720,	   1.0 / 120,
		1.0 / 24,	  1.0 / 6,	   0.5,
	};
	return 1 + (r + r * r * glint_poly(r, c, sizeof(c) / sizeof(c[0])));
}

/* exp(x), within 3 ulp of libm's (libm's own beyond |x| = 700). */
static inline double glint_fast_exp(double x)
{
	if (!(x > -700 && x < 700))
		return exp(x);
	double k = glint_floor(x * 1.4426950408889634 + 0.5);
	double e = glint_exp_reduced(x, k);
	/* times 2^k, |k| <= 1010 here */
	union {
		double d;
		unsigned long long u;
	} b = { .u = (unsigned long long)((long long)k + 1023) << 52 };
	return e * b.d;
}

/* exp(x) for x <= 0, as glint_fast_exp() to 3 ulp (0 from -708 down,
 * where libm's is 3e-308 or less), without a branch or a call, so that a
 * loop of it vectorises: k = round(x / ln 2) by the 1.5 x 2^52 shift,
 * whose low bits then hold k for the exponent. */
static inline double glint_fast_exp_neg(double x)
{
	double xc = x > -708 ? x : -708;
	double t = xc * 1.4426950408889634 + 6755399441055744.0;
	double e = glint_exp_reduced(xc, t - 6755399441055744.0);
	union {
		double d;
		unsigned long long u;
	} b = { .d = t };
	/* t's bits are 0x4338000000000000 + k: 2^k's exponent is k + 1023 */
	b.u = (b.u - 0x4338000000000000ULL + 1023) << 52;
	return x > -708 ? e * b.d : 0;
}

/* e ln 2 + log m for m in [sqrt(1/2), sqrt(2)): log m = 2 atanh(s),
 * s = (m - 1) / (m + 1), |s| <= 0.172, the series to s^21 (3e-18). */
static inline double glint_log_reduced(double e, double m)
{
	double s = (m - 1) / (m + 1), s2 = s * s;
	static const double c[] = {
		2.0 / 21, 2.0 / 19, 2.0 / 17, 2.0 / 15, 2.0 / 13,
		2.0 / 11, 2.0 / 9,  2.0 / 7,  2.0 / 5,	2.0 / 3,
	};
	/* 2 s apart: the polynomial's rounding scaled by s^2 */
	double l = 2 * s + s * s2 * glint_poly(s2, c, sizeof(c) / sizeof(c[0]));
	return e * 6.93147180369123816490e-01 +
	       (e * 1.90821492927058770002e-10 + l);
}

/* log(x), within 3 ulp of libm's (libm's own for x not a positive normal
 * number). */
static inline double glint_fast_log(double x)
{
	union {
		double d;
		unsigned long long u;
	} b = { .d = x };
	long long e = (long long)((b.u >> 52) & 0x7ff) - 1023;
	if (!(x > 0) || e == -1023 || e == 1024)
		return log(x);
	/* the mantissa in [sqrt(1/2), sqrt(2)) */
	b.u = (b.u & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL;
	if (b.d > 1.4142135623730951) {
		b.d *= 0.5;
		e++;
	}
	return glint_log_reduced((double)e, b.d);
}

/* glint_fast_log() for x a positive normal number (1 - u of a uniform
 * u in [0, 1)), the same arithmetic without a branch or a call, so that
 * a loop of it vectorises: the exponent read as a double by the 2^52
 * shift (SSE2 has no int64 conversion), the mantissa's halving chosen. */
static inline double glint_fast_log_normal(double x)
{
	union {
		double d;
		unsigned long long u;
	} b = { .d = x }, e;
	e.u = (b.u >> 52) | 0x4330000000000000ULL;
	double ex = e.d - (4503599627370496.0 + 1023);
	b.u = (b.u & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL;
	int big = b.d > 1.4142135623730951;
	double mm = big ? b.d * 0.5 : b.d;
	ex = big ? ex + 1 : ex;
	return glint_log_reduced(ex, mm);
}

/* atan2(y, x) in [-pi, pi]. */
static inline double glint_fast_atan2(double y, double x)
{
	double ax = fabs(x), ay = fabs(y);
	double hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
	double a = hi > 0 ? lo / hi : 0, s = a * a;
	static const double c[] = {
		0.0024567263222858571, -0.014401363693472016,
		0.039781230566781012,  -0.072348576973247702,
		0.10498946061999831,   -0.14161229125265329,
		0.19985906743738605,   -0.33332597025554167,
		0.99999988638221204,
	};
	double p = glint_poly(s, c, sizeof(c) / sizeof(c[0]));
	double r = a * p;
	if (ay > ax)
		r = M_PI / 2 - r;
	if (x < 0)
		r = M_PI - r;
	return copysign(r, y);
}

/* acos(t) for t in [-1, 1] (clamped). */
static inline double glint_fast_acos(double t)
{
	double a = fabs(t) < 1 ? fabs(t) : 1;
	static const double c[] = {
		0.00081791769862606806, -0.0044790539976668851,
		0.011801080649785699,	-0.021341832146287251,
		0.032840581557878341,	-0.050657485767627908,
		0.089037549586408596,	-0.21460148676792273,
		1.5707963249873267,
	};
	double q = glint_poly(a, c, sizeof(c) / sizeof(c[0]));
	double r = sqrt(1 - a) * q;
	return t < 0 ? M_PI - r : r;
}

/* sin x and cos x on |x| <= pi / 4 (x2 = x^2): Taylor to x^15 and x^16,
 * within 8e-16, so that sin^2 + cos^2 = 1 as closely as libm's. */
static inline void glint_sincos_series(double x, double x2, double *sn,
				       double *cs)
{
	static const double sc[] = {
		-1.0 / 1307674368000,
		1.0 / 6227020800,
		-1.0 / 39916800,
		1.0 / 362880,
		-1.0 / 5040,
		1.0 / 120,
		-1.0 / 6,
		1,
	};
	static const double cc[] = {
		1.0 / 20922789888000,
		-1.0 / 87178291200,
		1.0 / 479001600,
		-1.0 / 3628800,
		1.0 / 40320,
		-1.0 / 720,
		1.0 / 24,
		-0.5,
		1,
	};
	*sn = x * glint_poly(x2, sc, sizeof(sc) / sizeof(sc[0]));
	*cs = glint_poly(x2, cc, sizeof(cc) / sizeof(cc[0]));
}

/* sin and cos of 2 pi u, |u| < 2^60. */
static inline void glint_fast_sincos_2pi(double u, double *s, double *c)
{
	/* the nearest quarter turn */
	long long qi = (long long)glint_floor(4 * u + 0.5);
	double x = (u - 0.25 * (double)qi) * (2 * M_PI), x2 = x * x;
	double sn, cs;
	glint_sincos_series(x, x2, &sn, &cs);
	switch (qi & 3) {
	case 0:
		*s = sn;
		*c = cs;
		break;
	case 1:
		*s = cs;
		*c = -sn;
		break;
	case 2:
		*s = -sn;
		*c = -cs;
		break;
	default:
		*s = -cs;
		*c = sn;
		break;
	}
}

/* glint_fast_sincos_2pi() without a branch, for loops that vectorise: the
 * quarter turn rounded to even by the 1.5 x 2^52 shift (ties, u an odd
 * eighth, go the other way: both reductions are within the series' range)
 * and the quadrant's signs and swap chosen, all in doubles (a 64-bit
 * integer's test keeps GCC from vectorising on SSE2). */
static inline void glint_fast_sincos_2pi_nb(double u, double *s, double *c)
{
	const double shift = 6755399441055744.0; /* 1.5 x 2^52 */
	double qi = (4 * u + shift) - shift;
	double x = (u - 0.25 * qi) * (2 * M_PI), x2 = x * x, sn, cs;
	glint_sincos_series(x, x2, &sn, &cs);
	/* the quadrant qi mod 4 as q in {-2, ..., 2}; (sin, cos) = (sn, cs),
	 * (cs, -sn), (-sn, -cs), (-cs, sn) in quadrants 0, 1, 2, 3 (-1) */
	double q = qi - 4 * ((0.25 * qi + shift) - shift);
	int odd = q == 1 || q == -1;
	double s0 = odd ? cs : sn, c0 = odd ? sn : cs;
	*s = q < 0 || q > 1 ? -s0 : s0;
	*c = q > 0 || q < -1 ? -c0 : c0;
}

#endif
