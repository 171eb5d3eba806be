/* SPDX-License-Identifier: MIT */
#include "envmap.h"

#include "core/error.h"
#include "core/fastmath.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/*
 * Sampling weight of texel (i, j): the mean of the bilinear interpolant over
 * the texel (a separable [1, 6, 1] / 8 filter of the luminance), times
 * sin(theta).  Weighting by the texel alone would give the neighbours of a
 * small bright source (the sun) a tiny pdf while the bilinear lookup still
 * returns half its radiance there: fireflies.  With the filter, radiance /
 * pdf stays bounded.
 */
static double texel_weight(const struct glint_image *img,
			   const unsigned char *zero, int i, int j)
{
	static const double k[3] = { 1.0 / 8, 6.0 / 8, 1.0 / 8 };
	int w = img->width, h = img->height;
	double sum = 0;

	for (int dy = -1; dy <= 1; dy++) {
		int y = j + dy < 0 ? 0 : j + dy >= h ? h - 1 : j + dy;
		for (int dx = -1; dx <= 1; dx++) {
			int x = ((i + dx) % w + w) % w;
			if (zero && zero[(size_t)y * w + x])
				continue;
			const float *p = glint_image_px(img, x, y);
			sum += k[dx + 1] * k[dy + 1] *
			       rgb_luminance(p[0], p[1], p[2]);
		}
	}
	return sum * sin(M_PI * (j + 0.5) / h);
}

/*
 * CDFs of the texel weights, the texels where zero[] is set read as black:
 * the rest of a map split by value (glint_env_hot).  A texel next to a
 * black one keeps the weight of its other neighbours (the weights are
 * blurred), so the samples reach wherever the rest's bilinear radiance
 * does, inside the black texels' edges too.
 */
static int dist_build(const struct glint_image *img, const unsigned char *zero,
		      struct glint_env_dist *d)
{
	int w = img->width, h = img->height;

	d->marginal = calloc((size_t)h + 1, sizeof(double));
	d->cond = calloc((size_t)h * (w + 1), sizeof(double));
	if (!d->marginal || !d->cond)
		return glint_error_set(ENOMEM,
				       "out of memory for the env map's "
				       "sampling tables");
	for (int j = 0; j < h; j++) {
		double *c = d->cond + (size_t)j * (w + 1);
		for (int i = 0; i < w; i++)
			c[i + 1] = c[i] + texel_weight(img, zero, i, j);
		d->marginal[j + 1] = d->marginal[j] + c[w];
	}
	d->total = d->marginal[h];
	return 0;
}

static void dist_free(struct glint_env_dist *d)
{
	free(d->marginal);
	free(d->cond);
	d->marginal = d->cond = NULL;
}

static int build_tables(struct glint_envmap *env)
{
	return dist_build(env->img, NULL, &env->dist);
}

/*
 * Lossy EXR compression (DWAA/DWAB) rings slightly below zero next to
 * bright edges: Blender's courtyard.exr has values down to -0.0011 with a
 * mean luminance of 0.54.  Clamp negatives within 1 % of the mean luminance
 * to zero; anything more negative is not radiance and is an error.
 */
static int clamp_compression_noise(struct glint_image *img, const char *what)
{
	size_t n = (size_t)img->width * img->height * 3;
	double mean = 0;

	for (size_t i = 0; i < n; i++)
		mean += img->data[i];
	mean /= (double)n;
	for (size_t i = 0; i < n; i++) {
		if (img->data[i] >= 0)
			continue;
		if (img->data[i] < -0.01 * fabs(mean)) {
			size_t px = i / 3;
			return glint_error_set(
				EINVAL,
				"%s: pixel (%zu, %zu) has radiance %g: "
				"expected "
				">= 0 (small negatives from lossy "
				"compression, within 1%% of the mean %g, are "
				"clamped)",
				what, px % img->width, px / img->width,
				(double)img->data[i], mean);
		}
		img->data[i] = 0;
	}
	return 0;
}

int glint_envmap_new(struct glint_image *img, const double rot_deg[3],
		     double scale, const char *what, struct glint_envmap **out)
{
	struct glint_envmap *env;
	int ret;

	*out = NULL;
	ret = glint_image_check_finite(img, what, 0);
	if (ret < 0)
		goto err_img;
	ret = clamp_compression_noise(img, what);
	if (ret < 0)
		goto err_img;
	if (img->width < 2 || img->height < 1) {
		ret = glint_error_set(EINVAL,
				      "%s: %dx%d is too small for a lat-long "
				      "map",
				      what, img->width, img->height);
		goto err_img;
	}
	if (!(scale > 0) || !isfinite(scale)) {
		ret = glint_error_set(EINVAL,
				      "%s: radiance scale %g: expected > 0",
				      what, scale);
		goto err_img;
	}
	env = calloc(1, sizeof(*env));
	if (!env) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto err_img;
	}
	env->img = img;
	env->scale = scale;
	env->rot = m3_rotation_xyz_deg(rot_deg ? rot_deg[0] : 0,
				       rot_deg ? rot_deg[1] : 0,
				       rot_deg ? rot_deg[2] : 0);
	ret = build_tables(env);
	if (ret < 0) {
		glint_envmap_free(env);
		return ret;
	}
	*out = env;
	return 0;
err_img:
	glint_image_free(img);
	return ret;
}

int glint_envmap_load(const char *path, const double rot_deg[3], double scale,
		      int srgb, struct glint_envmap **out)
{
	struct glint_image *img;
	int ret = glint_image_read_radiance(path, srgb, &img);

	*out = NULL;
	if (ret < 0)
		return ret;
	return glint_envmap_new(img, rot_deg, scale, path, out);
}

void glint_envmap_free(struct glint_envmap *env)
{
	if (!env)
		return;
	glint_image_free(env->img);
	dist_free(&env->dist);
	free(env);
}

static void lookup_uv(const struct glint_envmap *env, double u, double v,
		      double rgb[3])
{
	const struct glint_image *img = env->img;
	int w = img->width, h = img->height;
	double x = u * w - 0.5, y = v * h - 0.5;
	double fx = floor(x), fy = floor(y);
	double tx = x - fx, ty = y - fy;
	int x0 = (int)fx, y0 = (int)fy;
	int x1 = x0 + 1, y1 = y0 + 1;

	/* Wrap around in azimuth, clamp at the poles. */
	x0 = ((x0 % w) + w) % w;
	x1 = ((x1 % w) + w) % w;
	y0 = y0 < 0 ? 0 : y0 >= h ? h - 1 : y0;
	y1 = y1 < 0 ? 0 : y1 >= h ? h - 1 : y1;
	const float *a = glint_image_px(img, x0, y0);
	const float *b = glint_image_px(img, x1, y0);
	const float *c = glint_image_px(img, x0, y1);
	const float *e = glint_image_px(img, x1, y1);
	for (int k = 0; k < 3; k++)
		rgb[k] =
			env->scale * ((1 - ty) * ((1 - tx) * a[k] + tx * b[k]) +
				      ty * ((1 - tx) * c[k] + tx * e[k]));
}

/*
 * The bilinear radiance made from one part of the texels: the hot ones
 * (part 1) or the others (part 0), the rest read as black.  The two parts
 * add up to lookup_uv() and each is continuous, where cutting the map at
 * a hot texel's edge is not: next to a sun the bilinear radiance is half
 * the sun's.
 */
static void lookup_uv_part(const struct glint_envmap *env,
			   const unsigned char *is_hot, int part, double u,
			   double v, double rgb[3])
{
	const struct glint_image *img = env->img;
	int w = img->width, h = img->height;
	double x = u * w - 0.5, y = v * h - 0.5;
	double fx = floor(x), fy = floor(y);
	double tx = x - fx, ty = y - fy;
	int xs[2] = { (int)fx, (int)fx + 1 }, ys[2] = { (int)fy, (int)fy + 1 };
	double wx[2] = { 1 - tx, tx }, wy[2] = { 1 - ty, ty };

	rgb[0] = rgb[1] = rgb[2] = 0;
	for (int b = 0; b < 2; b++) {
		int yy = ys[b] < 0 ? 0 : ys[b] >= h ? h - 1 : ys[b];
		for (int a = 0; a < 2; a++) {
			int xx = ((xs[a] % w) + w) % w;
			if (!is_hot[(size_t)yy * w + xx] != !part)
				continue;
			const float *t = glint_image_px(img, xx, yy);
			for (int k = 0; k < 3; k++)
				rgb[k] += env->scale * wy[b] * wx[a] * t[k];
		}
	}
}

void glint_envmap_lookup(const struct glint_envmap *env, struct vec3 d,
			 double rgb[3])
{
	double u, v;

	glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &u, &v);
	lookup_uv(env, u, v, rgb);
}

/* Largest i < n with cdf[i] <= x (0 where none is), for count searches
 * at once (cdf[k], x[k]) in lockstep: each step is a select, not a
 * branch, so that the searches' table reads overlap.  The CDFs do not
 * decrease, so this is the same index a bisection finds.  Then past the
 * zero-width intervals a search may land on: cdf[i] <= x < cdf[i + 1]. */
static void cdf_find_n(const double *const *cdf, int n, const double *x,
		       int count, int *out)
{
	int len = n;

	for (int k = 0; k < count; k++)
		out[k] = 0;
	while (len > 1) {
		int half = len / 2;
		for (int k = 0; k < count; k++)
			out[k] = cdf[k][out[k] + half] <= x[k] ? out[k] + half
							       : out[k];
		len -= half;
	}
	for (int k = 0; k < count; k++)
		while (out[k] < n - 1 && cdf[k][out[k] + 1] <= cdf[k][out[k]])
			out[k]++;
}

double glint_envmap_sample(const struct glint_envmap *env, double u1, double u2,
			   struct vec3 *dir)
{
	return glint_env_dist_sample(env, &env->dist, u1, u2, dir);
}

void glint_envmap_sample_n(const struct glint_envmap *env, int count,
			   const double *u1, const double *u2, struct vec3 *dir,
			   double *pdf)
{
	glint_env_dist_sample_n(env, &env->dist, count, u1, u2, dir, pdf);
}

double glint_env_dist_sample(const struct glint_envmap *env,
			     const struct glint_env_dist *dd, double u1,
			     double u2, struct vec3 *dir)
{
	double pdf;

	glint_env_dist_sample_n(env, dd, 1, &u1, &u2, dir, &pdf);
	return pdf;
}

void glint_env_dist_sample_n(const struct glint_envmap *env,
			     const struct glint_env_dist *dd, int count,
			     const double *u1, const double *u2,
			     struct vec3 *dir, double *pdf)
{
	int w = env->img->width, h = env->img->height;

	if (!(dd->total > 0)) {
		for (int k = 0; k < count; k++) {
			dir[k] = v3(0, 1, 0);
			pdf[k] = 0;
		}
		return;
	}
	while (count > 0) {
		enum { BATCH = 16 };
		int m = count < BATCH ? count : BATCH, row[BATCH], col[BATCH];
		const double *cdf[BATCH];
		double x[BATCH], y[BATCH];
		for (int k = 0; k < m; k++) {
			cdf[k] = dd->marginal;
			x[k] = u1[k] * dd->total;
		}
		cdf_find_n(cdf, h, x, m, row);
		for (int k = 0; k < m; k++) {
			cdf[k] = dd->cond + (size_t)row[k] * (w + 1);
			y[k] = u2[k] * cdf[k][w];
		}
		cdf_find_n(cdf, w, y, m, col);
		for (int k = 0; k < m; k++) {
			int j = row[k], i = col[k];
			const double *c = cdf[k];
			double row_w = dd->marginal[j + 1] - dd->marginal[j];
			double fv = row_w > 0 ? (x[k] - dd->marginal[j]) / row_w
					      : 0.5;
			double cell = c[i + 1] - c[i];
			double fu = cell > 0 ? (y[k] - c[i]) / cell : 0.5;
			double u = (i + fu) / w, v = (j + fv) / h;
			/* glint_latlong_uv_to_dir() by polynomials (to
			 * 8e-16): theta = pi v, phi = 2 pi (u - 1/2) */
			double s, ct, sp, cp;
			glint_fast_sincos_2pi(0.5 * v, &s, &ct);
			glint_fast_sincos_2pi(u - 0.5, &sp, &cp);
			dir[k] = m3_mul(&env->rot, v3(s * sp, ct, -s * cp));
			/* Density over (u, v) is cell * W * H / total;
			 * dA = 2 pi^2 sin. */
			pdf[k] = !(s > 0) || !(cell > 0)
					 ? 0
					 : cell * w * h / dd->total /
						   (2 * M_PI * M_PI * s);
		}
		u1 += m, u2 += m, dir += m, pdf += m, count -= m;
	}
}

double glint_envmap_pdf(const struct glint_envmap *env, struct vec3 d)
{
	return glint_env_dist_pdf(env, &env->dist, d);
}

/* dd's pdf at map coordinates (u, v). */
static double dist_pdf_uv(const struct glint_envmap *env,
			  const struct glint_env_dist *dd, double u, double v)
{
	int w = env->img->width, h = env->img->height;

	if (!(dd->total > 0))
		return 0;
	int i = (int)(u * w), j = (int)(v * h);
	i = i < 0 ? 0 : i >= w ? w - 1 : i;
	j = j < 0 ? 0 : j >= h ? h - 1 : j;
	double s = sin(M_PI * v);
	const double *c = dd->cond + (size_t)j * (w + 1);
	double cell = c[i + 1] - c[i];
	if (!(s > 0))
		return 0;
	return cell * w * h / dd->total / (2 * M_PI * M_PI * s);
}

double glint_env_dist_pdf(const struct glint_envmap *env,
			  const struct glint_env_dist *dd, struct vec3 d)
{
	double u, v;

	if (!(dd->total > 0))
		return 0;
	glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &u, &v);
	return dist_pdf_uv(env, dd, u, v);
}

void glint_envmap_locate(const struct glint_envmap *env, struct vec3 d,
			 struct glint_envmap_loc *q)
{
	const struct glint_image *img = env->img;
	int w = img->width, h = img->height;

	glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &q->u, &q->v);
	/* The texel holding (u, v), the row beside it that a bilinear
	 * read takes, and the texel's sampling weight. */
	double y = q->v * h;
	int i = (int)(q->u * w), j = (int)y;
	i = i < 0 ? 0 : i >= w ? w - 1 : i;
	j = j < 0 ? 0 : j >= h ? h - 1 : j;
	int jn = y - j < 0.5 ? j - 1 : j + 1;
	jn = jn < 0 ? 0 : jn >= h ? h - 1 : jn;
	__builtin_prefetch(glint_image_px(img, i, j));
	__builtin_prefetch(glint_image_px(img, i, jn));
	__builtin_prefetch(env->dist.cond + (size_t)j * (w + 1) + i);
}

double glint_envmap_located_pdf(const struct glint_envmap *env,
				const struct glint_envmap_loc *q)
{
	return dist_pdf_uv(env, &env->dist, q->u, q->v);
}

void glint_envmap_located_lookup(const struct glint_envmap *env,
				 const struct glint_envmap_loc *q,
				 double rgb[3])
{
	lookup_uv(env, q->u, q->v, rgb);
}

/* Sampling density over (u, v) of texel (i, j) (wrapping i, clamping j). */
static double uv_density(const struct glint_envmap *env,
			 const struct glint_env_dist *dd, int i, int j)
{
	int w = env->img->width, h = env->img->height;

	i = ((i % w) + w) % w;
	j = j < 0 ? 0 : j >= h ? h - 1 : j;
	const double *c = dd->cond + (size_t)j * (w + 1);
	return (c[i + 1] - c[i]) * w * h / dd->total;
}

double glint_envmap_pdf_smooth(const struct glint_envmap *env, struct vec3 d)
{
	return glint_env_dist_pdf_smooth(env, &env->dist, d);
}

static double pdf_smooth_uv(const struct glint_envmap *env,
			    const struct glint_env_dist *dd, double u, double v)
{
	int w = env->img->width, h = env->img->height;

	if (!(dd->total > 0))
		return 0;
	double s = sin(M_PI * v);
	if (!(s > 0))
		return 0;
	double x = u * w - 0.5, y = v * h - 0.5;
	double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
	int i = (int)fx, j = (int)fy;
	double p = (1 - ty) * ((1 - tx) * uv_density(env, dd, i, j) +
			       tx * uv_density(env, dd, i + 1, j)) +
		   ty * ((1 - tx) * uv_density(env, dd, i, j + 1) +
			 tx * uv_density(env, dd, i + 1, j + 1));
	return p / (2 * M_PI * M_PI * s);
}

double glint_env_dist_pdf_smooth(const struct glint_envmap *env,
				 const struct glint_env_dist *dd, struct vec3 d)
{
	double u, v;

	glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &u, &v);
	return pdf_smooth_uv(env, dd, u, v);
}

/* The texels hot or next to one (the support of the hot part's bilinear
 * radiance), as indices j w + i in the map's row order, into *list (the
 * caller frees it) and their count *n: each hot texel's 3 x 3 marked
 * (wrapped in azimuth, clamped at the poles), then the marks read. */
static int near_hot_list(const struct glint_env_hot *hot, int w, int h,
			 int **list, int *n)
{
	unsigned char *mark = calloc((size_t)w * h, 1);

	*list = NULL;
	*n = 0;
	if (!mark)
		return glint_error_set(ENOMEM, "out of memory");
	for (int j = 0; j < h && hot->ntexels; j++)
		for (int i = 0; i < w; i++) {
			if (!hot->is_hot[(size_t)j * w + i])
				continue;
			for (int y = j - 1; y <= j + 1; y++)
				for (int x = i - 1; x <= i + 1; x++)
					if (y >= 0 && y < h)
						mark[(size_t)y * w +
						     (x < 0    ? x + w
						      : x >= w ? x - w
							       : x)] = 1;
		}
	for (size_t t = 0; t < (size_t)w * h; t++)
		*n += mark[t];
	*list = malloc((size_t)(*n ? *n : 1) * sizeof(int));
	if (!*list) {
		free(mark);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (size_t t = 0, k = 0; t < (size_t)w * h; t++)
		if (mark[t])
			(*list)[k++] = (int)t;
	free(mark);
	return 0;
}

/* Point k of pts: direction d, radiance l times dom. */
static void hot_point_set(float *pts, int k, struct vec3 d, const double l[3],
			  double dom)
{
	float *pt = pts + 6 * (size_t)k;

	pt[0] = (float)d.x;
	pt[1] = (float)d.y;
	pt[2] = (float)d.z;
	for (int c = 0; c < 3; c++)
		pt[3 + c] = (float)(l[c] * dom);
}

/* The hot part's points (*part, *npart): q x q points on every texel
 * where the hot part's radiance (lookup_uv_part(), part 1) is not zero,
 * carrying it x solid angle; with var, one point a texel instead, at
 * the flux-weighted mean direction of its q x q (the texel's own
 * centroid: its solid angle grows toward the equator, so its centre is
 * not), and in (*var)[k] the spread about it that the point leaves out
 * (the variance of the texel's flux over directions, both axes, rad^2). */
static int hot_part_points(const struct glint_envmap *env,
			   struct glint_env_hot *hot, const int *near, int n,
			   int q, float **part, int *npart, float **var)
{
	int w = env->img->width, h = env->img->height;
	int merge = var != NULL;
	*npart = 0;
	*part = malloc((size_t)(n ? (merge ? n : n * q * q) : 1) * 6 *
		       sizeof(float));
	if (merge)
		*var = malloc((size_t)(n ? n : 1) * sizeof(float));
	if (!*part || (merge && !*var))
		return glint_error_set(ENOMEM, "out of memory");
	for (int t = 0; t < n; t++) {
		int i = near[t] % w, j = near[t] / w;
		double flux[3] = { 0, 0, 0 };
		struct vec3 mean = v3(0, 0, 0);
		for (int b = 0; b < q; b++)
			for (int a = 0; a < q; a++) {
				double u = (i + (a + 0.5) / q) / w;
				double v = (j + (b + 0.5) / q) / h;
				double l[3];
				lookup_uv_part(env, hot->is_hot, 1, u, v, l);
				if (!(l[0] + l[1] + l[2] > 0))
					continue;
				double dom = (2 * M_PI / w) * (M_PI / h) *
					     sin(M_PI * v) / (q * q);
				struct vec3 d =
					m3_mul(&env->rot,
					       glint_latlong_uv_to_dir(u, v));
				for (int c = 0; c < 3; c++)
					flux[c] += l[c] * dom;
				mean = v3_add(mean, v3_scale(d, (l[0] + l[1] +
								 l[2]) * dom));
				if (!merge)
					hot_point_set(*part, (*npart)++, d, l,
						      dom);
			}
		double wsum = flux[0] + flux[1] + flux[2];
		if (!merge || !(wsum > 0))
			continue;
		/* the unit directions' variance: 1 - |their mean|^2 */
		struct vec3 mu = v3_scale(mean, 1 / wsum);
		(*var)[*npart] = (float)fmax(0, 1 - v3_dot(mu, mu));
		hot_point_set(*part, (*npart)++, v3_norm(mean), flux, 1);
	}
	return 0;
}

/* hot->tab: the rest's texels and densities with a one-texel border. */
static int rest_table(const struct glint_envmap *env, struct glint_env_hot *hot)
{
	int w = env->img->width, h = env->img->height;
	size_t stride = (size_t)w + 2;

	hot->env = env;
	hot->tab = malloc(stride * ((size_t)h + 2) * 4 * sizeof(float));
	if (!hot->tab)
		return glint_error_set(ENOMEM,
				       "out of memory for the env map's "
				       "table");
	for (int j = -1; j <= h; j++) {
		int y = j < 0 ? 0 : j >= h ? h - 1 : j;
		for (int i = -1; i <= w; i++) {
			int x = ((i % w) + w) % w;
			float *t = hot->tab + 4 * (((size_t)j + 1) * stride +
						   (size_t)i + 1);
			const float *px = glint_image_px(env->img, x, y);
			int off = hot->is_hot[(size_t)y * w + x];
			for (int c = 0; c < 3; c++)
				t[c] = off ? 0.0f : px[c];
			t[3] = hot->rest.total > 0
				       ? (float)uv_density(env, &hot->rest, x,
							   y)
				       : 0.0f;
		}
	}
	return 0;
}

/* Point k of the points of the hot split (pts, then part, then
 * coarse). */
static float *hot_point(struct glint_env_hot *hot, int k)
{
	if (k < hot->npts)
		return hot->pts + 6 * (size_t)k;
	k -= hot->npts;
	return k < hot->npart ? hot->part + 6 * (size_t)k
			      : hot->coarse + 6 * ((size_t)k - hot->npart);
}

/* The points in cluster order, each array on its own (counting sort,
 * stable). */
static int hot_reorder(float *pts, int stride, int n, const int *id, int nc,
		       int *first)
{
	float *tmp = malloc((size_t)(n ? n : 1) * stride * sizeof(float));
	int *at = calloc((size_t)nc + 1, sizeof(int));

	if (!tmp || !at) {
		free(tmp);
		free(at);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int k = 0; k < n; k++)
		at[id[k] + 1]++;
	for (int c = 0; c < nc; c++)
		at[c + 1] += at[c];
	memcpy(first, at, (size_t)(nc + 1) * sizeof(int));
	for (int k = 0; k < n; k++)
		memcpy(tmp + stride * (size_t)at[id[k]]++,
		       pts + stride * (size_t)k, stride * sizeof(float));
	memcpy(pts, tmp, (size_t)n * stride * sizeof(float));
	free(tmp);
	free(at);
	return 0;
}

/*
 * Group the hot points by where they are: a point joins the first
 * cluster whose first point is within `seed` radians, else starts one.
 * Each cluster's cone: the mean of its points' directions, out to the
 * farthest plus `margin` (a texel's extent).  A lobe skips a cone only
 * beyond its extent (below 1e-12 of its peak: shade_lobe.c), so the
 * grouping changes how many points a lobe visits, not what it sums.
 */
static int hot_clusters(struct glint_env_hot *hot, float *coarse_var,
			double seed, double margin)
{
	int np = hot->npts + hot->npart + hot->ncoarse, nc = 0, ret = 0;
	int *id = malloc((size_t)(np ? np : 1) * sizeof(int));
	int *lead = malloc((size_t)(np ? np : 1) * sizeof(int));
	int *first_pts = NULL, *first_part = NULL, *first_coarse = NULL;
	double cos_seed = cos(seed);

	if (!id || !lead) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	for (int k = 0; k < np; k++) {
		const float *pt = hot_point(hot, k);
		int c = 0;
		for (; c < nc; c++) {
			const float *ld = hot_point(hot, lead[c]);
			if (pt[0] * ld[0] + pt[1] * ld[1] + pt[2] * ld[2] >=
			    cos_seed)
				break;
		}
		if (c == nc)
			lead[nc++] = k;
		id[k] = c;
	}
	hot->clusters = calloc((size_t)(nc ? nc : 1), sizeof(*hot->clusters));
	first_pts = malloc(((size_t)nc + 1) * sizeof(int));
	first_part = malloc(((size_t)nc + 1) * sizeof(int));
	first_coarse = malloc(((size_t)nc + 1) * sizeof(int));
	if (!hot->clusters || !first_pts || !first_part || !first_coarse) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	hot->nclusters = nc;
	for (int k = 0; k < np; k++) {
		const float *pt = hot_point(hot, k);
		struct glint_env_hot_cluster *cl = &hot->clusters[id[k]];
		cl->axis = v3_add(cl->axis, v3(pt[0], pt[1], pt[2]));
	}
	for (int c = 0; c < nc; c++)
		hot->clusters[c].axis = v3_norm(hot->clusters[c].axis);
	for (int k = 0; k < np; k++) {
		const float *pt = hot_point(hot, k);
		struct glint_env_hot_cluster *cl = &hot->clusters[id[k]];
		double d = v3_dot(cl->axis, v3(pt[0], pt[1], pt[2]));
		cl->radius = fmax(cl->radius, acos(fmin(1, fmax(-1, d))));
	}
	ret = hot_reorder(hot->pts, 6, hot->npts, id, nc, first_pts);
	if (ret == 0)
		ret = hot_reorder(hot->part, 6, hot->npart, id + hot->npts, nc,
				  first_part);
	if (ret == 0)
		ret = hot_reorder(hot->coarse, 6, hot->ncoarse,
				  id + hot->npts + hot->npart, nc,
				  first_coarse);
	if (ret == 0 && coarse_var)
		ret = hot_reorder(coarse_var, 1, hot->ncoarse,
				  id + hot->npts + hot->npart, nc,
				  first_coarse);
	for (int c = 0; c < nc && ret == 0; c++) {
		struct glint_env_hot_cluster *cl = &hot->clusters[c];
		cl->radius += margin;
		cl->pts0 = first_pts[c];
		cl->pts1 = first_pts[c + 1];
		cl->part0 = first_part[c];
		cl->part1 = first_part[c + 1];
		cl->coarse0 = first_coarse[c];
		cl->coarse1 = first_coarse[c + 1];
		/* the flux-weighted mean of the spread each coarse point
		 * leaves out, per axis */
		double sw = 0, sv = 0;
		for (int t = cl->coarse0; t < cl->coarse1 && coarse_var; t++) {
			const float *pt = hot->coarse + 6 * (size_t)t;
			double f = (double)pt[3] + pt[4] + pt[5];
			sw += f;
			sv += f * coarse_var[t];
		}
		cl->coarse_s = sw > 0 ? sqrt(sv / sw / 2) : 0;
	}
out:
	free(id);
	free(lead);
	free(first_pts);
	free(first_part);
	free(first_coarse);
	return ret;
}

int glint_env_hot_new(const struct glint_envmap *env, double tau,
		      int max_texels, int q, struct glint_env_hot **out)
{
	const struct glint_env_dist *dd = &env->dist;
	int w = env->img->width, h = env->img->height, n = 0, ret;
	struct glint_env_hot *hot = calloc(1, sizeof(*hot));
	double mx = 0;

	*out = NULL;
	if (!hot)
		return glint_error_set(ENOMEM, "out of memory");
	hot->is_hot = calloc((size_t)w * h, 1);
	if (!hot->is_hot) {
		free(hot);
		return glint_error_set(ENOMEM, "out of memory");
	}
	for (int j = 0; j < h; j++)
		for (int i = 0; i < w; i++) {
			const double *c = dd->cond + (size_t)j * (w + 1);
			mx = fmax(mx, c[i + 1] - c[i]);
		}
	for (int j = 0; j < h && mx > 0; j++)
		for (int i = 0; i < w; i++) {
			const double *c = dd->cond + (size_t)j * (w + 1);
			if (c[i + 1] - c[i] >= tau * mx) {
				hot->is_hot[(size_t)j * w + i] = 1;
				n++;
			}
		}
	if (n > max_texels) { /* no compact peak: nothing is hot */
		memset(hot->is_hot, 0, (size_t)w * h);
		n = 0;
	}
	hot->ntexels = n;
	hot->npts = n * q * q;
	hot->pts =
		malloc((size_t)(hot->npts ? hot->npts : 1) * 6 * sizeof(float));
	if (!hot->pts) {
		glint_env_hot_free(hot);
		return glint_error_set(ENOMEM, "out of memory");
	}
	struct vec3 axis = v3(0, 0, 0);
	int k = 0;
	for (int j = 0; j < h; j++)
		for (int i = 0; i < w; i++) {
			if (!hot->is_hot[(size_t)j * w + i])
				continue;
			for (int b = 0; b < q; b++)
				for (int a = 0; a < q; a++) {
					double u = (i + (a + 0.5) / q) / w;
					double v = (j + (b + 0.5) / q) / h;
					struct vec3 d = m3_mul(
						&env->rot,
						glint_latlong_uv_to_dir(u, v));
					double l[3];
					double dom = (2 * M_PI / w) *
						     (M_PI / h) *
						     sin(M_PI * v) / (q * q);
					glint_envmap_lookup(env, d, l);
					float *pt = hot->pts + 6 * (size_t)k++;
					pt[0] = (float)d.x;
					pt[1] = (float)d.y;
					pt[2] = (float)d.z;
					for (int c = 0; c < 3; c++)
						pt[3 + c] = (float)(l[c] * dom);
					axis = v3_add(
						axis,
						v3_scale(d, rgb_luminance(
								    l[0], l[1],
								    l[2]) *
								    dom));
				}
		}
	hot->axis = v3_norm(axis);
	int *near = NULL, nnear = 0;
	float *coarse_var = NULL; /* each coarse point's spread */
	ret = near_hot_list(hot, w, h, &near, &nnear);
	if (ret == 0)
		ret = hot_part_points(env, hot, near, nnear, q, &hot->part,
				      &hot->npart, NULL);
	/* and one point a texel, for lobes many texels wide */
	if (ret == 0 && q > 1)
		ret = hot_part_points(env, hot, near, nnear, 8, &hot->coarse,
				      &hot->ncoarse, &coarse_var);
	free(near);
	if (ret < 0) {
		free(coarse_var);
		glint_env_hot_free(hot);
		return ret;
	}
	/* Half-angle: the farthest point of either set plus a texel's half
	 * diagonal. */
	double radius = 0;
	for (int t = 0; t < hot->npts + hot->npart; t++) {
		const float *pt =
			t < hot->npts ? hot->pts + 6 * (size_t)t
				      : hot->part + 6 * (size_t)(t - hot->npts);
		double c = v3_dot(hot->axis, v3(pt[0], pt[1], pt[2]));
		radius = fmax(radius, acos(fmin(1, fmax(-1, c))));
	}
	double margin = M_PI / h * 1.5 + 2 * M_PI / w * 1.5;
	hot->radius = radius + margin;
	/* A lamp's points within a few degrees (8 texels at least: the
	 * hot texels of a lamp a texel across span 4 or 5) of its first. */
	ret = hot_clusters(hot, coarse_var, fmax(2 * M_PI / 180, 16 * M_PI / w),
			   margin);
	free(coarse_var);
	if (ret == 0)
		ret = dist_build(env->img, hot->is_hot, &hot->rest);
	if (ret == 0)
		ret = rest_table(env, hot);
	if (ret < 0) {
		glint_env_hot_free(hot);
		return ret;
	}
	*out = hot;
	return 0;
}

void glint_env_hot_free(struct glint_env_hot *hot)
{
	if (!hot)
		return;
	free(hot->pts);
	free(hot->part);
	free(hot->coarse);
	free(hot->clusters);
	free(hot->is_hot);
	free(hot->tab);
	dist_free(&hot->rest);
	free(hot);
}

/* The rest's radiance at (u, v): the whole map's without hot texels. */
static void rest_uv(const struct glint_envmap *env,
		    const struct glint_env_hot *hot, double u, double v,
		    double rgb[3])
{
	if (hot && hot->ntexels)
		lookup_uv_part(env, hot->is_hot, 0, u, v, rgb);
	else
		lookup_uv(env, u, v, rgb);
}

/* Direction d's place in hot->tab (in floats, as a double: exact) and
 * its bilinear weights tx, ty, with cy its map-frame y (the pdf's
 * sin(pi v)); no branch, so that a loop of it vectorises. */
static inline double query_place(const struct glint_env_hot *hot, int w, int h,
				 struct vec3 d, double *tx, double *ty,
				 double *cy)
{
	struct vec3 dm = m3_tmul(&hot->env->rot, d);

	*cy = glint_clamp(dm.y, -1, 1);
	/* glint_latlong_dir_to_uv()'s map, by polynomials: this runs for
	 * every lobe sample (core/fastmath.h) */
	double u = 0.5 + glint_fast_atan2(dm.x, -dm.z) / (2 * M_PI);
	double v = glint_fast_acos(*cy) / M_PI;
	/* u, v in [0, 1]: x, y within half a texel of the map, whose
	 * border in the table holds what wrapping and clamping would read. */
	double x = glint_clamp(u * w - 0.5, -0.5, w - 0.5);
	double y = glint_clamp(v * h - 0.5, -0.5, h - 0.5);
	double fx = glint_floor_nb(x), fy = glint_floor_nb(y);
	*tx = x - fx;
	*ty = y - fy;
	return 4 * ((fy + 1) * (w + 2) + (fx + 1));
}

void glint_env_query_start(const struct glint_env_hot *hot, struct vec3 d,
			   struct glint_env_query *q)
{
	int w = hot->env->img->width, h = hot->env->img->height;
	double at = query_place(hot, w, h, d, &q->tx, &q->ty, &q->cy);

	q->stride = (size_t)w + 2;
	q->t = hot->tab + (size_t)at;
	__builtin_prefetch(q->t);
	__builtin_prefetch(q->t + 4 * q->stride);
}

void glint_env_query_start_n(const struct glint_env_hot *hot, int n,
			     const double *dx, const double *dy,
			     const double *dz, struct glint_env_query *q)
{
	enum { BLOCK = 16 };
	double at[BLOCK], tx[BLOCK], ty[BLOCK], cy[BLOCK];
	int w = hot->env->img->width, h = hot->env->img->height;
	size_t stride = (size_t)w + 2;

	for (int k0 = 0; k0 < n; k0 += BLOCK) {
		int nk = n - k0 < BLOCK ? n - k0 : BLOCK;
		for (int k = 0; k < nk; k++)
			at[k] = query_place(
				hot, w, h,
				v3(dx[k0 + k], dy[k0 + k], dz[k0 + k]), &tx[k],
				&ty[k], &cy[k]);
		for (int k = 0; k < nk; k++) {
			struct glint_env_query *qk = &q[k0 + k];
			qk->t = hot->tab + (size_t)at[k];
			qk->stride = stride;
			qk->tx = tx[k];
			qk->ty = ty[k];
			qk->cy = cy[k];
			__builtin_prefetch(qk->t);
			__builtin_prefetch(qk->t + 4 * stride);
		}
	}
}

void glint_env_query_finish(const struct glint_env_hot *hot,
			    const struct glint_env_query *qs, double rgb[3],
			    double *pdf_smooth)
{
	const float *t = qs->t;
	size_t stride = qs->stride;
	double tx = qs->tx, ty = qs->ty, cy = qs->cy;
	const float *q[4] = { t, t + 4, t + 4 * stride, t + 4 * stride + 4 };
	double wt[4] = { (1 - ty) * (1 - tx), (1 - ty) * tx, ty * (1 - tx),
			 ty * tx };
	double a[4] = { 0, 0, 0, 0 }; /* RGB and the density, side by side */

	for (int k = 0; k < 4; k++)
		for (int c = 0; c < 4; c++)
			a[c] += wt[k] * q[k][c];
	for (int c = 0; c < 3; c++)
		rgb[c] = hot->env->scale * a[c];
	double s = sqrt(1 - cy * cy); /* sin(pi v) */
	*pdf_smooth =
		s > 0 && hot->rest.total > 0 ? a[3] / (2 * M_PI * M_PI * s) : 0;
}

void glint_env_query(const struct glint_env_hot *hot, struct vec3 d,
		     double rgb[3], double *pdf_smooth)
{
	struct glint_env_query q;

	glint_env_query_start(hot, d, &q);
	glint_env_query_finish(hot, &q, rgb, pdf_smooth);
}

void glint_env_rest_lookup(const struct glint_envmap *env,
			   const struct glint_env_hot *hot, struct vec3 d,
			   double rgb[3])
{
	double u, v;

	glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &u, &v);
	rest_uv(env, hot, u, v, rgb);
}
