/* SPDX-License-Identifier: MIT */
#include "misfit.h"

#include "core/error.h"
#include "core/json.h"

#include <stdlib.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static const double view_edges[GLINT_MISFIT_BANDS + 1] = { 0,  10, 20, 30, 40,
							   50, 60, 70, 80, 90 };
static const double mirror_edges[GLINT_MISFIT_BANDS + 1] = { 0,	  2,  5,  10,
							     20,  40, 60, 90,
							     120, 180 };

struct acc {
	double s, s2, c2;
	long n;
};

/* The map's brightest direction: the texel of most power (radiance x
 * solid angle). */
struct vec3 glint_misfit_light(const struct glint_envmap *env)
{
	const struct glint_image *img = env->img;
	double best = -1;
	int bi = 0, bj = 0;

	for (int j = 0; j < img->height; j++) {
		double dom = sin(M_PI * (j + 0.5) / img->height);
		for (int i = 0; i < img->width; i++) {
			const float *p = glint_image_px(img, i, j);
			double y = rgb_luminance(p[0], p[1], p[2]) * dom;
			if (y > best) {
				best = y;
				bi = i;
				bj = j;
			}
		}
	}
	return m3_mul(&env->rot,
		      glint_latlong_uv_to_dir((bi + 0.5) / img->width,
					      (bj + 0.5) / img->height));
}

static int band_of(const double *edges, double a)
{
	for (int b = 0; b < GLINT_MISFIT_BANDS; b++)
		if (a < edges[b + 1])
			return b;
	return GLINT_MISFIT_BANDS - 1;
}

/* A pixel's mean normal and view direction (towards the camera) from
 * its spp hits hs. */
static void pixel_geometry(const struct glint_hit *hs, int spp, struct vec3 *n,
			   struct vec3 *wo)
{
	struct vec3 sn = v3(0, 0, 0), sd = v3(0, 0, 0);

	for (int s = 0; s < spp; s++) {
		const struct glint_hit *h = &hs[s];
		sn = v3_add(sn, v3(h->n[0], h->n[1], h->n[2]));
		sd = v3_add(sd, v3(h->d[0], h->d[1], h->d[2]));
	}
	*n = v3_norm(sn);
	*wo = v3_scale(v3_norm(sd), -1);
}

void glint_misfit_bands(const struct glint_hit *hs, int spp, struct vec3 light,
			int *view_band, int *mirror_band)
{
	struct vec3 n, wo;

	pixel_geometry(hs, spp, &n, &wo);
	double cv = fmin(1, fmax(-1, v3_dot(n, wo)));
	struct vec3 refl = v3_sub(v3_scale(n, 2 * cv), wo);
	*view_band = band_of(view_edges, acos(cv) * 180 / M_PI);
	*mirror_band = band_of(mirror_edges,
			       acos(fmin(1, fmax(-1, v3_dot(refl, light)))) *
				       180 / M_PI);
}

static void finish_bands(const struct acc *a, const double *edges, int weighted,
			 struct glint_misfit_band *b)
{
	for (int k = 0; k < GLINT_MISFIT_BANDS; k++) {
		b[k].lo_deg = edges[k];
		b[k].hi_deg = edges[k + 1];
		b[k].n = a[k].n;
		b[k].mean = a[k].n ? a[k].s / a[k].n : NAN;
		double var = a[k].n > 1 ? (a[k].s2 - a[k].s * b[k].mean) /
						  (a[k].n - 1)
					: NAN;
		b[k].se = a[k].n > 1 ? sqrt(fmax(var, 0) / a[k].n) : NAN;
		b[k].chi2 = weighted && a[k].n ? a[k].c2 / (3.0 * a[k].n) : NAN;
	}
}

/* The band most off zero, in standard errors (among bands of >= 20
 * pixels). */
static double worst_band(const struct glint_misfit_band *b, int *which)
{
	double z = 0;

	*which = -1;
	for (int k = 0; k < GLINT_MISFIT_BANDS; k++) {
		if (b[k].n < 20 || !(b[k].se > 0))
			continue;
		double zk = fabs(b[k].mean) / b[k].se;
		if (zk > z) {
			z = zk;
			*which = k;
		}
	}
	return z;
}

/* "too dark 70-80 deg from the view direction, near the rim (34
 * standard errors)" for band b of axis `view` (1) or mirror (0). */
static void describe(const struct glint_misfit_band *b, int view, double z,
		     char *buf, size_t n)
{
	const char *where = view ? (b->lo_deg >= 60   ? ", near the rim"
				    : b->hi_deg <= 30 ? ", at the centre"
						      : "")
			    : b->hi_deg <= 10 ? ", in the highlight"
			    : b->hi_deg <= 40 ? ", in the lobe's tail"
					      : ", away from the highlight";

	snprintf(buf, n,
		 "too %s %g-%g deg from the %s%s (%.0f standard errors)",
		 b->mean > 0 ? "bright" : "dark", b->lo_deg, b->hi_deg,
		 view ? "view direction"
		      : "mirror direction of the brightest "
			"light",
		 where, z);
}

static void verdict(struct glint_misfit *m)
{
	int kv, km;
	double zv = worst_band(m->view, &kv), zm = worst_band(m->mirror, &km);
	int noisy = !m->weighted || m->chi2 > 1.5;
	char a[160], b[160];

	m->structured = (zv > 5 || zm > 5) && noisy;
	if (kv >= 0)
		describe(&m->view[kv], 1, zv, a, sizeof(a));
	if (km >= 0)
		describe(&m->mirror[km], 0, zm, b, sizeof(b));
	if (m->structured && zv > 5 && zm > 5)
		snprintf(m->verdict, sizeof(m->verdict),
			 "structured residual, the model is too simple (or "
			 "the scene is not the photo's): the "
			 "render is %s; %s",
			 zv >= zm ? a : b, zv >= zm ? b : a);
	else if (m->structured)
		snprintf(m->verdict, sizeof(m->verdict),
			 "structured residual, the model is too simple (or "
			 "the scene is not the photo's): the "
			 "render is %s",
			 zv > 5 ? a : b);
	else if (m->weighted && m->chi2 > 1.5)
		snprintf(m->verdict, sizeof(m->verdict),
			 "residual %.1f times the noise's variance, without "
			 "structure in either angle",
			 m->chi2);
	else
		snprintf(m->verdict, sizeof(m->verdict), "%s",
			 m->weighted ? "residual at the noise floor"
				     : "no structure in either angle (no noise "
				       "model to compare with)");
}

int glint_misfit_analyse(const struct glint_gbuffer *gb,
			 const struct glint_envmap *env,
			 const struct glint_image *photo,
			 const struct glint_image *render,
			 const struct glint_image *weight,
			 const struct glint_image *cov, double render_noise,
			 struct glint_misfit *m)
{
	int w = photo->width, h = photo->height;
	struct acc av[GLINT_MISFIT_BANDS] = { { 0 } };
	struct acc am[GLINT_MISFIT_BANDS] = { { 0 } };
	double level = 0, c2 = 0;
	long np = 0;

	memset(m, 0, sizeof(*m));
	if (render->width != w || render->height != h || cov->width != w ||
	    cov->height != h || gb->width != w || gb->height != h ||
	    (weight && (weight->width != w || weight->height != h)))
		return glint_error_set(EINVAL, "misfit: images of different "
					       "sizes");
	m->weighted = weight != NULL;
	m->render_noise =
		render_noise >= 0 && isfinite(render_noise) ? render_noise : 0;
	/* a weight is 1 / the photo's variance; the residual's is the
	 * photo's and the render's */
	double wscale = 1 / (1 + m->render_noise);
	/* The photo's mean on the sphere, over its valid (finite) values:
	 * invalid pixels carry NaN and weight 0. */
	for (size_t i = 0; i < (size_t)w * h; i++) {
		const float *ph = photo->data + 3 * i;
		double v = (ph[0] + ph[1] + ph[2]) / 3.0;
		if (cov->data[3 * i] >= 0.999f && isfinite(v)) {
			level += v;
			np++;
		}
	}
	if (!np || !(level > 0))
		return glint_error_set(EINVAL, "misfit: no lit pixel wholly "
					       "on the sphere");
	level /= np;
	struct vec3 light = glint_misfit_light(env);
	m->light[0] = light.x;
	m->light[1] = light.y;
	m->light[2] = light.z;
	/* A sparse G-buffer's rows are traced again as they are read. */
	struct glint_hit *buf =
		gb->hits ? NULL : malloc((size_t)w * gb->spp * sizeof(*buf));
	if (!gb->hits && !buf)
		return glint_error_set(ENOMEM, "out of memory");
	const struct glint_hit *row = NULL;
	int row_y = -1;
	for (size_t i = 0; i < (size_t)w * h; i++) {
		if (cov->data[3 * i] < 0.999f)
			continue;
		double r = 0, rr = 0;
		int used = 0;
		for (int c = 0; c < 3; c++) {
			double d = render->data[3 * i + c] -
				   photo->data[3 * i + c];
			double wt =
				weight ? weight->data[3 * i + c] * wscale : 1;
			if (!isfinite(d) || !(wt > 0))
				continue;
			d = weight ? d * sqrt(wt) : d / level;
			r += d;
			rr += d * d;
			used++;
		}
		if (!used)
			continue;
		r /= used;
		if ((int)(i / (size_t)w) != row_y) {
			row_y = (int)(i / (size_t)w);
			row = glint_gbuffer_row(gb, row_y, buf);
		}
		int kv, km;
		glint_misfit_bands(row + i % (size_t)w * gb->spp, gb->spp,
				   light, &kv, &km);
		struct acc *bv = &av[kv], *bm = &am[km];
		bv->s += r;
		bv->s2 += r * r;
		bv->c2 += rr * 3.0 / used;
		bv->n++;
		bm->s += r;
		bm->s2 += r * r;
		bm->c2 += rr * 3.0 / used;
		bm->n++;
		c2 += rr / used;
	}
	free(buf);
	long total = 0;
	for (int k = 0; k < GLINT_MISFIT_BANDS; k++)
		total += av[k].n;
	m->chi2 = m->weighted && total ? c2 / total : NAN;
	finish_bands(av, view_edges, m->weighted, m->view);
	finish_bands(am, mirror_edges, m->weighted, m->mirror);
	verdict(m);
	return 0;
}

static json_t *bands_json(const struct glint_misfit_band *b)
{
	json_t *arr = json_array();

	for (int k = 0; k < GLINT_MISFIT_BANDS; k++)
		json_array_append_new(
			arr, json_pack("{s:[f,f], s:I, s:o, s:o, s:o}", "deg",
				       b[k].lo_deg, b[k].hi_deg, "pixels",
				       (json_int_t)b[k].n, "mean_residual",
				       glint_json_real_or_null(b[k].mean),
				       "standard_error",
				       glint_json_real_or_null(b[k].se),
				       "chi2_per_value",
				       glint_json_real_or_null(b[k].chi2)));
	return arr;
}

json_t *glint_misfit_json(const struct glint_misfit *m)
{
	return json_pack(
		"{s:s, s:b, s:s, s:f, s:o, s:[f,f,f], s:o, s:o}", "verdict",
		m->verdict, "structured", m->structured, "residual",
		m->weighted ? "render - photo, in standard deviations of the "
			      "photo's noise and the render's"
			    : "render - photo, over the photo's mean on the "
			      "sphere",
		"render_noise", m->render_noise, "chi2_per_value",
		glint_json_real_or_null(m->chi2), "light_direction",
		m->light[0], m->light[1], m->light[2], "by_view_angle",
		bands_json(m->view), "by_mirror_angle", bands_json(m->mirror));
}
