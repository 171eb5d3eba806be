/* SPDX-License-Identifier: MIT */
/*
 * Compact light sources in a mirror-ball photo (probe_sources.h): found,
 * measured, taken out of the photo before the unwrap and put back into
 * the map as points.
 */
#include "capture/probe/probe_sources.h"
#include "capture/probe/probe_internal.h"

#include "core/output.h"
#include "core/error.h"
#include "core/json.h"
#include "core/optics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define APERTURE 4 /* px: the source's light */
#define CORE	 2 /* px: where a compact source's light lies */
#define RING_IN	 5 /* px: the background ring */
#define RING_OUT 7

void glint_source_default_opts(struct glint_source_opts *o)
{
	o->min_contrast = 8;
	o->min_concentration = 0.7;
	o->min_share = 0.002;
}

static double luma(const float *p)
{
	return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/* What the photo's pixel (x, y) (its centre) shows of the light: the
 * direction, the solid angle of directions the pixel covers and the
 * ball's reflectance per channel; 0 where the pixel is off the ball or
 * beyond the grazing angle. */
struct px_geom {
	struct vec3 d;
	double omega, refl[3], span_rad;
};

static int pixel_geom(const struct probe_ball *b,
		      const struct glint_unwrap_opts *o, int x, int y,
		      struct px_geom *g)
{
	struct vec3 a, c, e, f;
	double ci, cj;
	double px = x + 0.5, py = y + 0.5;

	if (!glint_probe_ball_reflect(b, px, py, &g->d, &ci) ||
	    ci < cos(o->grazing_deg * M_PI / 180))
		return 0;
	if (!glint_probe_ball_reflect(b, px - 0.5, py, &a, &cj) ||
	    !glint_probe_ball_reflect(b, px + 0.5, py, &c, &cj) ||
	    !glint_probe_ball_reflect(b, px, py - 0.5, &e, &cj) ||
	    !glint_probe_ball_reflect(b, px, py + 0.5, &f, &cj))
		return 0;
	struct vec3 dx = v3_sub(c, a), dy = v3_sub(f, e);
	g->omega = v3_len(v3_cross(dx, dy));
	g->span_rad = fmax(v3_len(dx), v3_len(dy));
	for (int k = 0; k < 3; k++)
		g->refl[k] =
			o->reflectivity > 0
				? o->reflectivity
				: glint_fresnel_conductor(o->n[k], o->k[k], ci);
	return 1;
}

/*
 * A source's aperture and background ring may reach past the map's
 * grazing limit: a lamp behind the sample (the light 120-150 degrees from
 * the view) lies at 0.87-0.97 of the ball's radius, where the ball
 * compresses it into a few pixels whose 4-pixel aperture crosses the
 * 80-degree line.  Left in the photo, the unwrap stretches that spot over
 * degrees of the map and a glossy sphere's rim highlight under it is
 * fitted with too smooth a surface.  Their pixels count up to 89 degrees
 * of incidence (the ball's Fresnel and solid angle are still exact
 * there): the aperture's anywhere on the ball (a spot a few pixels inside
 * the rim loses nothing past it to the blur), the ring's only inside the
 * rim that the camera's blur mixes with the backdrop
 * (glint_unwrap_rim_margin_px()), where the background is the ball's.
 */
static int source_geom(const struct probe_ball *b,
		       const struct glint_unwrap_opts *o, int x, int y,
		       double margin, struct px_geom *g)
{
	struct glint_unwrap_opts so = *o;
	if (o->ball_r > 0 && hypot(x + 0.5 - o->ball_cx, y + 0.5 - o->ball_cy) >
				     o->ball_r - margin)
		return 0;
	so.grazing_deg = fmax(o->grazing_deg, 89);
	return pixel_geom(b, &so, x, y, g);
}

/* The median of n values (reorders them). */
static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* A plane a + b dx + c dy per channel fitted to the ring around (x0, y0)
 * by least squares; *rms the residual's RMS per channel, *n the ring's
 * pixels on the ball.  0 when the ring has too few. */
struct plane {
	double a[3], b[3], c[3], rms[3];
	int n;
};

/* Whether offset (dx, dy) from a candidate, pixel (x, y), is a usable
 * pixel of its background ring: in the photo, on the ball's usable part. */
static int ring_pixel(const struct glint_image *photo,
		      const struct probe_ball *b,
		      const struct glint_unwrap_opts *o, int dx, int dy, int x,
		      int y)
{
	struct px_geom g;
	int rr = dx * dx + dy * dy;
	return rr >= RING_IN * RING_IN && rr <= RING_OUT * RING_OUT && x >= 0 &&
	       y >= 0 && x < photo->width && y < photo->height &&
	       source_geom(b, o, x, y, glint_unwrap_rim_margin_px(o), &g);
}

static int ring_plane(const struct glint_image *photo,
		      const struct probe_ball *b,
		      const struct glint_unwrap_opts *o, int x0, int y0,
		      struct plane *pl)
{
	double m[3][3] = { { 0 } }, r[3][3] = { { 0 } };
	int n = 0;

	for (int dy = -RING_OUT; dy <= RING_OUT; dy++)
		for (int dx = -RING_OUT; dx <= RING_OUT; dx++) {
			int x = x0 + dx, y = y0 + dy;
			if (!ring_pixel(photo, b, o, dx, dy, x, y))
				continue;
			const float *p = glint_image_px(photo, x, y);
			double v[3] = { 1, dx, dy };
			for (int i = 0; i < 3; i++) {
				for (int j = 0; j < 3; j++)
					m[i][j] += v[i] * v[j];
				for (int c = 0; c < 3; c++)
					r[c][i] += v[i] * p[c];
			}
			n++;
		}
	if (n < 12)
		return 0;
	/* 3 x 3 solve by Cramer's rule (m is symmetric, well conditioned
	 * for a ring). */
	double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
		     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
		     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
	if (!(fabs(det) > 1e-9))
		return 0;
	for (int c = 0; c < 3; c++) {
		double sol[3];
		for (int k = 0; k < 3; k++) {
			double t[3][3];
			memcpy(t, m, sizeof(t));
			for (int i = 0; i < 3; i++)
				t[i][k] = r[c][i];
			sol[k] = (t[0][0] * (t[1][1] * t[2][2] -
					     t[1][2] * t[2][1]) -
				  t[0][1] * (t[1][0] * t[2][2] -
					     t[1][2] * t[2][0]) +
				  t[0][2] * (t[1][0] * t[2][1] -
					     t[1][1] * t[2][0])) /
				 det;
		}
		pl->a[c] = sol[0];
		pl->b[c] = sol[1];
		pl->c[c] = sol[2];
		pl->rms[c] = 0;
	}
	for (int dy = -RING_OUT; dy <= RING_OUT; dy++)
		for (int dx = -RING_OUT; dx <= RING_OUT; dx++) {
			int x = x0 + dx, y = y0 + dy;
			if (!ring_pixel(photo, b, o, dx, dy, x, y))
				continue;
			const float *p = glint_image_px(photo, x, y);
			for (int c = 0; c < 3; c++) {
				double e = p[c] - (pl->a[c] + pl->b[c] * dx +
						   pl->c[c] * dy);
				pl->rms[c] += e * e;
			}
		}
	for (int c = 0; c < 3; c++)
		pl->rms[c] = sqrt(pl->rms[c] / (n - 3 > 1 ? n - 3 : 1));
	pl->n = n;
	return 1;
}

/* The ring's median luminance around (x0, y0): the quick test. */
static double ring_median(const struct glint_image *photo, int x0, int y0)
{
	double v[4 * RING_OUT * RING_OUT * 4];
	int n = 0;
	for (int dy = -RING_OUT; dy <= RING_OUT; dy++)
		for (int dx = -RING_OUT; dx <= RING_OUT; dx++) {
			int rr = dx * dx + dy * dy, x = x0 + dx, y = y0 + dy;
			if (rr < RING_IN * RING_IN ||
			    rr > RING_OUT * RING_OUT || x < 0 || y < 0 ||
			    x >= photo->width || y >= photo->height)
				continue;
			v[n++] = luma(glint_image_px(photo, x, y));
		}
	if (n == 0)
		return INFINITY;
	qsort(v, (size_t)n, sizeof(double), cmp_double);
	return v[n / 2];
}

/* A candidate at (x0, y0) measured; 0 when it is not a compact source. */
static int measure(const struct glint_image *photo,
		   const struct glint_image *var, const struct glint_image *wt,
		   const struct probe_ball *b,
		   const struct glint_unwrap_opts *o,
		   const struct glint_source_opts *so, int x0, int y0,
		   struct glint_light_source *s, struct plane *pl)
{
	double f4[3] = { 0, 0, 0 }, f3[3] = { 0, 0, 0 }, v4[3] = { 0, 0, 0 };
	double geo[3] = { 0, 0, 0 }, core = 0, all = 0, span = 0;
	double cx = 0, cy = 0, wsum = 0;
	struct vec3 dsum = v3(0, 0, 0);
	int clipped = 0;

	if (!ring_plane(photo, b, o, x0, y0, pl))
		return 0;
	double bg_y = 0.2126 * pl->a[0] + 0.7152 * pl->a[1] + 0.0722 * pl->a[2];
	double peak = luma(glint_image_px(photo, x0, y0));
	if (!(peak > so->min_contrast * fmax(bg_y, 0)) || !(peak > 0))
		return 0;
	for (int dy = -APERTURE; dy <= APERTURE; dy++)
		for (int dx = -APERTURE; dx <= APERTURE; dx++) {
			int rr = dx * dx + dy * dy, x = x0 + dx, y = y0 + dy;
			struct px_geom g;
			if (rr > APERTURE * APERTURE)
				continue;
			/* the core must lie on the ball; the rest of the
			 * aperture may be cut by its rim (what lies past it
			 * is the blur's tail, 2 px and more from the spot;
			 * a cut beyond 3 px shows in the flux's convergence
			 * term) */
			if (x < 0 || y < 0 || x >= photo->width ||
			    y >= photo->height ||
			    !source_geom(b, o, x, y, 0, &g)) {
				if (rr <= CORE * CORE)
					return 0;
				continue;
			}
			const float *p = glint_image_px(photo, x, y);
			double ex[3], ey = 0;
			for (int c = 0; c < 3; c++) {
				double bg = pl->a[c] + pl->b[c] * dx +
					    pl->c[c] * dy;
				ex[c] = (p[c] - bg) * g.omega / g.refl[c];
				f4[c] += ex[c];
				if (rr <= 9)
					f3[c] += ex[c];
				geo[c] += g.omega / g.refl[c];
				if (var) {
					double sv =
						glint_image_px(var, x, y)[c] *
						g.omega / g.refl[c];
					v4[c] += sv * g.omega / g.refl[c];
				}
				if (wt && rr <= CORE * CORE &&
				    !(glint_image_px(wt, x, y)[c] > 0))
					clipped = 1;
			}
			ey = 0.2126 * ex[0] + 0.7152 * ex[1] + 0.0722 * ex[2];
			all += ey;
			if (rr <= CORE * CORE)
				core += ey;
			double w = fmax(ey, 0);
			dsum = v3_add(dsum, v3_scale(g.d, w));
			cx += w * dx;
			cy += w * dy;
			wsum += w;
			if (dx == 0 && dy == 0)
				span = g.span_rad;
		}
	/* A clipped core holds less than its share: the concentration
	 * cannot be judged, and the contrast against the ring (a light
	 * wider than the aperture lifts the ring too) stands alone. */
	if (!(all > 0) || !(wsum > 0) ||
	    (!clipped && core < so->min_concentration * all))
		return 0;
	memset(s, 0, sizeof(*s));
	s->photo_x = x0 + 0.5 + cx / wsum;
	s->photo_y = y0 + 0.5 + cy / wsum;
	/* The direction at the spot's centroid: the spread is the camera's
	 * and symmetric in the photo, not on the sphere of directions, where
	 * the ball compresses it towards its rim; a flux-weighted mean of
	 * directions would be pulled by that. */
	double ci;
	if (!glint_probe_ball_reflect(b, s->photo_x, s->photo_y, &s->dir, &ci))
		s->dir = v3_norm(dsum);
	double m2 = 0;
	for (int dy = -APERTURE; dy <= APERTURE; dy++)
		for (int dx = -APERTURE; dx <= APERTURE; dx++) {
			int x = x0 + dx, y = y0 + dy;
			struct px_geom g;
			if (dx * dx + dy * dy > APERTURE * APERTURE || x < 0 ||
			    y < 0 || x >= photo->width || y >= photo->height ||
			    !source_geom(b, o, x, y, 0, &g))
				continue;
			const float *p = glint_image_px(photo, x, y);
			double ey = 0;
			for (int c = 0; c < 3; c++)
				ey += (c == 0	? 0.2126
				       : c == 1 ? 0.7152
						: 0.0722) *
				      (p[c] - (pl->a[c] + pl->b[c] * dx +
					       pl->c[c] * dy)) *
				      g.omega / g.refl[c];
			double a = acos(fmin(1, v3_dot(g.d, s->dir)));
			m2 += fmax(ey, 0) * a * a;
		}
	s->size_deg = sqrt(m2 / wsum) * 180 / M_PI;
	s->px_deg = span * 180 / M_PI;
	s->contrast = bg_y > 0 ? peak / bg_y : INFINITY;
	s->saturated = clipped;
	double snr_y = 0;
	for (int c = 0; c < 3; c++) {
		/* the background under the spot: the plane's own error, and
		 * the sky's structure the plane leaves in the ring (its RMS),
		 * taken as half correlated across the aperture */
		double bg_mean = pl->rms[c] * geo[c] * sqrt(1.0 / pl->n + 0.25);
		double conv = f4[c] - f3[c];
		s->flux[c] = fmax(0, f4[c]); /* no light is negative */
		s->flux_sigma[c] =
			sqrt(v4[c] + bg_mean * bg_mean + conv * conv);
		snr_y += s->flux_sigma[c] > 0 ? f4[c] / s->flux_sigma[c] : 0;
	}
	snr_y /= 3;
	/* a quarter pixel of centroid error, plus the noise's share of the
	 * spot's size */
	double noise_px = snr_y > 0 ? s->size_deg / s->px_deg / snr_y : 0;
	s->dir_sigma_deg = s->px_deg * sqrt(0.0625 + noise_px * noise_px);
	return 1;
}

/* The photo's light over the usable ball: the integral of L d(omega)
 * that the pixels show (for each source's share). */
static void ball_flux(const struct glint_image *photo,
		      const struct probe_ball *b,
		      const struct glint_unwrap_opts *o, double f[3])
{
	f[0] = f[1] = f[2] = 0;
	for (int y = 0; y < photo->height; y++)
		for (int x = 0; x < photo->width; x++) {
			struct px_geom g;
			if (!pixel_geom(b, o, x, y, &g))
				continue;
			const float *p = glint_image_px(photo, x, y);
			for (int c = 0; c < 3; c++)
				f[c] += p[c] * g.omega / g.refl[c];
		}
}

/* A source found and what took it out of the photo: its peak pixel and
 * the background plane around it. */
struct candidate {
	struct glint_light_source s;
	struct plane pl;
	int x, y;
};

static double flux_y(const double f[3])
{
	return 0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2];
}

static int by_flux(const void *a, const void *b)
{
	const struct candidate *x = a, *y = b;
	double fx = flux_y(x->s.flux), fy = flux_y(y->s.flux);
	return (fx < fy) - (fx > fy);
}

/* The photo with each kept source's aperture (and a pixel more) replaced
 * by its background plane. */
static struct glint_image *clean_photo(const struct glint_image *photo,
				       const struct candidate *keep, int n)
{
	int w = photo->width, h = photo->height, r = APERTURE + 1;
	struct glint_image *cl = glint_image_new(w, h);
	if (!cl)
		return NULL;
	memcpy(cl->data, photo->data, (size_t)w * h * 3 * sizeof(float));
	for (int i = 0; i < n; i++) {
		const struct plane *pl = &keep[i].pl;
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++) {
				int x = keep[i].x + dx, y = keep[i].y + dy;
				if (dx * dx + dy * dy > r * r || x < 0 ||
				    y < 0 || x >= w || y >= h)
					continue;
				float *q = glint_image_px(cl, x, y);
				for (int c = 0; c < 3; c++)
					q[c] = (float)fmax(
						0, pl->a[c] + pl->b[c] * dx +
							   pl->c[c] * dy);
			}
	}
	return cl;
}

int glint_probe_find_sources(const struct glint_image *photo,
			     const struct glint_image *variance,
			     const struct glint_image *weights,
			     const struct glint_unwrap_opts *o,
			     const struct glint_source_opts *so,
			     struct glint_light_sources *out,
			     struct glint_image **cleaned)
{
	struct probe_ball b;
	enum { MAXC = 8 * GLINT_MAX_SOURCES };
	struct candidate *cand, keep[GLINT_MAX_SOURCES];
	int x0, x1, y0, y1, nc = 0, nk = 0, w = photo->width, h = photo->height;

	memset(out, 0, sizeof(*out));
	if (cleaned)
		*cleaned = NULL;
	/* the reflected direction turns by 2 / (R cos(theta / 2)) radians a
	 * pixel at theta from the axis: 2 sqrt 2 / R at 90 degrees */
	if (o->ball_r > 0)
		out->map_pixel_deg = 2 * sqrt(2.0) / o->ball_r * 180 / M_PI;
	if ((variance && (variance->width != w || variance->height != h)) ||
	    (weights && (weights->width != w || weights->height != h)))
		return glint_error_set(EINVAL,
				       "light sources: the variance or "
				       "weights image is not the photo's "
				       "size %dx%d",
				       w, h);
	int ret = glint_probe_ball_setup(photo, o, &b);
	if (ret < 0)
		return ret;
	if (!(cand = malloc(MAXC * sizeof(*cand))))
		return glint_error_set(ENOMEM, "light sources: out of memory");
	x0 = (int)fmax(0, floor(o->ball_cx - o->ball_r));
	x1 = (int)fmin(w - 1, ceil(o->ball_cx + o->ball_r));
	y0 = (int)fmax(0, floor(o->ball_cy - o->ball_r));
	y1 = (int)fmin(h - 1, ceil(o->ball_cy + o->ball_r));
	for (int y = y0; y <= y1 && nc < MAXC; y++)
		for (int x = x0; x <= x1 && nc < MAXC; x++) {
			double v = luma(glint_image_px(photo, x, y));
			int is_max = v > 0;
			/* a strict maximum of its 5 x 5 neighbourhood (the
			 * first of equal ones) */
			for (int dy = -2; is_max && dy <= 2; dy++)
				for (int dx = -2; is_max && dx <= 2; dx++) {
					int xx = x + dx, yy = y + dy;
					if ((!dx && !dy) || xx < 0 || yy < 0 ||
					    xx >= w || yy >= h)
						continue;
					double u = luma(
						glint_image_px(photo, xx, yy));
					if (u > v ||
					    (u == v &&
					     (dy < 0 || (!dy && dx < 0))))
						is_max = 0;
				}
			if (!is_max ||
			    !(v > so->min_contrast * ring_median(photo, x, y)))
				continue;
			struct candidate *c = &cand[nc];
			if (!measure(photo, variance, weights, &b, o, so, x, y,
				     &c->s, &c->pl))
				continue;
			c->x = x;
			c->y = y;
			nc++;
		}
	double total[3];
	ball_flux(photo, &b, o, total);
	/* the brightest first; one source per patch; a share of the light */
	qsort(cand, (size_t)nc, sizeof(cand[0]), by_flux);
	for (int i = 0; i < nc && nk < GLINT_MAX_SOURCES; i++) {
		int near = 0;
		for (int j = 0; j < nk; j++)
			if (hypot(keep[j].x - cand[i].x,
				  keep[j].y - cand[i].y) < 2 * RING_IN)
				near = 1;
		if (near ||
		    !(flux_y(cand[i].s.flux) >= so->min_share * flux_y(total)))
			continue;
		keep[nk++] = cand[i];
	}
	free(cand);
	for (int i = 0; i < nk; i++)
		out->s[i] = keep[i].s;
	out->n = nk;
	if (cleaned && !(*cleaned = clean_photo(photo, keep, nk)))
		return glint_error_set(ENOMEM, "light sources: out of memory");
	return 0;
}

void glint_latlong_flux(const struct glint_image *env, double flux[3])
{
	int w = env->width, h = env->height;
	flux[0] = flux[1] = flux[2] = 0;
	for (int y = 0; y < h; y++) {
		double om =
			(2 * M_PI / w) * (M_PI / h) * sin((y + 0.5) * M_PI / h);
		for (int x = 0; x < w; x++) {
			const float *p = glint_image_px(env, x, y);
			for (int c = 0; c < 3; c++)
				flux[c] += p[c] * om;
		}
	}
}

void glint_probe_add_sources(struct glint_image *env,
			     struct glint_light_sources *s)
{
	int w = env->width, h = env->height;
	for (int i = 0; i < s->n; i++) {
		double u, v;
		glint_latlong_dir_to_uv(s->s[i].dir, &u, &v);
		double fx = u * w - 0.5, fy = v * h - 0.5;
		fy = fmin(fmax(fy, 0), h - 1);
		int ix = (int)floor(fx), iy = (int)floor(fy);
		double tx = fx - ix, ty = fy - iy;
		for (int k = 0; k < 4; k++) {
			int xx = ix + (k & 1), yy = iy + (k >> 1);
			double wt = ((k & 1) ? tx : 1 - tx) *
				    ((k >> 1) ? ty : 1 - ty);
			if (yy >= h)
				yy = h - 1;
			xx = ((xx % w) + w) % w;
			double om = (2 * M_PI / w) * (M_PI / h) *
				    sin((yy + 0.5) * M_PI / h);
			float *p = glint_image_px(env, xx, yy);
			for (int c = 0; c < 3; c++)
				p[c] += (float)(wt * s->s[i].flux[c] / om);
		}
	}
	glint_latlong_flux(env, s->total_flux);
}

static json_t *triple(const double v[3])
{
	return glint_json_reals(v, 3);
}

int glint_probe_sources_write(const char *path, const char *photo,
			      const struct glint_light_sources *s)
{
	json_t *doc = json_object(), *arr = json_array();
	double ty = flux_y(s->total_flux);

	json_object_set_new(doc, "generator",
			    json_string(GLINT_OUTPUT_SOFTWARE));
	json_object_set_new(doc, "photo", json_string(photo ? photo : ""));
	json_object_set_new(
		doc, "what",
		json_string("light sources the probe photo does not resolve "
			    "(capture/probe/probe_sources.h): put into the "
			    "map as points; flux = integral of radiance "
			    "over solid angle in the map's units, sigmas 1 "
			    "standard deviation"));
	json_object_set_new(doc, "total_flux", triple(s->total_flux));
	if (s->map_pixel_deg > 0)
		json_object_set_new(doc, "map_pixel_deg",
				    json_real(s->map_pixel_deg));
	for (int i = 0; i < s->n; i++) {
		const struct glint_light_source *l = &s->s[i];
		json_t *o = json_object();
		double d[3] = { l->dir.x, l->dir.y, l->dir.z }, mean = 0;
		double colour[3], colour_sigma[3];
		for (int c = 0; c < 3; c++)
			mean += l->flux[c] / 3;
		for (int c = 0; c < 3; c++) {
			colour[c] = mean > 0 ? l->flux[c] / mean : 0;
			colour_sigma[c] =
				mean > 0 ? l->flux_sigma[c] / mean : 0;
		}
		json_object_set_new(o, "direction", triple(d));
		json_object_set_new(
			o, "azimuth_deg",
			json_real(atan2(l->dir.x, -l->dir.z) * 180 / M_PI));
		json_object_set_new(
			o, "elevation_deg",
			json_real(asin(fmax(-1, fmin(1, l->dir.y))) * 180 /
				  M_PI));
		json_object_set_new(o, "direction_sigma_deg",
				    glint_json_real_or_null(l->dir_sigma_deg));
		json_object_set_new(o, "flux", triple(l->flux));
		json_object_set_new(o, "flux_sigma", triple(l->flux_sigma));
		json_object_set_new(o, "colour", triple(colour));
		json_object_set_new(o, "colour_sigma", triple(colour_sigma));
		json_object_set_new(o, "share",
				    glint_json_real_or_null(
					    ty > 0 ? flux_y(l->flux) / ty : 0));
		json_object_set_new(o, "size_deg",
				    glint_json_real_or_null(l->size_deg));
		json_object_set_new(o, "pixel_deg",
				    glint_json_real_or_null(l->px_deg));
		double at[2] = { l->photo_x, l->photo_y };
		json_t *pa = json_array();
		for (int k = 0; k < 2; k++)
			json_array_append_new(pa, json_real(at[k]));
		json_object_set_new(o, "photo_px", pa);
		json_object_set_new(o, "contrast",
				    glint_json_real_or_null(l->contrast));
		json_object_set_new(o, "saturated", json_boolean(l->saturated));
		json_array_append_new(arr, o);
	}
	json_object_set_new(doc, "sources", arr);
	return glint_json_write_file(path, doc);
}

int glint_probe_sources_read(const char *path, struct glint_light_sources *s)
{
	static const char *const top[] = {
		"generator",	 "photo",   "what", "total_flux",
		"map_pixel_deg", "sources", NULL
	};
	const struct glint_range any = { -1e30, 1e30, 0, 0 };
	const struct glint_range pos = { 0, 1e30, 0, 0 };
	json_t *doc, *arr;
	int ret = glint_json_load(path, &doc);

	memset(s, 0, sizeof(*s));
	if (ret < 0)
		return ret;
	ret = glint_json_known_keys(path, "", doc, top);
	if (ret == 0)
		ret = glint_json_numbers(path, "", doc, "total_flux", 1, 3, pos,
					 s->total_flux);
	if (ret == 0)
		ret = glint_json_number(path, "", doc, "map_pixel_deg", 0,
					(struct glint_range){ 0, 180, 0, 0 },
					&s->map_pixel_deg);
	arr = json_object_get(doc, "sources");
	if (ret == 0 && !json_is_array(arr))
		ret = glint_error_set(EINVAL, "%s: sources: expected an array",
				      path);
	if (ret == 0 && json_array_size(arr) > GLINT_MAX_SOURCES)
		ret = glint_error_set(EINVAL,
				      "%s: sources: %zu entries: expected at "
				      "most %d",
				      path, json_array_size(arr),
				      GLINT_MAX_SOURCES);
	for (size_t i = 0; ret == 0 && i < json_array_size(arr); i++) {
		json_t *o = json_array_get(arr, i), *sat;
		struct glint_light_source *l = &s->s[i];
		char where[32];
		double d[3], xy[2] = { 0, 0 };
		snprintf(where, sizeof(where), "sources[%zu]", i);
		if (!json_is_object(o)) {
			ret = glint_error_set(EINVAL,
					      "%s: %s: expected an object",
					      path, where);
			break;
		}
		ret = glint_json_numbers(path, where, o, "direction", 1, 3, any,
					 d);
		if (ret == 0 &&
		    !(fabs(hypot(hypot(d[0], d[1]), d[2]) - 1) < 1e-3))
			ret = glint_error_set(EINVAL,
					      "%s: %s.direction: expected a "
					      "unit vector",
					      path, where);
		if (ret == 0)
			ret = glint_json_numbers(path, where, o, "flux", 1, 3,
						 pos, l->flux);
		if (ret == 0)
			ret = glint_json_numbers(path, where, o, "flux_sigma",
						 1, 3, pos, l->flux_sigma);
		if (ret == 0)
			ret = glint_json_number(
				path, where, o, "direction_sigma_deg", 1,
				(struct glint_range){ 0, 180, 0, 0 },
				&l->dir_sigma_deg);
		if (ret == 0)
			ret = glint_json_number(path, where, o, "size_deg", 0,
						pos, &l->size_deg);
		if (ret == 0)
			ret = glint_json_number(path, where, o, "pixel_deg", 0,
						pos, &l->px_deg);
		if (ret == 0)
			ret = glint_json_number(path, where, o, "contrast", 0,
						pos, &l->contrast);
		if (ret == 0)
			ret = glint_json_numbers(path, where, o, "photo_px", 0,
						 2, any, xy);
		sat = json_object_get(o, "saturated");
		if (ret == 0 && sat && !json_is_boolean(sat))
			ret = glint_error_set(EINVAL,
					      "%s: %s.saturated: expected true "
					      "or false",
					      path, where);
		if (ret < 0)
			break;
		l->dir = v3_norm(v3(d[0], d[1], d[2]));
		l->photo_x = xy[0];
		l->photo_y = xy[1];
		l->saturated = json_is_true(sat);
		s->n = (int)i + 1;
	}
	json_decref(doc);
	if (ret < 0)
		memset(s, 0, sizeof(*s));
	return ret;
}
