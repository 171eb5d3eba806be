/* SPDX-License-Identifier: MIT */
/* Environment map: lookup, rotation, importance sampling and its pdf. */
#include "chisq.h"
#include "test.h"

#include "core/error.h"
#include "fit/scene/envmap.h"
#include "fit/render/irradiance.h"
#include "fit/render/sampling.h"

#include <stdlib.h>
#include <string.h>

/* A synthetic map with a small bright "sun", a sky gradient, dark ground. */
static struct glint_envmap *make_env(int w, int h, const double rot[3])
{
	struct glint_image *img = glint_image_new(w, h);
	struct glint_envmap *env;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y);
			double v = (y + 0.5) / h;
			p[0] = (float)(v < 0.5 ? 1.0 - v : 0.1);
			p[1] = (float)(v < 0.5 ? 0.8 : 0.05 * (x % 3));
			p[2] = (float)(v < 0.5 ? 1.5 : 0.02);
		}
	for (int c = 0; c < 3; c++)
		glint_image_px(img, w / 3, h / 4)[c] = 500;
	if (glint_envmap_new(img, rot, 1.0, "synthetic", &env) < 0)
		return NULL;
	return env;
}

static double angle_to(struct vec3 axis, const float *pt)
{
	double d = v3_dot(axis, v3(pt[0], pt[1], pt[2]));
	return acos(fmin(1, fmax(-1, d)));
}

static void test_uv_dir(void)
{
	struct vec3 d = glint_latlong_uv_to_dir(0.5, 0.5);
	CHECK_NEAR(d.z, -1, 1e-12, "u=v=0.5 is -Z");
	d = glint_latlong_uv_to_dir(0.5, 0.0);
	CHECK_NEAR(d.y, 1, 1e-12, "v=0 is +Y");
	d = glint_latlong_uv_to_dir(0.75, 0.5);
	CHECK_NEAR(d.x, 1, 1e-12, "u=0.75 is +X");
	for (int i = 0; i < 100; i++) {
		double u = glint_u01(glint_hash32(i)),
		       v = glint_u01(glint_hash32(i + 999));
		double u2, v2;
		glint_latlong_dir_to_uv(glint_latlong_uv_to_dir(u, v), &u2,
					&v2);
		CHECK(fabs(u - u2) < 1e-9 && fabs(v - v2) < 1e-9,
		      "uv round trip (%g,%g) -> (%g,%g)", u, v, u2, v2);
	}
}

static void test_lookup(void)
{
	double zero[3] = { 0, 0, 0 }, rgb[3];
	struct glint_envmap *env = make_env(64, 32, zero);
	/* At a texel centre the bilinear lookup returns the texel. */
	struct vec3 d = glint_latlong_uv_to_dir((64 / 3 + 0.5) / 64,
						(32 / 4 + 0.5) / 32);
	glint_envmap_lookup(env, d, rgb);
	CHECK_NEAR(rgb[0], 500, 1e-3, "texel centre");
	/* Halfway between two texels: their mean. */
	d = glint_latlong_uv_to_dir((64 / 3 + 1.0) / 64, (32 / 4 + 0.5) / 32);
	glint_envmap_lookup(env, d, rgb);
	float *a = glint_image_px(env->img, 64 / 3 + 1, 32 / 4);
	CHECK_NEAR(rgb[2], (500 + a[2]) / 2, 1e-3, "bilinear midpoint");
	glint_envmap_free(env);

	/* A rotated map seen along R d equals the plain map along d. */
	double rot[3] = { 20, -70, 35 };
	struct glint_envmap *plain = make_env(64, 32, zero);
	struct glint_envmap *turned = make_env(64, 32, rot);
	for (int i = 0; i < 200; i++) {
		struct vec3 dd = glint_latlong_uv_to_dir(
			glint_u01(glint_hash32(3 * i)),
			glint_u01(glint_hash32(3 * i + 1)));
		double p1[3], p2[3];
		glint_envmap_lookup(plain, dd, p1);
		glint_envmap_lookup(turned, m3_mul(&turned->rot, dd), p2);
		CHECK(fabs(p1[0] - p2[0]) < 1e-6 * (1 + p1[0]),
		      "rotation: %g vs %g", p1[0], p2[0]);
		/* Located once, the direction reads the same, bit for bit,
		 * as the lookup and the pdf do on their own. */
		struct glint_envmap_loc q;
		double p3[3], wd[2];
		glint_envmap_locate(turned, dd, &q);
		glint_envmap_lookup(turned, dd, p2);
		glint_envmap_located_lookup(turned, &q, p3);
		wd[0] = glint_envmap_pdf(turned, dd);
		wd[1] = glint_envmap_located_pdf(turned, &q);
		CHECK(!memcmp(p2, p3, sizeof(p2)) &&
			      !memcmp(&wd[0], &wd[1], sizeof(wd[0])),
		      "located: %.17g %.17g vs %.17g %.17g", p3[0], wd[1],
		      p2[0], wd[0]);
	}
	glint_envmap_free(plain);
	glint_envmap_free(turned);
}

/* The pdf integrates to 1 over the sphere (midpoint rule in u, v). */
static void test_pdf_integrates(void)
{
	double rot[3] = { 10, 40, 0 };
	struct glint_envmap *env = make_env(64, 32, rot);
	int n = 512, m = 256;
	double sum = 0;
	for (int j = 0; j < m; j++) {
		double v = (j + 0.5) / m, s = sin(M_PI * v);
		for (int i = 0; i < n; i++) {
			struct vec3 d = m3_mul(
				&env->rot,
				glint_latlong_uv_to_dir((i + 0.5) / n, v));
			sum += glint_envmap_pdf(env, d) * s;
		}
	}
	sum *= (2 * M_PI / n) * (M_PI / m);
	CHECK_NEAR(sum, 1.0, 2e-3, "integral of the pdf over the sphere");
	glint_envmap_free(env);
}

/* The interval holding x in a CDF of n intervals by a full scan: the
 * last whose start is at most x. */
static int scan_cdf(const double *cdf, int n, double x)
{
	int i = 0;
	for (int k = 1; k < n; k++)
		if (cdf[k] <= x)
			i = k;
	return i;
}

/* Sampling inverts the CDFs as a full scan does: samples at random and
 * at every interval's edge (and just below it), on a map with a sun,
 * black rows and black runs within rows (zero-width intervals). */
static void test_sampling_inverse(void)
{
	double rot[3] = { 0, 70, 0 };
	int w = 70, h = 35, worst_i = 0, unlike = 0;
	struct glint_image *img = glint_image_new(w, h);
	struct glint_envmap *env;
	double worst = 0;

	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y);
			int black = (y >= 20 && y < 24) || (x >= 10 && x < 30);
			for (int c = 0; c < 3; c++)
				p[c] = black ? 0 : (float)(0.1 + 0.01 * x);
		}
	for (int c = 0; c < 3; c++)
		glint_image_px(img, 40, 8)[c] = 1e5f;
	int ret = glint_envmap_new(img, rot, 1.0, "cdf", &env);
	CHECK(ret == 0, "%s", glint_error_msg());
	if (ret < 0)
		return;
	const struct glint_env_dist *dd = &env->dist;
	int n = 20000 + 4 * (h + 1) * (w + 1);
	double *us = malloc(2 * (size_t)n * sizeof(*us));
	double *pdfs = malloc((size_t)n * sizeof(*pdfs));
	struct vec3 *dirs = malloc((size_t)n * sizeof(*dirs));
	CHECK(us && pdfs && dirs, "out of memory");
	if (!us || !pdfs || !dirs)
		n = 0;
	for (int k = 0; k < n; k++) {
		double u1, u2;
		if (k < 20000) {
			u1 = glint_u01(glint_hash32(2 * k + 3));
			u2 = glint_u01(glint_hash32(2 * k + 9999));
		} else { /* each row's and column's edge, and just below */
			int e = (k - 20000) / 4, j = e / (w + 1),
			    i = e % (w + 1);
			u1 = dd->marginal[j] / dd->total;
			u2 = (double)i / w;
			if ((k & 1) && u1 > 0)
				u1 = nextafter(u1, 0);
			if ((k & 2) && u2 > 0)
				u2 = nextafter(u2, 0);
			u1 = fmin(u1, nextafter(1, 0));
			u2 = fmin(u2, nextafter(1, 0));
		}
		struct vec3 d;
		us[k] = u1;
		us[n + k] = u2;
		pdfs[k] = glint_envmap_sample(env, u1, u2, &d);
		dirs[k] = d;
		double x = u1 * dd->total;
		int j = scan_cdf(dd->marginal, h, x);
		double row_w = dd->marginal[j + 1] - dd->marginal[j];
		double fv = row_w > 0 ? (x - dd->marginal[j]) / row_w : 0.5;
		const double *c = dd->cond + (size_t)j * (w + 1);
		double y = u2 * c[w];
		int i = scan_cdf(c, w, y);
		double cell = c[i + 1] - c[i];
		double fu = cell > 0 ? (y - c[i]) / cell : 0.5;
		struct vec3 e = m3_mul(
			&env->rot,
			glint_latlong_uv_to_dir((i + fu) / w, (j + fv) / h));
		double dist = v3_len(v3_sub(d, e));
		if (dist > worst) {
			worst = dist;
			worst_i = k;
		}
	}
	CHECK(worst < 1e-9,
	      "sample %d: %.3g from the full scan's direction (another "
	      "interval)",
	      worst_i, worst);
	/* Drawn in batches of 37 (across the searches' own batches), each
	 * sample is the one drawn alone, bit for bit. */
	for (int k0 = 0; k0 < n; k0 += 37) {
		int m = n - k0 < 37 ? n - k0 : 37;
		struct vec3 d[37];
		double pdf[37];
		glint_envmap_sample_n(env, m, us + k0, us + n + k0, d, pdf);
		for (int e = 0; e < m; e++)
			unlike +=
				memcmp(&d[e], &dirs[k0 + e], sizeof(d[e])) ||
				memcmp(&pdf[e], &pdfs[k0 + e], sizeof(pdf[e]));
	}
	CHECK(unlike == 0,
	      "%d of %d batched samples unlike the one drawn alone", unlike, n);
	free(us);
	free(pdfs);
	free(dirs);
	glint_envmap_free(env);
}

/* Samples return the pdf glint_envmap_pdf gives, and their histogram
 * over texels matches the pdf (chi-square). */
static void test_sampling_histogram(void)
{
	double rot[3] = { 0, 30, 0 };
	int w = 32, h = 16, ns = 200000;
	struct glint_envmap *env = make_env(w, h, rot);
	double *obs = calloc((size_t)w * h, sizeof(double));
	double *expc = calloc((size_t)w * h, sizeof(double));
	int mismatched = 0;

	for (int k = 0; k < ns; k++) {
		struct vec3 d;
		double u1 = glint_u01(glint_hash32(2 * k + 1));
		double u2 = glint_u01(glint_hash32(2 * k + 7777));
		double pdf = glint_envmap_sample(env, u1, u2, &d);
		double p2 = glint_envmap_pdf(env, d);
		if (fabs(pdf - p2) > 1e-6 * pdf)
			mismatched++;
		double u, v;
		glint_latlong_dir_to_uv(m3_tmul(&env->rot, d), &u, &v);
		int i = (int)(u * w), j = (int)(v * h);
		i = i >= w ? w - 1 : i;
		j = j >= h ? h - 1 : j;
		obs[j * w + i] += 1;
	}
	/* Expected count per texel: ns * integral of the pdf over it. */
	for (int j = 0; j < h; j++)
		for (int i = 0; i < w; i++) {
			double acc = 0;
			for (int b = 0; b < 8; b++)
				for (int a = 0; a < 8; a++) {
					double u = (i + (a + 0.5) / 8) / w;
					double v = (j + (b + 0.5) / 8) / h;
					struct vec3 d = m3_mul(
						&env->rot,
						glint_latlong_uv_to_dir(u, v));
					acc += glint_envmap_pdf(env, d) *
					       sin(M_PI * v);
				}
			expc[j * w + i] =
				ns * acc / 64 * (2 * M_PI / w) * (M_PI / h);
		}
	int dof;
	double p = chisq_test(obs, expc, w * h, &dof);
	CHECK(mismatched == 0, "%d samples whose pdf differs from pdf()",
	      mismatched);
	CHECK(p > 1e-3, "chi-square p-value %g (dof %d)", p, dof);
	free(obs);
	free(expc);
	glint_envmap_free(env);
}

static void test_bad_maps(void)
{
	struct glint_envmap *env;
	struct glint_image *img = glint_image_new(8, 4);
	glint_image_px(img, 2, 1)[2] = NAN;
	CHECK(glint_envmap_new(img, NULL, 1, "nan.hdr", &env) == -EINVAL,
	      "NaN map accepted");
	CHECK_MSG(glint_error_msg(), "nan.hdr: pixel (2, 1) channel B");
	img = glint_image_new(8, 4);
	for (int i = 0; i < 8 * 4 * 3; i++)
		img->data[i] = 1;
	glint_image_px(img, 1, 1)[0] = -0.001f; /* compression noise */
	CHECK(glint_envmap_new(img, NULL, 1, "dwab.exr", &env) == 0, "%s",
	      glint_error_msg());
	CHECK(env && glint_image_px(env->img, 1, 1)[0] == 0,
	      "small negative not clamped");
	glint_envmap_free(env);
	img = glint_image_new(8, 4);
	glint_image_px(img, 0, 0)[0] = -1;
	CHECK(glint_envmap_new(img, NULL, 1, "neg.hdr", &env) == -EINVAL,
	      "negative radiance accepted");
	CHECK_MSG(glint_error_msg(),
		  "pixel (0, 0) has radiance -1: expected >= 0");
	/* An all-black map is legal; sampling reports pdf 0. */
	img = glint_image_new(8, 4);
	CHECK(glint_envmap_new(img, NULL, 1, "black", &env) == 0, "%s",
	      glint_error_msg());
	struct vec3 d;
	CHECK(glint_envmap_sample(env, 0.3, 0.3, &d) == 0,
	      "black map sampled with pdf > 0");
	glint_envmap_free(env);
	CHECK(glint_envmap_load("/no/such/map.hdr", NULL, 1, 0, &env) < 0,
	      "missing map loaded");
	CHECK_MSG(glint_error_msg(), "/no/such/map.hdr");
}

/* Irradiance of a uniform map is pi L for every normal, whatever the map's
 * size: sizes that the reduction to at most 256 cells does not divide (an
 * unwrapped probe is 386 x 193; 1030 x 515 leaves a last cell 2 texels
 * wide and 3 tall) once overran the reduced grid.  Within 0.2 %: the
 * texels across a normal's horizon are each clamped as a whole, which
 * leaves a 64 x 32 map (5.6 degree texels) 0.12 % low, the others 0.01 %. */
static void test_irradiance_odd_sizes(void)
{
	static const int sizes[][2] = {
		{ 386, 193 }, { 257, 129 }, { 64, 32 }, { 1030, 515 }
	};
	for (int s = 0; s < 4; s++) {
		struct glint_image *img =
			glint_image_new(sizes[s][0], sizes[s][1]);
		struct glint_envmap *env = NULL;
		struct glint_irradiance ir;
		double rot[3] = { 0, 0, 0 };
		for (size_t i = 0; i < (size_t)img->width * img->height * 3;
		     i++)
			img->data[i] = 2.0f;
		CHECK(glint_envmap_new(img, rot, 1, "uniform", &env) == 0, "%s",
		      glint_error_msg());
		CHECK(glint_irradiance_build(env, NULL, 64, 1, &ir) == 0, "%s",
		      glint_error_msg());
		struct vec3 n[3] = { v3(0, 1, 0), v3(0.6, 0, -0.8),
				     v3(0, -1, 0) };
		for (int k = 0; k < 3; k++) {
			double e[3];
			glint_irradiance_lookup(&ir, n[k], e);
			CHECK_NEAR(e[1], 2 * M_PI, 2e-3 * 2 * M_PI,
				   "irradiance of a uniform odd-size map");
		}
		glint_irradiance_free(&ir);
		glint_envmap_free(env);
	}
}

/*
 * Irradiance next to bright area lights, against a brute-force integral of
 * the bilinear radiance (2 x 2 points a texel): two softboxes on a dim
 * gradient, a rotated map wider than the 256 cells (reduced by 2), normals
 * at random and with their horizon across a softbox, where bilinear
 * weights missed by 3.8 % (64-wide grid) and 1.4 % (128); the tree and the
 * cubic on 128 by 0.055 %.
 */
static double brute_irradiance(const struct glint_envmap *env, struct vec3 n)
{
	int W = env->img->width * 2, H = env->img->height * 2;
	double e = 0;

	for (int j = 0; j < H; j++) {
		double t0 = M_PI * j / H, t1 = M_PI * (j + 1) / H;
		double om = (2 * M_PI / W) * (cos(t0) - cos(t1));
		for (int i = 0; i < W; i++) {
			struct vec3 d =
				m3_mul(&env->rot,
				       glint_latlong_uv_to_dir((i + 0.5) / W,
							       (j + 0.5) / H));
			double c = v3_dot(n, d), l[3];
			if (c <= 0)
				continue;
			glint_envmap_lookup(env, d, l);
			e += c * l[1] * om;
		}
	}
	return e;
}

static void test_irradiance_softboxes(void)
{
	const int w = 520, h = 260;
	struct glint_image *img = glint_image_new(w, h);
	struct glint_envmap *env = NULL;
	struct glint_irradiance ir;
	double rot[3] = { 10, 35, 0 }, worst = 0;
	/* softboxes: (u0, v0, u1, v1) */
	static const double box[2][4] = { { 0.20, 0.30, 0.24, 0.38 },
					  { 0.55, 0.40, 0.60, 0.44 } };

	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			double u = (x + 0.5) / w, v = (y + 0.5) / h;
			float l = (float)(0.05 + 0.1 * (1 - v));
			for (int b = 0; b < 2; b++)
				if (u >= box[b][0] && u < box[b][2] &&
				    v >= box[b][1] && v < box[b][3])
					l = 40;
			for (int c = 0; c < 3; c++)
				glint_image_px(img, x, y)[c] = l;
		}
	CHECK(glint_envmap_new(img, rot, 1, "softboxes", &env) == 0, "%s",
	      glint_error_msg());
	CHECK(glint_irradiance_build(env, NULL, 128, 2, &ir) == 0, "%s",
	      glint_error_msg());
	for (int k = 0; k < 20; k++) {
		struct vec3 n;
		if (k < 8) { /* horizon through a softbox's middle */
			const double *b = box[k % 2];
			struct vec3 c = m3_mul(
				&env->rot,
				glint_latlong_uv_to_dir((b[0] + b[2]) / 2,
							(b[1] + b[3]) / 2));
			struct vec3 t, s;
			v3_frame(c, &t, &s);
			double a = M_PI * k / 8 + 0.3;
			n = v3_add(v3_scale(t, cos(a)), v3_scale(s, sin(a)));
		} else {
			double z = 2 * glint_u01(glint_hash3(k, 1, 7)) - 1;
			double p = 2 * M_PI * glint_u01(glint_hash3(k, 2, 7));
			n = v3(sqrt(1 - z * z) * cos(p),
			       sqrt(1 - z * z) * sin(p), z);
		}
		double e[3], ref = brute_irradiance(env, n);
		glint_irradiance_lookup(&ir, n, e);
		double rel = fabs(e[1] / ref - 1);
		worst = rel > worst ? rel : worst;
	}
	CHECK(worst < 2e-3,
	      "irradiance next to softboxes within 0.2 %%: %.3f %%",
	      100 * worst);
	glint_irradiance_free(&ir);
	glint_envmap_free(env);
}

/*
 * The map split at its sun (glint_env_hot_new): the rest's radiance plus
 * the hot part's adds up to the map's everywhere; the rest's is
 * continuous across a hot texel's edge, where a cut by area jumps (the
 * fitter's objective jumped there), and sampled wherever it is not black
 * (inside the hot texels' edges too); the hot part's points integrate
 * what the rest leaves out, and the area split's points the hot texels'
 * area.
 */
static void test_hot_split(void)
{
	double rot[3] = { 0, 25, 0 };
	int w = 64, h = 32;
	struct glint_envmap *env = make_env(w, h, rot);
	struct glint_env_hot *hot = NULL;

	CHECK(env && glint_env_hot_new(env, 0.01, 64, 2, &hot) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return;
	/* The sun and the texels its bilinear pdf reaches. */
	CHECK(hot->ntexels >= 1 && hot->ntexels <= 9, "hot texels: %d",
	      hot->ntexels);
	CHECK(hot->npts == 4 * hot->ntexels, "2 x 2 points on each: %d",
	      hot->npts);
	CHECK(hot->npart > hot->npts, "the hot part reaches beyond: %d",
	      hot->npart);

	/* rest + hot part = map, on a fine grid of directions; the hot part
	 * integrated on a fine grid against its points. */
	int n = 1024, m = 512;
	double hot_fine = 0, area_fine = 0;
	for (int j = 0; j < m; j++) {
		double v = (j + 0.5) / m, sn = sin(M_PI * v);
		for (int i = 0; i < n; i++) {
			double u = (i + 0.5) / n;
			struct vec3 d = m3_mul(&env->rot,
					       glint_latlong_uv_to_dir(u, v));
			double all[3], rest[3], q[3], pdf;
			glint_envmap_lookup(env, d, all);
			glint_env_rest_lookup(env, hot, d, rest);
			glint_env_query(hot, d, q, &pdf);
			double ps =
				glint_env_dist_pdf_smooth(env, &hot->rest, d);
			CHECK(rest[0] <= all[0] + 1e-9, "the rest is below");
			for (int c = 0; c < 3; c++)
				CHECK_NEAR(
					q[c], rest[c], 1e-6 * (1 + rest[c]),
					"query and lookup of the rest agree");
			CHECK_NEAR(pdf, ps, 1e-6 * ps + 1e-12,
				   "query and smooth pdf agree");
			/* MIS needs the rest's samples wherever it shines. */
			CHECK(!(rest[0] > 1e-9) ||
				      glint_env_dist_pdf(env, &hot->rest, d) >
					      0,
			      "the rest is sampled where it shines");
			double dom = (2 * M_PI / n) * (M_PI / m) * sn;
			hot_fine += (all[0] - rest[0]) * dom;
			int ti = (int)(u * w), tj = (int)(v * h);
			if (hot->is_hot[(size_t)tj * w + ti])
				area_fine += all[0] * dom;
		}
	}
	double hot_pts = 0, area_pts = 0;
	for (int k = 0; k < hot->npart; k++)
		hot_pts += hot->part[6 * k + 3];
	for (int k = 0; k < hot->npts; k++)
		area_pts += hot->pts[6 * k + 3];
	CHECK_NEAR(hot_pts, hot_fine, 0.02 * hot_fine,
		   "the hot part's points integrate it");
	CHECK_NEAR(area_pts, area_fine, 0.02 * area_fine,
		   "the area split's points integrate the hot texel");

	/* Across the hot texels' right edge the rest is continuous. */
	double v = (h / 4 + 0.5) / h, eps = 1e-7;
	int edge = w / 3;
	while (hot->is_hot[(size_t)(h / 4) * w + edge])
		edge++;
	double ue = (double)edge / w;
	struct vec3 in =
		m3_mul(&env->rot, glint_latlong_uv_to_dir(ue - eps, v));
	struct vec3 out =
		m3_mul(&env->rot, glint_latlong_uv_to_dir(ue + eps, v));
	double ri[3], ro[3], ai[3];
	glint_env_rest_lookup(env, hot, in, ri);
	glint_env_rest_lookup(env, hot, out, ro);
	glint_envmap_lookup(env, in, ai);
	/* Cut by area the rest would jump from 0 to the map's value. */
	CHECK(ai[0] > 0.5, "the map at the hot edge: %g", ai[0]);
	CHECK_NEAR(ri[0], ro[0], 1e-3, "the rest is continuous at the edge");
	CHECK(ri[0] < 2, "the rest holds no sun: %g", ri[0]);
	glint_env_hot_free(hot);
	glint_envmap_free(env);
}

/* Queries in a batch (glint_env_query_start_n(), the lobe samples') read
 * what one query at a time reads, bit for bit: everywhere, at the poles
 * and across the seam. */
static void test_query_batch(void)
{
	double rot[3] = { 10, 25, -5 };
	struct glint_envmap *env = make_env(64, 32, rot);
	struct glint_env_hot *hot = NULL;
	enum { N = 1001 };
	static double dx[N], dy[N], dz[N];
	static struct glint_env_query q[N];
	int bad = 0;

	CHECK(env && glint_env_hot_new(env, 0.01, 64, 2, &hot) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return;
	for (int k = 0; k < N; k++) {
		double u = (k * 0.6180339887498949) -
			   (int)(k * 0.6180339887498949);
		double v = (k + 0.5) / N;
		if (k % 10 == 0) /* the seam, the poles */
			u = k % 20 ? 1e-12 : 1 - 1e-12;
		if (k % 25 == 0)
			v = k % 50 ? 1e-13 : 1 - 1e-13;
		struct vec3 d =
			m3_mul(&env->rot, glint_latlong_uv_to_dir(u, v));
		dx[k] = d.x, dy[k] = d.y, dz[k] = d.z;
	}
	glint_env_query_start_n(hot, N, dx, dy, dz, q);
	for (int k = 0; k < N; k++) {
		double a[3], b[3], pa, pb;
		glint_env_query(hot, v3(dx[k], dy[k], dz[k]), a, &pa);
		glint_env_query_finish(hot, &q[k], b, &pb);
		bad += memcmp(a, b, sizeof(a)) != 0 ||
		       memcmp(&pa, &pb, sizeof(pa)) != 0;
	}
	CHECK(bad == 0, "%d of %d batched queries differ", bad, N);
	glint_env_hot_free(hot);
	glint_envmap_free(env);
}

/* A Gaussian lobe of standard deviation sg (radians, per axis) about r
 * over a set of hot points [k0, k1): the sum of its density times each
 * point's flux (red). */
static double gauss_over(const float *pts, int k0, int k1, struct vec3 r,
			 double sg)
{
	double sum = 0;
	for (int k = k0; k < k1; k++) {
		double a = angle_to(r, pts + 6 * (size_t)k);
		sum += exp(-a * a / (2 * sg * sg)) / (2 * M_PI * sg * sg) *
		       pts[6 * k + 3];
	}
	return sum;
}

/* The hot part on one point a texel, widened by the cluster's coarse_s
 * (shade_lobe.c takes it for lobes 6 texels wide and more), against the
 * same part on 8 x 8 points a texel: within 2e-4 of the peak for a lobe
 * 6 texels wide (about 5e-5 here), and more than ten times closer than
 * without the widening (about 2e-3); two suns, one low (texels as wide
 * as high) and one high (a third as wide). */
static void test_hot_coarse(void)
{
	int w = 256, h = 128;
	double rot[3] = { 0, 0, 0 };
	struct glint_image *img = glint_image_new(w, h);
	struct glint_envmap *env = NULL;
	struct glint_env_hot *hot = NULL, *ref = NULL;

	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			for (int c = 0; c < 3; c++)
				glint_image_px(img, x, y)[c] = 0.5f;
	/* 3 x 3 texels each, uneven */
	for (int b = 0; b < 3; b++)
		for (int a = 0; a < 3; a++) {
			glint_image_px(img, 40 + a, 60 + b)[0] =
				(float)(300 + 60 * a + 25 * b);
			glint_image_px(img, 170 + a, 15 + b)[0] =
				(float)(420 - 50 * a + 30 * b);
		}
	CHECK(img && glint_envmap_new(img, rot, 1.0, "suns", &env) == 0 &&
		      glint_env_hot_new(env, 0.01, 256, 2, &hot) == 0 &&
		      glint_env_hot_new(env, 0.01, 256, 8, &ref) == 0,
	      "%s", glint_error_msg());
	if (test_failures)
		return;
	CHECK(hot->nclusters == 2 && hot->ncoarse * 2 < hot->npart,
	      "two suns, at most a quarter of the points: %d clusters, %d and "
	      "%d",
	      hot->nclusters, hot->ncoarse, hot->npart);
	double worst = 0, worst_plain = 1;
	for (int g = 0; g < hot->nclusters; g++) {
		const struct glint_env_hot_cluster *cl = &hot->clusters[g];
		struct vec3 t, b;
		v3_frame(cl->axis, &t, &b);
		for (int k = 0; k < 3; k++) {
			double sg = (6 << k) * M_PI / h, peak = 0;
			double err = 0, plain = 0;
			for (int o = 0; o < 4; o++) {
				/* off the sun by 0, 1, 2 sigma, two ways */
				double off = (o % 3) * sg;
				struct vec3 dir = o == 3 ? b : t;
				struct vec3 r = v3_norm(
					v3_add(v3_scale(cl->axis, cos(off)),
					       v3_scale(dir, sin(off))));
				double exact = gauss_over(ref->part, 0,
							  ref->npart, r, sg);
				double c = 0, c0 = 0;
				for (int e = 0; e < hot->nclusters; e++) {
					const struct glint_env_hot_cluster *ce =
						&hot->clusters[e];
					double s = ce->coarse_s;
					c += gauss_over(hot->coarse,
							ce->coarse0,
							ce->coarse1, r,
							sqrt(sg * sg + s * s));
					c0 += gauss_over(hot->coarse,
							 ce->coarse0,
							 ce->coarse1, r, sg);
				}
				peak = o ? peak : exact;
				err = fmax(err, fabs(c - exact));
				plain = fmax(plain, fabs(c0 - exact));
			}
			printf("sun %d, lobe %2d texels: coarse %.2e of the "
			       "peak, %.2e without widening\n",
			       g, 6 << k, err / peak, plain / peak);
			if (k == 0) {
				worst = fmax(worst, err / peak);
				worst_plain = fmin(worst_plain, plain / peak);
			}
		}
	}
	CHECK(worst < 2e-4, "coarse points off by %.2e of the peak", worst);
	CHECK(worst_plain > 10 * worst,
	      "widening takes off most of the error: %.2e against %.2e", worst,
	      worst_plain);
	glint_env_hot_free(hot);
	glint_env_hot_free(ref);
	glint_envmap_free(env);
}

/*
 * Several lamps (glint_env_hot_new's clusters): a cluster or two per
 * lamp and none holding two, their ranges partition both point sets,
 * and every point lies inside its cluster's cone, the bound a lobe's
 * cull relies on.
 */
static void test_hot_clusters(void)
{
	double rot[3] = { 0, 40, 0 };
	int w = 256, h = 128;
	struct glint_image *img = glint_image_new(w, h);
	struct glint_envmap *env = NULL;
	struct glint_env_hot *hot = NULL;
	/* Five 2 x 2 lamps 40 degrees apart or more, one across u = 0. */
	static const int lamp[5][2] = {
		{ 0, 40 }, { 40, 20 }, { 100, 60 }, { 160, 90 }, { 210, 50 }
	};

	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			for (int c = 0; c < 3; c++)
				glint_image_px(img, x, y)[c] = 0.05f;
	for (int l = 0; l < 5; l++)
		for (int k = 0; k < 4; k++) {
			int x = (lamp[l][0] + k % 2 - 1 + w) % w,
			    y = lamp[l][1] + k / 2;
			for (int c = 0; c < 3; c++)
				glint_image_px(img, x, y)[c] = 400.0f + 50 * l;
		}
	CHECK(glint_envmap_new(img, rot, 1.0, "lamps", &env) == 0 &&
		      glint_env_hot_new(env, 0.01, 256, 2, &hot) == 0,
	      "%s", glint_error_msg());
	if (test_failures)
		return;
	CHECK(hot->ntexels >= 20, "every lamp is hot: %d texels", hot->ntexels);
	CHECK(hot->nclusters >= 5 && hot->nclusters <= 10,
	      "a cluster or two per lamp: %d", hot->nclusters);
	int pts = 0, part = 0;
	for (int c = 0; c < hot->nclusters; c++) {
		const struct glint_env_hot_cluster *cl = &hot->clusters[c];
		CHECK(cl->pts0 == pts && cl->part0 == part,
		      "cluster %d follows the last", c);
		CHECK(cl->part1 > cl->part0, "cluster %d holds points", c);
		/* The lamps are 40 degrees apart or more. */
		CHECK(cl->radius < 15 * M_PI / 180,
		      "cluster %d is one lamp: %.1f deg", c,
		      cl->radius * 180 / M_PI);
		for (int k = cl->pts0; k < cl->pts1; k++)
			CHECK(angle_to(cl->axis, hot->pts + 6 * k) <=
				      cl->radius,
			      "area point %d in cluster %d's cone", k, c);
		for (int k = cl->part0; k < cl->part1; k++)
			CHECK(angle_to(cl->axis, hot->part + 6 * k) <=
				      cl->radius,
			      "part point %d in cluster %d's cone", k, c);
		pts = cl->pts1;
		part = cl->part1;
	}
	CHECK(pts == hot->npts && part == hot->npart,
	      "the clusters hold every point: %d of %d, %d of %d", pts,
	      hot->npts, part, hot->npart);
	glint_env_hot_free(hot);
	glint_envmap_free(env);
}

int main(void)
{
	RUN(test_uv_dir);
	RUN(test_lookup);
	RUN(test_pdf_integrates);
	RUN(test_sampling_histogram);
	RUN(test_sampling_inverse);
	RUN(test_bad_maps);
	RUN(test_irradiance_odd_sizes);
	RUN(test_irradiance_softboxes);
	RUN(test_hot_split);
	RUN(test_query_batch);
	RUN(test_hot_coarse);
	RUN(test_hot_clusters);
	return test_result();
}
