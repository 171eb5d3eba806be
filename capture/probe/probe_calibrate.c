/* SPDX-License-Identifier: MIT */
/*
 * A probe calibrated by a gray ball (probe_calibrate.h): per channel, the
 * linear least squares of the ball's pixels on the map's irradiance less
 * its sources and on each source's cosine.
 */
#define _DEFAULT_SOURCE
#include "capture/probe/probe_calibrate.h"
#include "capture/probe/probe_internal.h"

#include "core/error.h"
#include "core/json.h"
#include "core/output.h"

#include <gsl/gsl_multifit.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_PIXELS 4000
#define MAP_WIDTH  128
#define SECTORS	   8 /* of the ball, for the jackknife */

void glint_calibrate_default_opts(struct glint_calibrate_opts *o)
{
	memset(o, 0, sizeof(*o));
	for (int c = 0; c < 3; c++)
		o->albedo[c] = 0.18;
	o->max_radius = 0.9;
	o->max_rel_rms = 0.2;
}

/* The map less its sources, reduced: each texel's direction and its
 * radiance x solid angle. */
struct texels {
	int n;
	struct vec3 *dir;
	double (*ldw)[3];
};

static int rest_texels(const struct glint_image *env,
		       const struct glint_light_sources *src, struct texels *t)
{
	struct glint_image *rest = glint_image_dup(env), *small;
	if (!rest)
		return glint_error_set(ENOMEM, "calibrate: out of memory");
	if (src && src->n) {
		struct glint_light_sources neg = *src;
		for (int k = 0; k < neg.n; k++)
			for (int c = 0; c < 3; c++)
				neg.s[k].flux[c] = -neg.s[k].flux[c];
		glint_probe_add_sources(rest, &neg);
	}
	int f = env->width > MAP_WIDTH ? env->width / MAP_WIDTH : 1;
	small = f > 1 ? glint_image_downsample(rest, f) : rest;
	if (small != rest)
		glint_image_free(rest);
	if (!small)
		return glint_error_set(ENOMEM, "calibrate: out of memory");
	int w = small->width, h = small->height;
	t->dir = malloc(sizeof(*t->dir) * (size_t)w * h);
	t->ldw = malloc(sizeof(*t->ldw) * (size_t)w * h);
	t->n = 0;
	if (!t->dir || !t->ldw) {
		glint_image_free(small);
		return glint_error_set(ENOMEM, "calibrate: out of memory");
	}
	for (int j = 0; j < h; j++) {
		double om =
			(2 * M_PI / w) * (M_PI / h) * sin((j + 0.5) * M_PI / h);
		for (int i = 0; i < w; i++) {
			const float *p = glint_image_px(small, i, j);
			if (!(p[0] != 0 || p[1] != 0 || p[2] != 0))
				continue;
			t->dir[t->n] = glint_latlong_uv_to_dir((i + 0.5) / w,
							       (j + 0.5) / h);
			for (int c = 0; c < 3; c++)
				t->ldw[t->n][c] = p[c] * om;
			t->n++;
		}
	}
	glint_image_free(small);
	return 0;
}

/* The gray ball's usable pixels: normal and value. */
struct samples {
	int n;
	struct vec3 *normal;
	double (*value)[3];
	int *sector; /* of SECTORS around the ball's image centre */
};

static int gray_samples(const struct glint_image *gray,
			const struct glint_unwrap_opts *geom,
			const struct glint_calibrate_opts *o, struct samples *s)
{
	struct probe_ball b;
	int ret = glint_probe_ball_setup(gray, geom, &b);
	if (ret < 0)
		return glint_error_prefix(ret, "calibrate: the gray ball");
	double r = geom->ball_r * o->max_radius;
	int stride = (int)ceil(sqrt(M_PI * r * r / MAX_PIXELS));
	if (stride < 1)
		stride = 1;
	int x0 = (int)floor(geom->ball_cx - r),
	    x1 = (int)ceil(geom->ball_cx + r);
	int y0 = (int)floor(geom->ball_cy - r),
	    y1 = (int)ceil(geom->ball_cy + r);
	size_t cap = (size_t)((x1 - x0) / stride + 2) *
		     (size_t)((y1 - y0) / stride + 2);
	s->normal = malloc(sizeof(*s->normal) * cap);
	s->value = malloc(sizeof(*s->value) * cap);
	s->sector = malloc(sizeof(*s->sector) * cap);
	s->n = 0;
	if (!s->normal || !s->value || !s->sector)
		return glint_error_set(ENOMEM, "calibrate: out of memory");
	for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < gray->height; y += stride)
		for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < gray->width;
		     x += stride) {
			double dx = x + 0.5 - geom->ball_cx,
			       dy = y + 0.5 - geom->ball_cy;
			struct vec3 n, ray;
			if (dx * dx + dy * dy > r * r ||
			    !glint_probe_ball_normal(&b, x + 0.5, y + 0.5, &n,
						     &ray))
				continue;
			if (o->weights &&
			    !(glint_image_px(o->weights, x, y)[1] > 0))
				continue;
			const float *p = glint_image_px(gray, x, y);
			if (!isfinite(p[0]) || !isfinite(p[1]) ||
			    !isfinite(p[2]))
				continue;
			s->normal[s->n] = n;
			s->sector[s->n] = (int)((atan2(dy, dx) + M_PI) /
						(2 * M_PI) * SECTORS) %
					  SECTORS;
			for (int c = 0; c < 3; c++)
				s->value[s->n][c] = p[c];
			s->n++;
		}
	return 0;
}

/* One channel's least squares with the sources flagged free[k] as
 * unknowns and the rest folded into the scale's column at their probe
 * flux.  x[0] the scale, x[1 + j] the j-th free source's flux; se their
 * standard errors; *rms the residual's RMS. */
static int solve_channel(const struct samples *s, const double *erest,
			 const double *cosk,
			 const struct glint_light_sources *src,
			 const int *free_k, double rho, int c, double *x,
			 double *se, double *rms)
{
	int ns = src ? src->n : 0, p = 1;
	for (int k = 0; k < ns; k++)
		p += free_k[k];
	if (s->n <= p + 2)
		return glint_error_set(EINVAL,
				       "calibrate: %d pixels of the gray ball "
				       "for %d unknowns",
				       s->n, p);
	gsl_matrix *X = gsl_matrix_alloc((size_t)s->n, (size_t)p);
	gsl_vector *y = gsl_vector_alloc((size_t)s->n);
	gsl_vector *b = gsl_vector_alloc((size_t)p);
	gsl_matrix *cov = gsl_matrix_alloc((size_t)p, (size_t)p);
	gsl_multifit_linear_workspace *ws =
		gsl_multifit_linear_alloc((size_t)s->n, (size_t)p);
	double chisq = 0;
	int ret = 0;
	if (!X || !y || !b || !cov || !ws) {
		ret = glint_error_set(ENOMEM, "calibrate: out of memory");
		goto out;
	}
	for (int i = 0; i < s->n; i++) {
		double a0 = erest[i * 3 + c];
		int j = 1;
		for (int k = 0; k < ns; k++) {
			double v = cosk[(size_t)i * ns + k];
			if (free_k[k])
				gsl_matrix_set(X, (size_t)i, (size_t)j++,
					       rho / M_PI * v);
			else
				a0 += src->s[k].flux[c] * v;
		}
		gsl_matrix_set(X, (size_t)i, 0, rho / M_PI * a0);
		gsl_vector_set(y, (size_t)i, s->value[i][c]);
	}
	if (gsl_multifit_linear(X, y, b, cov, &chisq, ws)) {
		ret = glint_error_set(EDOM, "calibrate: the least squares of "
					    "the gray ball failed");
		goto out;
	}
	double var = chisq / (s->n - p);
	for (int j = 0; j < p; j++) {
		x[j] = gsl_vector_get(b, (size_t)j);
		se[j] = sqrt(fmax(
			0, var * gsl_matrix_get(cov, (size_t)j, (size_t)j)));
	}
	*rms = sqrt(chisq / s->n);
out:
	gsl_multifit_linear_free(ws);
	gsl_matrix_free(cov);
	gsl_vector_free(b);
	gsl_vector_free(y);
	gsl_matrix_free(X);
	return ret;
}

/* The least squares of green on the scale's column and each source's
 * vector G = F d (lit sides from the directions d), leaving out the
 * pixels of sector `skip` (-1: none).  b gets the solution; *d_out (may
 * be NULL) the directions G / |G|, *var the residual's variance. */
static int solve_vectors(const struct samples *s, const double *erest,
			 double rho, const struct vec3 *d, int ns, int skip,
			 gsl_matrix *X, gsl_vector *y, gsl_vector *w,
			 gsl_vector *b, gsl_matrix *cov,
			 gsl_multifit_linear_workspace *ws, double *var)
{
	int p = 1 + 3 * ns, used = 0;
	double chisq;
	gsl_matrix_set_zero(X);
	for (int i = 0; i < s->n; i++) {
		int in = s->sector[i] != skip;
		used += in;
		gsl_vector_set(w, (size_t)i, in);
		gsl_matrix_set(X, (size_t)i, 0, rho / M_PI * erest[i * 3 + 1]);
		gsl_vector_set(y, (size_t)i, s->value[i][1]);
		for (int k = 0; k < ns; k++) {
			struct vec3 n = s->normal[i];
			if (v3_dot(n, d[k]) <= 0)
				continue;
			double a[3] = { n.x, n.y, n.z };
			for (int q = 0; q < 3; q++)
				gsl_matrix_set(X, (size_t)i,
					       (size_t)(1 + 3 * k + q),
					       rho / M_PI * a[q]);
		}
	}
	if (used <= p + 2 || gsl_multifit_wlinear(X, w, y, b, cov, &chisq, ws))
		return glint_error_set(EDOM, "calibrate: the least squares of "
					     "the gray ball failed");
	*var = chisq / (used - p);
	return 0;
}

static struct vec3 vector_of(const gsl_vector *b, int k, double *len)
{
	size_t o = (size_t)(1 + 3 * k);
	struct vec3 g = v3(gsl_vector_get(b, o), gsl_vector_get(b, o + 1),
			   gsl_vector_get(b, o + 2));
	*len = sqrt(v3_dot(g, g));
	return *len > 0 ? v3_scale(g, 1 / *len) : v3(0, 0, 0);
}

/*
 * Each source's direction as the gray ball's shading shows it.  On the
 * side a source lights, its share of the shading is rho / pi n . (F d):
 * linear in the vector G = F d.  Least squares of green on the scale's
 * column and each source's G (lit sides from the directions so far),
 * three rounds; a direction moves to G / |G| where the gray ball knows it
 * better than the probe did.  A sun's direction off by a degree moves
 * the scale by about 10 %: the two columns are nearly collinear over the
 * lit half, so the direction is measured rather than taken from a
 * clipped spot's centroid.  The standard errors of the direction, of the
 * scale and of each |G| are the larger of the least squares' and a
 * jackknife's over eight sectors of the ball's image: the residual is
 * not independent noise where the map's light is slightly off, and the
 * jackknife sees how far the answer depends on which part of the ball
 * shows it.
 */
static int refine_directions(const struct samples *s, const double *erest,
			     double rho, struct glint_light_sources *src,
			     double *scale_rel, double *flux_rel)
{
	int ns = src->n, p = 1 + 3 * ns;
	gsl_matrix *X = gsl_matrix_alloc((size_t)s->n, (size_t)p);
	gsl_vector *y = gsl_vector_alloc((size_t)s->n);
	gsl_vector *w = gsl_vector_alloc((size_t)s->n);
	gsl_vector *b = gsl_vector_alloc((size_t)p);
	gsl_matrix *cov = gsl_matrix_alloc((size_t)p, (size_t)p);
	gsl_multifit_linear_workspace *ws =
		gsl_multifit_linear_alloc((size_t)s->n, (size_t)p);
	struct vec3 d[GLINT_MAX_SOURCES];
	double sig[GLINT_MAX_SOURCES], len[GLINT_MAX_SOURCES], var = 0, s0;
	int ret = 0;

	if (!X || !y || !w || !b || !cov || !ws) {
		ret = glint_error_set(ENOMEM, "calibrate: out of memory");
		goto out;
	}
	for (int k = 0; k < ns; k++)
		d[k] = src->s[k].dir;
	for (int round = 0; round < 3; round++) {
		ret = solve_vectors(s, erest, rho, d, ns, -1, X, y, w, b, cov,
				    ws, &var);
		if (ret < 0)
			goto out;
		for (int k = 0; k < ns; k++) {
			struct vec3 g = vector_of(b, k, &len[k]);
			if (len[k] > 0)
				d[k] = g;
		}
	}
	/* the least squares' standard errors */
	s0 = gsl_vector_get(b, 0);
	*scale_rel = sqrt(fmax(0, var * gsl_matrix_get(cov, 0, 0))) / fabs(s0);
	for (int k = 0; k < ns; k++) {
		size_t o = (size_t)(1 + 3 * k);
		struct vec3 t, bt;
		double da[3] = { d[k].x, d[k].y, d[k].z }, ta[3], ba[3];
		double vd = 0, vt = 0, vb = 0;
		v3_frame(d[k], &t, &bt);
		ta[0] = t.x, ta[1] = t.y, ta[2] = t.z;
		ba[0] = bt.x, ba[1] = bt.y, ba[2] = bt.z;
		for (int q = 0; q < 3; q++)
			for (int r = 0; r < 3; r++) {
				double c =
					var * gsl_matrix_get(cov, o + q, o + r);
				vd += da[q] * c * da[r];
				vt += ta[q] * c * ta[r];
				vb += ba[q] * c * ba[r];
			}
		flux_rel[k] =
			len[k] > 0 ? sqrt(fmax(0, vd)) / len[k] : INFINITY;
		sig[k] = len[k] > 0 ? sqrt(fmax(0, (vt + vb) / 2)) / len[k]
				    : INFINITY;
	}
	/* the jackknife's */
	double js = 0, jd[GLINT_MAX_SOURCES] = { 0 },
	       jf[GLINT_MAX_SOURCES] = { 0 };
	for (int g = 0; g < SECTORS; g++) {
		double v;
		if (solve_vectors(s, erest, rho, d, ns, g, X, y, w, b, cov, ws,
				  &v) < 0) {
			glint_error_clear();
			continue;
		}
		double ds = gsl_vector_get(b, 0) / s0 - 1;
		js += ds * ds;
		for (int k = 0; k < ns; k++) {
			double l;
			struct vec3 dg = vector_of(b, k, &l);
			double a = acos(fmin(1, v3_dot(dg, d[k])));
			jd[k] += a * a;
			if (len[k] > 0)
				jf[k] += (l / len[k] - 1) * (l / len[k] - 1);
		}
	}
	const double jk = (SECTORS - 1.0) / SECTORS;
	*scale_rel = fmax(*scale_rel, sqrt(jk * js));
	for (int k = 0; k < ns; k++) {
		/* across two axes: half the squared angle on each */
		sig[k] = fmax(sig[k], sqrt(jk * jd[k] / 2)) * 180 / M_PI;
		flux_rel[k] = fmax(flux_rel[k], sqrt(jk * jf[k]));
		if (sig[k] < src->s[k].dir_sigma_deg) {
			src->s[k].dir = d[k];
			src->s[k].dir_sigma_deg = sig[k];
		}
	}
out:
	gsl_multifit_linear_free(ws);
	gsl_matrix_free(cov);
	gsl_vector_free(b);
	gsl_vector_free(w);
	gsl_vector_free(y);
	gsl_matrix_free(X);
	return ret;
}

int glint_probe_calibrate(const struct glint_image *env,
			  const struct glint_light_sources *src,
			  const struct glint_image *gray,
			  const struct glint_unwrap_opts *geom,
			  const struct glint_calibrate_opts *o,
			  struct glint_calibration *cal)
{
	struct texels t = { 0 };
	struct samples s = { 0 };
	struct glint_light_sources moved;
	double *erest = NULL, *cosk = NULL;
	int ns = src ? src->n : 0, free_k[GLINT_MAX_SOURCES];
	int ret;

	memset(cal, 0, sizeof(*cal));
	for (int c = 0; c < 3; c++)
		if (!(o->albedo[c] > 0 && o->albedo[c] <= 1) ||
		    !(o->albedo_sigma[c] >= 0))
			return glint_error_set(EINVAL,
					       "calibrate: gray ball albedo "
					       "%g (sigma %g): expected 0 to "
					       "1, sigma >= 0",
					       o->albedo[c],
					       o->albedo_sigma[c]);
	if (!env || abs(env->width - 2 * env->height) > 2)
		return glint_error_set(EINVAL,
				       "calibrate: the probe is not a 2:1 "
				       "lat-long map");
	ret = rest_texels(env, src, &t);
	if (ret == 0)
		ret = gray_samples(gray, geom, o, &s);
	if (ret < 0)
		goto out;
	if (s.n < 50) {
		ret = glint_error_set(EINVAL,
				      "calibrate: the gray ball shows %d "
				      "usable pixels (at least 50: a larger "
				      "ball, or fewer clipped pixels)",
				      s.n);
		goto out;
	}
	erest = calloc((size_t)s.n * 3, sizeof(double));
	cosk = calloc((size_t)s.n * (ns ? ns : 1), sizeof(double));
	if (!erest || !cosk) {
		ret = glint_error_set(ENOMEM, "calibrate: out of memory");
		goto out;
	}
	for (int i = 0; i < s.n; i++)
		for (int j = 0; j < t.n; j++) {
			double d = v3_dot(s.normal[i], t.dir[j]);
			if (d <= 0)
				continue;
			for (int c = 0; c < 3; c++)
				erest[i * 3 + c] += d * t.ldw[j][c];
		}
	double scale_rel = 0, flux_rel[GLINT_MAX_SOURCES] = { 0 };
	if (ns) {
		moved = *src;
		src = &moved;
		ret = refine_directions(&s, erest, o->albedo[1], &moved,
					&scale_rel, flux_rel);
		if (ret < 0)
			goto out;
	}
	for (int i = 0; i < s.n; i++) {
		for (int k = 0; k < ns; k++)
			cosk[(size_t)i * ns + k] =
				fmax(0, v3_dot(s.normal[i], src->s[k].dir));
	}
	for (int k = 0; k < ns; k++)
		free_k[k] = 1;
	/* Fold the sources the gray ball sees no better than the probe,
	 * by green, until none changes. */
	double x[3][1 + GLINT_MAX_SOURCES], se[3][1 + GLINT_MAX_SOURCES];
	double rms[3];
	/* xf, sf: the first round's, every source free: each source's flux
	 * as the gray ball alone sees it */
	double xf[3][1 + GLINT_MAX_SOURCES], sf[3][1 + GLINT_MAX_SOURCES];
	for (int round = 0; round <= ns; round++) {
		for (int c = 0; c < 3 && ret == 0; c++)
			ret = solve_channel(&s, erest, cosk, src, free_k,
					    o->albedo[c], c, x[c], se[c],
					    &rms[c]);
		if (ret < 0)
			goto out;
		if (round == 0) {
			memcpy(xf, x, sizeof(xf));
			memcpy(sf, se, sizeof(sf));
		}
		int changed = 0;
		for (int k = 0, j = 1; k < ns; k++) {
			if (!free_k[k])
				continue;
			const struct glint_light_source *l = &src->s[k];
			double probe_se = x[1][0] * l->flux_sigma[1];
			if (x[1][j] < 0 ||
			    (!l->saturated && se[1][j] >= probe_se)) {
				free_k[k] = 0;
				changed = 1;
			}
			j++;
		}
		if (!changed)
			break;
	}
	cal->pixels = s.n;
	cal->nsources = ns;
	for (int c = 0; c < 3; c++) {
		double mean = 0;
		for (int i = 0; i < s.n; i++)
			mean += s.value[i][c] / s.n;
		double ra = o->albedo_sigma[c] / o->albedo[c];
		cal->albedo[c] = o->albedo[c];
		cal->albedo_sigma[c] = o->albedo_sigma[c];
		cal->rel_rms[c] = mean > 0 ? rms[c] / mean : INFINITY;
		cal->scale[c] = x[c][0];
		/* the larger of the fit's with the directions held and the
		 * one where they were free (the columns' near-collinearity) */
		cal->scale_sigma[c] = hypot(fmax(se[c][0], x[c][0] * scale_rel),
					    x[c][0] * ra);
		for (int k = 0, j = 1; k < ns; k++) {
			struct glint_calibrated_source *cs = &cal->src[k];
			const struct glint_light_source *l = &src->s[k];
			cs->flux_probe[c] = l->flux[c];
			cs->dir = l->dir;
			cs->dir_sigma_deg = l->dir_sigma_deg;
			cs->saturated = l->saturated;
			cs->from_gray = free_k[k];
			/* the gray ball's flux alone (every source free),
			 * its standard error with the directions' freedom
			 * and the albedo's */
			double g = xf[c][1 + k],
			       gs = hypot(fmax(sf[c][1 + k],
					       fabs(g) * flux_rel[k]),
					  fabs(g) * ra);
			if (free_k[k]) {
				cs->flux[c] = x[c][j];
				cs->flux_sigma[c] = hypot(
					fmax(se[c][j], x[c][j] * flux_rel[k]),
					x[c][j] * ra);
				j++;
			} else {
				/* the probe's, scaled, and the gray ball's
				 * by their inverse variances: blue a mosaic
				 * aliased to nothing is the gray ball's */
				double pf = x[c][0] * l->flux[c];
				double ps = hypot(
					x[c][0] * l->flux_sigma[c],
					pf * hypot(ra, se[c][0] / x[c][0]));
				double wp = ps > 0 ? 1 / (ps * ps) : 0,
				       wg = gs > 0 ? 1 / (gs * gs) : 0;
				if (!(wp + wg > 0))
					wp = 1;
				cs->flux[c] =
					fmax(0, (wp * pf + wg * g) / (wp + wg));
				cs->flux_sigma[c] = 1 / sqrt(wp + wg);
			}
		}
	}
	for (int c = 0; c < 3; c++) {
		if (!(cal->rel_rms[c] <= o->max_rel_rms)) {
			ret = glint_error_set(
				EINVAL,
				"calibrate: the gray ball is not what a matte "
				"ball shows under this probe (relative RMS "
				"%.3f "
				"in channel %d, at most %.3f): another camera "
				"frame, a glossy ball or the wrong circle?",
				cal->rel_rms[c], c, o->max_rel_rms);
			goto out;
		}
		if (!(cal->scale[c] >= 0.2 && cal->scale[c] <= 5)) {
			ret = glint_error_set(
				EINVAL,
				"calibrate: the probe and the gray ball differ "
				"by x %.3g in channel %d (0.2 to 5 expected): "
				"is the albedo %.3g right, and were both "
				"photographed at one exposure scale?",
				cal->scale[c], c, o->albedo[c]);
			goto out;
		}
	}
out:
	free(erest);
	free(cosk);
	free(t.dir);
	free(t.ldw);
	free(s.normal);
	free(s.value);
	free(s.sector);
	return ret;
}

void glint_probe_calibration_apply(const struct glint_calibration *cal,
				   struct glint_image *env,
				   struct glint_light_sources *src)
{
	size_t n = (size_t)env->width * env->height;
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++)
			env->data[i * 3 + c] *= (float)cal->scale[c];
	if (!src)
		return;
	/* each source's probe flux, scaled, out where the probe put it; the
	 * calibrated flux in where the gray ball puts it */
	struct glint_light_sources out = *src, in = *src;
	for (int k = 0; k < src->n && k < cal->nsources; k++) {
		for (int c = 0; c < 3; c++)
			out.s[k].flux[c] = -cal->scale[c] * src->s[k].flux[c];
		memcpy(in.s[k].flux, cal->src[k].flux, sizeof(double) * 3);
		in.s[k].dir = cal->src[k].dir;
	}
	glint_probe_add_sources(env, &out);
	glint_probe_add_sources(env, &in);
	for (size_t i = 0; i < n * 3; i++)
		if (env->data[i] < 0) /* rounding where a splat came out */
			env->data[i] = 0;
	for (int k = 0; k < src->n && k < cal->nsources; k++) {
		memcpy(src->s[k].flux, cal->src[k].flux, sizeof(double) * 3);
		memcpy(src->s[k].flux_sigma, cal->src[k].flux_sigma,
		       sizeof(double) * 3);
		src->s[k].dir = cal->src[k].dir;
		src->s[k].dir_sigma_deg = cal->src[k].dir_sigma_deg;
		if (cal->src[k].from_gray)
			src->s[k].saturated = 0;
	}
	glint_latlong_flux(env, src->total_flux);
}

static json_t *triple(const double v[3])
{
	return glint_json_reals(v, 3);
}

int glint_probe_calibration_write(const char *path, const char *probe,
				  const char *gray,
				  const struct glint_calibration *cal)
{
	json_t *doc = json_object(), *arr = json_array();

	json_object_set_new(doc, "generator",
			    json_string(GLINT_OUTPUT_SOFTWARE));
	json_object_set_new(doc, "probe", json_string(probe ? probe : ""));
	json_object_set_new(doc, "gray_ball", json_string(gray ? gray : ""));
	json_object_set_new(
		doc, "what",
		json_string("the probe's scale and its compact sources' flux "
			    "as a matte ball of known albedo saw them "
			    "(capture/probe/probe_calibrate.h); sigmas 1 "
			    "standard deviation"));
	json_object_set_new(doc, "albedo", triple(cal->albedo));
	json_object_set_new(doc, "albedo_sigma", triple(cal->albedo_sigma));
	json_object_set_new(doc, "pixels", json_integer(cal->pixels));
	json_object_set_new(doc, "relative_rms", triple(cal->rel_rms));
	json_object_set_new(doc, "scale", triple(cal->scale));
	json_object_set_new(doc, "scale_sigma", triple(cal->scale_sigma));
	for (int k = 0; k < cal->nsources; k++) {
		const struct glint_calibrated_source *cs = &cal->src[k];
		json_t *o = json_object();
		double d[3] = { cs->dir.x, cs->dir.y, cs->dir.z };
		json_object_set_new(o, "direction", triple(d));
		json_object_set_new(o, "direction_sigma_deg",
				    glint_json_real_or_null(cs->dir_sigma_deg));
		json_object_set_new(o, "flux_probe", triple(cs->flux_probe));
		json_object_set_new(o, "flux", triple(cs->flux));
		json_object_set_new(o, "flux_sigma", triple(cs->flux_sigma));
		json_object_set_new(
			o, "from",
			json_string(cs->from_gray ? "gray ball" : "probe"));
		json_object_set_new(o, "saturated_in_probe",
				    json_boolean(cs->saturated));
		json_array_append_new(arr, o);
	}
	json_object_set_new(doc, "sources", arr);
	return glint_json_write_file(path, doc);
}
