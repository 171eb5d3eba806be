/* SPDX-License-Identifier: MIT */
/*
 * The fit's polynomial atan2, acos, sincos, exp and log (core/fastmath.h)
 * against libm: their largest errors over a million arguments each (exp
 * and log relative, within 3 ulp), floor and clamp exact, the edges
 * (axes, signed zeros, +-1, quadrant boundaries) within the same bounds, and
 * a direction's map coordinates through them within two millionths of a
 * 1024-texel map's texel of glint_latlong_dir_to_uv()'s.
 */
#include "test.h"

#include "core/fastmath.h"
#include "core/vec.h"

/* A reproducible uniform draw in [0, 1) (xorshift64*). */
static double draw(unsigned long long *st)
{
	*st ^= *st >> 12;
	*st ^= *st << 25;
	*st ^= *st >> 27;
	return (double)((*st * 2685821657736338717ULL) >> 11) * 0x1p-53;
}

static void test_atan2(void)
{
	unsigned long long st = 1;
	double worst = 0;
	for (int i = 0; i < 1000000; i++) {
		double y = 2 * draw(&st) - 1, x = 2 * draw(&st) - 1;
		double e = fabs(glint_fast_atan2(y, x) - atan2(y, x));
		worst = e > worst ? e : worst;
	}
	printf("atan2: largest error %.3g rad\n", worst);
	CHECK(worst < 1e-8, "atan2 off by %g", worst);
	static const double edge[][2] = { { 0, 1 },  { 1, 0 },	   { 0, -1 },
					  { -1, 0 }, { 1, 1 },	   { -1, -1 },
					  { 1, -1 }, { -0.0, -1 }, { 0, 0 } };
	for (size_t k = 0; k < sizeof(edge) / sizeof(edge[0]); k++) {
		double y = edge[k][0], x = edge[k][1];
		CHECK_NEAR(glint_fast_atan2(y, x), atan2(y, x), 1e-8,
			   "atan2 at an edge");
	}
	CHECK(glint_fast_atan2(-0.0, -1) < 0 && glint_fast_atan2(0.0, -1) > 0,
	      "the sign of zero picks -pi or pi");
}

static void test_acos(void)
{
	unsigned long long st = 2;
	double worst = 0;
	for (int i = 0; i < 1000000; i++) {
		double t = 2 * draw(&st) - 1;
		double e = fabs(glint_fast_acos(t) - acos(t));
		worst = e > worst ? e : worst;
	}
	printf("acos: largest error %.3g rad\n", worst);
	CHECK(worst < 5e-9, "acos off by %g", worst);
	CHECK(glint_fast_acos(1) == 0, "acos(1) %g", glint_fast_acos(1));
	CHECK_NEAR(glint_fast_acos(-1), M_PI, 1e-8, "acos(-1)");
	CHECK_NEAR(glint_fast_acos(0), M_PI / 2, 1e-8, "acos(0)");
	CHECK(glint_fast_acos(1.0000001) == 0, "clamped above 1");
}

static void test_sincos(void)
{
	unsigned long long st = 3;
	double worst = 0, far = 0;
	for (int i = 0; i < 1000000; i++) {
		double u = i < 999000 ? draw(&st) : (i - 999000) / 8.0 - 60;
		double s, c, sb, cb;
		glint_fast_sincos_2pi(u, &s, &c);
		/* the branch-free one: the same series, its quarter turn
		 * rounded to even */
		glint_fast_sincos_2pi_nb(u, &sb, &cb);
		double e = fmax(fabs(s - sin(2 * M_PI * u)),
				fabs(c - cos(2 * M_PI * u)));
		e = fmax(e, fmax(fabs(sb - sin(2 * M_PI * u)),
				 fabs(cb - cos(2 * M_PI * u))));
		if (i < 999000)
			worst = e > worst ? e : worst;
		else
			far = e > far ? e : far;
	}
	printf("sincos: largest error %.3g in [0, 1), %.3g out to 64 turns\n",
	       worst, far);
	CHECK(worst < 1e-15, "sincos off by %g", worst);
	/* out there libm's own sin(2 pi u) rounds 2 pi u (6e-14 at 400) */
	CHECK(far < 1e-13, "sincos off by %g far from 0", far);
}

static void test_exp_log(void)
{
	unsigned long long st = 5;
	double we = 0, wl = 0, wn = 0;
	int nb = 0;
	for (int i = 0; i < 1000000; i++) {
		/* exp over [-750, 750] (libm's own past 700), most of the draws
		 * where the fit calls it: -tan^2 / m^2 in [-50, 0] */
		double x = i % 4 ? -50 * draw(&st) : 1500 * draw(&st) - 750;
		double e = glint_fast_exp(x), r = exp(x);
		if (r > 0 && isfinite(r))
			we = fmax(we, fabs(e - r) / r);
		else
			CHECK(e == r, "exp(%g) %g for %g", x, e, r);
		/* the branch-free one on x <= 0: libm's where that is a
		 * normal number, 0 below -708 */
		double xn = -fabs(x), en = glint_fast_exp_neg(xn);
		if (xn > -708)
			wn = fmax(wn, fabs(en - exp(xn)) / exp(xn));
		else
			CHECK(en == 0, "exp_neg(%g) %g", xn, en);
		/* log over (0, 1] (1 - u) and 30 orders of magnitude */
		double y = i % 2 ? 1 - draw(&st) : pow(10, 30 * draw(&st) - 15);
		double l = glint_fast_log(y), lr = log(y);
		wl = fmax(wl, fabs(l - lr) / fmax(fabs(lr), 1e-300));
		/* the branch-free one: the same arithmetic */
		double ln = glint_fast_log_normal(y);
		nb += memcmp(&ln, &l, sizeof(l)) != 0;
	}
	printf("exp: largest relative error %.3g; log %.3g\n", we, wl);
	CHECK(we < 6.7e-16, "exp off by %g", we);
	printf("exp of x <= 0 without a branch: largest relative error %.3g\n",
	       wn);
	CHECK(wn < 6.7e-16, "exp_neg off by %g", wn);
	CHECK(glint_fast_exp_neg(0) == 1 && glint_fast_exp_neg(-0.0) == 1 &&
		      glint_fast_exp_neg(-708) == 0 &&
		      glint_fast_exp_neg(-INFINITY) == 0 &&
		      glint_fast_exp_neg(-707.9) > 0,
	      "exp_neg at 0 and -708");
	CHECK(wl < 6.7e-16, "log off by %g", wl);
	CHECK(nb == 0, "the branch-free log differs at %d of 1000000", nb);
	CHECK(glint_fast_exp(0) == 1 && glint_fast_log(1) == 0,
	      "exp(0) %g, log(1) %g", glint_fast_exp(0), glint_fast_log(1));
	CHECK(glint_fast_log(0) == -INFINITY && isnan(glint_fast_log(-1)) &&
		      glint_fast_log(0x1p-1060) == log(0x1p-1060),
	      "log at 0, below and subnormal");
	static const double fl[] = { -2.5, -2, -0.5, -0.0,	0,
				     0.5,  2,  2.5,  1e15 + 0.5 };
	for (size_t k = 0; k < sizeof(fl) / sizeof(fl[0]); k++)
		CHECK(glint_floor(fl[k]) == floor(fl[k]), "floor(%g) %g", fl[k],
		      glint_floor(fl[k]));
	CHECK(glint_clamp(-2, -1, 1) == -1 && glint_clamp(2, -1, 1) == 1 &&
		      glint_clamp(0.25, -1, 1) == 0.25 &&
		      glint_clamp(NAN, -1, 1) == -1,
	      "clamp (a NaN to the low end, as fmin(fmax()) gives)");
}

/* Directions to the map's (u, v) as envmap.c computes them. */
static void test_map_coordinates(void)
{
	unsigned long long st = 4;
	double worst = 0;
	for (int i = 0; i < 200000; i++) {
		struct vec3 d = v3_norm(v3(2 * draw(&st) - 1, 2 * draw(&st) - 1,
					   2 * draw(&st) - 1));
		double u, v;
		glint_latlong_dir_to_uv(d, &u, &v);
		double fu = 0.5 + glint_fast_atan2(d.x, -d.z) / (2 * M_PI);
		double fv = glint_fast_acos(d.y) / M_PI;
		double e = fmax(fabs(fu - u) * 1024, fabs(fv - v) * 512);
		worst = e > worst ? e : worst;
	}
	printf("map coordinates: largest error %.3g texel of a 1024 x 512 "
	       "map\n",
	       worst);
	CHECK(worst < 2e-6, "%g of a texel", worst);
}

int main(void)
{
	RUN(test_atan2);
	RUN(test_acos);
	RUN(test_sincos);
	RUN(test_exp_log);
	RUN(test_map_coordinates);
	return test_result();
}
