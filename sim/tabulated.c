/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "tabulated.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "fit/brdf/microfacet.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

enum { NTH = 90, NTD = 90, NPD = 180, NBINS = NTH * NTD * NPD };

static const double chan_scale[3] = { 1.0 / 1500, 1.15 / 1500, 1.66 / 1500 };

struct glint_brdf_table {
	float *v; /* 3 planes of NBINS, unscaled (per steradian) */
};

static struct glint_brdf_table *table_new(void)
{
	struct glint_brdf_table *t = calloc(1, sizeof(*t));

	if (t && !(t->v = malloc((size_t)3 * NBINS * sizeof(float)))) {
		free(t);
		t = NULL;
	}
	return t;
}

void glint_brdf_table_free(struct glint_brdf_table *t)
{
	if (t)
		free(t->v);
	free(t);
}

int glint_brdf_table_read(const char *path, struct glint_brdf_table **out)
{
	FILE *f = fopen(path, "rb");
	int32_t dims[3];
	struct stat st;
	int ret = 0;

	*out = NULL;
	if (!f)
		return glint_error_set(errno, "%s: cannot open: %s", path,
				       strerror(errno));
	if (fstat(fileno(f), &st) < 0 || fread(dims, 4, 3, f) != 3)
		ret = glint_error_set(
			EINVAL, "%s: not a MERL BRDF: no 12-byte header", path);
	else if (dims[0] != NTH || dims[1] != NTD || dims[2] != NPD)
		ret = glint_error_set(EINVAL,
				      "%s: MERL BRDF dimensions %d x %d x %d: "
				      "expected %d x %d x %d",
				      path, dims[0], dims[1], dims[2], NTH, NTD,
				      NPD);
	else if ((long long)st.st_size != 12 + 3LL * NBINS * 8)
		ret = glint_error_set(EINVAL,
				      "%s: %lld bytes: a MERL BRDF of %d x %d "
				      "x %d has %lld",
				      path, (long long)st.st_size, NTH, NTD,
				      NPD, 12 + 3LL * NBINS * 8);
	struct glint_brdf_table *t = ret ? NULL : table_new();
	if (!ret && !t)
		ret = glint_error_set(ENOMEM, "out of memory");
	double *row = ret ? NULL : malloc(NPD * sizeof(double));
	if (!ret && !row)
		ret = glint_error_set(ENOMEM, "out of memory");
	for (size_t i = 0; !ret && i < (size_t)3 * NBINS; i += NPD) {
		if (fread(row, sizeof(double), NPD, f) != NPD) {
			ret = glint_error_set(EIO, "%s: short read", path);
			break;
		}
		for (int k = 0; k < NPD; k++) {
			double v = row[k] * chan_scale[i / NBINS];
			t->v[i + k] = isfinite(v) && v > 0 ? (float)v : 0;
		}
	}
	free(row);
	fclose(f);
	if (ret)
		glint_brdf_table_free(t);
	else
		*out = t;
	return ret;
}

int glint_brdf_table_write(const char *path, const struct glint_brdf_table *t)
{
	size_t n = 12 + (size_t)3 * NBINS * 8;
	unsigned char *buf = malloc(n);
	int32_t dims[3] = { NTH, NTD, NPD };

	if (!buf)
		return glint_error_set(ENOMEM, "out of memory");
	memcpy(buf, dims, 12);
	for (size_t i = 0; i < (size_t)3 * NBINS; i++) {
		double v = t->v[i] / chan_scale[i / NBINS];
		memcpy(buf + 12 + 8 * i, &v, 8);
	}
	int ret = glint_atomic_write_file(path, buf, n);
	free(buf);
	return ret;
}

/* Rotate v about the y axis (the binormal) by a, then about z by b. */
static struct vec3 rot_y(struct vec3 v, double a)
{
	double c = cos(a), s = sin(a);
	return v3(c * v.x + s * v.z, v.y, -s * v.x + c * v.z);
}

static struct vec3 rot_z(struct vec3 v, double a)
{
	double c = cos(a), s = sin(a);
	return v3(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
}

/* The bin of (wo, wi): Rusinkiewicz's half and difference angles. */
static size_t bin_of(struct vec3 wo, struct vec3 wi)
{
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double th = acos(fmin(1, fmax(-1, h.z))), ph = atan2(h.y, h.x);
	struct vec3 d = rot_y(rot_z(wi, -ph), -th);
	double td = acos(fmin(1, fmax(-1, d.z))), pd = atan2(d.y, d.x);
	if (pd < 0)
		pd += M_PI;
	int i = th <= 0 ? 0 : (int)(sqrt(th / (M_PI / 2)) * NTH);
	int j = (int)(td / (M_PI / 2) * NTD);
	int k = (int)(pd / M_PI * NPD);
	i = i < 0 ? 0 : i >= NTH ? NTH - 1 : i;
	j = j < 0 ? 0 : j >= NTD ? NTD - 1 : j;
	k = k < 0 ? 0 : k >= NPD ? NPD - 1 : k;
	return (size_t)k + (size_t)j * NPD + (size_t)i * NPD * NTD;
}

void glint_brdf_table_eval(const struct glint_brdf_table *t, struct vec3 wo,
			   struct vec3 wi, double rgb[3])
{
	rgb[0] = rgb[1] = rgb[2] = 0;
	if (!(wo.z > 0) || !(wi.z > 0))
		return;
	size_t b = bin_of(wo, wi);
	for (int c = 0; c < 3; c++)
		rgb[c] = t->v[(size_t)c * NBINS + b];
}

int glint_brdf_table_from(void (*f)(void *ctx, struct vec3 wo, struct vec3 wi,
				    double rgb[3]),
			  void *ctx, struct glint_brdf_table **out)
{
	struct glint_brdf_table *t = table_new();

	*out = NULL;
	if (!t)
		return glint_error_set(ENOMEM, "out of memory");
	for (int i = 0; i < NTH; i++) {
		double u = (i + 0.5) / NTH, th = u * u * (M_PI / 2);
		struct vec3 h = v3(sin(th), 0, cos(th));
		for (int j = 0; j < NTD; j++) {
			double td = (j + 0.5) / NTD * (M_PI / 2);
			for (int k = 0; k < NPD; k++) {
				double pd = (k + 0.5) / NPD * M_PI;
				struct vec3 d = v3(sin(td) * cos(pd),
						   sin(td) * sin(pd), cos(td));
				struct vec3 wi = rot_y(d, th);
				struct vec3 wo = v3_sub(
					v3_scale(h, 2 * v3_dot(wi, h)), wi);
				double rgb[3] = { 0, 0, 0 };
				if (wi.z > 0 && wo.z > 0)
					f(ctx, wo, wi, rgb);
				size_t b = (size_t)k + (size_t)j * NPD +
					   (size_t)i * NPD * NTD;
				for (int c = 0; c < 3; c++)
					t->v[(size_t)c * NBINS + b] =
						(float)rgb[c];
			}
		}
	}
	*out = t;
	return 0;
}

void glint_ashikhmin_shirley_eval(void *ctx, struct vec3 wo, struct vec3 wi,
				  double rgb[3])
{
	const struct glint_ashikhmin_shirley *a = ctx;
	struct vec3 h = v3_norm(v3_add(wo, wi));
	double hk = v3_dot(h, wi);
	double f = a->rs + (1 - a->rs) * pow(1 - hk, 5);
	double spec = (a->n + 1) / (8 * M_PI) * pow(h.z, a->n) /
		      (hk * fmax(wi.z, wo.z)) * f;
	double k1 = 1 - pow(1 - wi.z / 2, 5), k2 = 1 - pow(1 - wo.z / 2, 5);
	for (int c = 0; c < 3; c++)
		rgb[c] = 28 * a->rd[c] / (23 * M_PI) * (1 - a->rs) * k1 * k2 +
			 spec;
}

/* Lobe c's albedo: the unit vector of channel c. */
static const double unit_rgb[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };

static const double *tab_albedo(const void *self, int j)
{
	(void)self;
	return unit_rgb + 3 * j;
}

static void tab_eval(const void *self, struct vec3 wo, struct vec3 wi,
		     double f[3])
{
	const struct glint_tabulated *tab = self;

	glint_brdf_table_eval(tab->table, wo, wi, f);
}

static void tab_lobes(const void *self, struct vec3 wo, struct vec3 wi,
		      double *b)
{
	const struct glint_tabulated *tab = self;

	glint_brdf_table_eval(tab->table, wo, wi, b);
}

/* Half the cosine, half a Beckmann lobe about the mirror direction. */
static double tab_pdf_lobe(const void *self, int j, struct vec3 wo,
			   struct vec3 wi)
{
	const struct glint_tabulated *tab = self;

	(void)j;
	if (!(wi.z > 0) || !(wo.z > 0))
		return 0;
	return 0.5 * wi.z / M_PI +
	       0.5 * glint_beckmann_pdf(tab->proposal, wo, wi);
}

static double tab_sample_lobe(const void *self, int j, struct vec3 wo,
			      const double u[2], struct vec3 *wi)
{
	const struct glint_tabulated *tab = self;

	if (u[0] < 0.5) {
		double r = sqrt(u[1]), a = 2 * M_PI * (2 * u[0]);
		*wi = v3(r * cos(a), r * sin(a), sqrt(fmax(0, 1 - u[1])));
	} else {
		double uu[2] = { 2 * u[0] - 1, u[1] };
		glint_beckmann_sample(tab->proposal, wo, uu, wi);
	}
	return tab_pdf_lobe(self, j, wo, *wi);
}

static double tab_sample(const void *self, struct vec3 wo, const double u[3],
			 struct vec3 *wi)
{
	return tab_sample_lobe(self, 0, wo, u, wi);
}

static double tab_pdf(const void *self, struct vec3 wo, struct vec3 wi)
{
	return tab_pdf_lobe(self, 0, wo, wi);
}

static const struct glint_bxdf_ops tab_ops = {
	.flags = GLINT_BXDF_REFLECTION | GLINT_BXDF_DIFFUSE |
		 GLINT_BXDF_GLOSSY | GLINT_BXDF_LOBES,
	.eval = tab_eval,
	.sample = tab_sample,
	.pdf = tab_pdf,
	.nlobes = 3,
	.albedo = tab_albedo,
	.eval_lobes = tab_lobes,
	.sample_lobe = tab_sample_lobe,
	.pdf_lobe = tab_pdf_lobe,
};

struct glint_bxdf glint_tabulated_bxdf(struct glint_tabulated *tab,
				       const struct glint_brdf_table *t,
				       double proposal)
{
	tab->table = t;
	tab->proposal = proposal;
	return (struct glint_bxdf){ &tab_ops, tab };
}
