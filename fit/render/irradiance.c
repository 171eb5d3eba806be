/* SPDX-License-Identifier: MIT */
#include "irradiance.h"

#include "core/error.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* At most this many cells across (the map reduced by an integer factor):
 * studio.exr's irradiance within 0.05 % rms of the full map's at 128 cells,
 * 0.02 % at 256, no better at 512 (the grid's interpolation dominates). */
#define MAX_CELLS 256
/* A node of at most this many cells is summed cell by cell. */
#define BUCKET 16

/*
 * A rectangle of cells [x0, x1) x [y0, y1): the sum of its cells' first
 * moments (per channel, the integral of L(w) w dw), and a cone holding every
 * direction of its texels (axis, sine of the half-angle; 2 when the cone is
 * a hemisphere or more: never wholly on one side of a normal).
 */
struct irr_node {
	double m[3][3];
	struct vec3 axis;
	double sin_r;
	int x0, y0, x1, y1;
	int child; /* index of the first of two children, or -1 */
};

struct irr_tree {
	int w, h;     /* the map's size */
	int cw, ch;   /* cells across and down */
	int f;	      /* map texels per cell side */
	double *cell; /* cw * ch * 9: each cell's moments */
	struct irr_node *node;
	int nnodes, cap;
	const struct mat3 *rot; /* world from map */
};

/* The first moment of a lat-long texel (the integral of w dw over it) in
 * the map's convention (glint_latlong_uv_to_dir: w = (sin t sin p, cos t,
 * -sin t cos p), t the polar angle from +y): a product of a row's and a
 * column's integrals. */
struct row_integrals {
	double s2; /* integral of sin^2 t dt over the row */
	double y;  /* integral of cos t sin t dt */
};

struct col_integrals {
	double sx; /* integral of sin p dp over the column */
	double cz; /* integral of cos p dp */
	double dp; /* its width */
};

static struct row_integrals texel_row(double t0, double t1)
{
	double sa = sin(t0), sb = sin(t1);

	return (struct row_integrals){
		(t1 - t0) / 2 - (sin(2 * t1) - sin(2 * t0)) / 4,
		(sb * sb - sa * sa) / 2,
	};
}

static struct col_integrals texel_col(double p0, double p1)
{
	return (struct col_integrals){ cos(p0) - cos(p1), sin(p1) - sin(p0),
				       p1 - p0 };
}

/* The cone of the lat-long rectangle [t0, t1] x [p0, p1]: axis at its middle;
 * for a fixed polar angle the farthest point is at an azimuth edge, and
 * along an edge at an end (the distance is a sinusoid of the polar angle
 * peaking inside), so the corners bound it. */
static void rect_cone(double t0, double t1, double p0, double p1,
		      struct irr_node *nd)
{
	struct vec3 a =
		v3(sin((t0 + t1) / 2) * sin((p0 + p1) / 2), cos((t0 + t1) / 2),
		   -sin((t0 + t1) / 2) * cos((p0 + p1) / 2));
	double cmin = 1;

	nd->axis = a;
	if (p1 - p0 > M_PI) {
		nd->sin_r = 2;
		return;
	}
	for (int k = 0; k < 4; k++) {
		double t = k & 1 ? t1 : t0, p = k & 2 ? p1 : p0;
		struct vec3 c = v3(sin(t) * sin(p), cos(t), -sin(t) * cos(p));
		double d = v3_dot(a, c);
		cmin = d < cmin ? d : cmin;
	}
	/* sin of the half-angle, with a margin for rounding */
	nd->sin_r = cmin <= 0 ? 2 : sqrt(fmax(0, 1 - cmin * cmin)) + 1e-9;
}

static int imin(int a, int b)
{
	return a < b ? a : b;
}

static int add_node(struct irr_tree *t, int x0, int y0, int x1, int y1)
{
	if (t->nnodes == t->cap) {
		int cap = t->cap ? 2 * t->cap : 256;
		struct irr_node *n = realloc(t->node, cap * sizeof(*n));
		if (!n)
			return -1;
		t->node = n;
		t->cap = cap;
	}
	struct irr_node *nd = &t->node[t->nnodes];
	memset(nd, 0, sizeof(*nd));
	nd->x0 = x0;
	nd->y0 = y0;
	nd->x1 = x1;
	nd->y1 = y1;
	nd->child = -1;
	rect_cone(M_PI * imin(y0 * t->f, t->h) / t->h,
		  M_PI * imin(y1 * t->f, t->h) / t->h,
		  2 * M_PI * ((double)imin(x0 * t->f, t->w) / t->w - 0.5),
		  2 * M_PI * ((double)imin(x1 * t->f, t->w) / t->w - 0.5), nd);
	return t->nnodes++;
}

/* Splits node i (the longer side in halves) until buckets are small; sums
 * the moments up.  Depth is log2 of the cell count. */
static int build_node(struct irr_tree *t, int i)
{
	int x0 = t->node[i].x0, y0 = t->node[i].y0;
	int x1 = t->node[i].x1, y1 = t->node[i].y1;

	if ((x1 - x0) * (y1 - y0) <= BUCKET) {
		for (int y = y0; y < y1; y++)
			for (int x = x0; x < x1; x++)
				for (int k = 0; k < 9; k++)
					t->node[i].m[k / 3][k % 3] +=
						t->cell[((size_t)y * t->cw +
							 x) * 9 +
							k];
		return 0;
	}
	int a, b;
	if (x1 - x0 >= y1 - y0) {
		int xm = (x0 + x1) / 2;
		a = add_node(t, x0, y0, xm, y1);
		b = add_node(t, xm, y0, x1, y1);
	} else {
		int ym = (y0 + y1) / 2;
		a = add_node(t, x0, y0, x1, ym);
		b = add_node(t, x0, ym, x1, y1);
	}
	if (a < 0 || b < 0)
		return -1;
	t->node[i].child = a; /* b == a + 1 */
	if (build_node(t, a) < 0 || build_node(t, b) < 0)
		return -1;
	for (int k = 0; k < 9; k++)
		t->node[i].m[k / 3][k % 3] =
			t->node[a].m[k / 3][k % 3] + t->node[b].m[k / 3][k % 3];
	return 0;
}

/* E(n) for a map-frame normal: a node wholly above n's horizon adds n . m
 * (exact: the cosine is linear there), one wholly below nothing, one across
 * it is split; a cell across it adds its clamped n . m. */
static void tree_query(const struct irr_tree *t, struct vec3 n, double e[3])
{
	int stack[64], sp = 0;

	e[0] = e[1] = e[2] = 0;
	stack[sp++] = 0;
	while (sp) {
		const struct irr_node *nd = &t->node[stack[--sp]];
		double c = v3_dot(n, nd->axis);
		if (nd->sin_r <= 1 && c >= nd->sin_r) {
			for (int ch = 0; ch < 3; ch++)
				e[ch] += n.x * nd->m[ch][0] +
					 n.y * nd->m[ch][1] +
					 n.z * nd->m[ch][2];
			continue;
		}
		if (nd->sin_r <= 1 && c <= -nd->sin_r)
			continue;
		if (nd->child >= 0 && sp + 2 <= 64) {
			stack[sp++] = nd->child;
			stack[sp++] = nd->child + 1;
			continue;
		}
		for (int y = nd->y0; y < nd->y1; y++)
			for (int x = nd->x0; x < nd->x1; x++) {
				const double *m =
					t->cell + ((size_t)y * t->cw + x) * 9;
				for (int ch = 0; ch < 3; ch++) {
					double d = n.x * m[3 * ch] +
						   n.y * m[3 * ch + 1] +
						   n.z * m[3 * ch + 2];
					if (d > 0)
						e[ch] += d;
				}
			}
	}
}

struct irr_job {
	struct glint_irradiance *ir;
	const struct irr_tree *t;
};

static void irr_rows(void *ctx, int y0, int y1, int thread)
{
	struct irr_job *job = ctx;
	struct glint_irradiance *ir = job->ir;

	(void)thread;
	for (int y = y0; y < y1; y++)
		for (int x = 0; x < ir->w; x++) {
			struct vec3 n = glint_latlong_uv_to_dir(
				(x + 0.5) / ir->w, (y + 0.5) / ir->h);
			tree_query(job->t, m3_tmul(job->t->rot, n),
				   ir->e + ((size_t)y * ir->w + x) * 3);
		}
}

/* Each cell's moments: per map texel, the mean of the bilinear radiance
 * over it (a separable [1, 6, 1] / 8 filter) times the texel's exact
 * first moment. */
static int cell_moments(const struct glint_envmap *env,
			const unsigned char *exclude, struct irr_tree *t)
{
	static const double k[3] = { 1.0 / 8, 6.0 / 8, 1.0 / 8 };
	const struct glint_image *img = env->img;
	int W = img->width, H = img->height;
	struct col_integrals *col = malloc((size_t)W * sizeof(*col));

	if (!col)
		return -1;
	for (int i = 0; i < W; i++)
		col[i] = texel_col(2 * M_PI * ((double)i / W - 0.5),
				   2 * M_PI * ((double)(i + 1) / W - 0.5));
	for (int j = 0; j < H; j++) {
		struct row_integrals row =
			texel_row(M_PI * j / H, M_PI * (j + 1) / H);
		for (int i = 0; i < W; i++) {
			if (exclude && exclude[(size_t)j * W + i])
				continue;
			struct vec3 mo =
				v3(row.s2 * col[i].sx, row.y * col[i].dp,
				   -row.s2 * col[i].cz);
			double l[3] = { 0, 0, 0 };
			for (int dy = -1; dy <= 1; dy++) {
				int y = j + dy < 0    ? 0
					: j + dy >= H ? H - 1
						      : j + dy;
				for (int dx = -1; dx <= 1; dx++) {
					int x = ((i + dx) % W + W) % W;
					const float *p =
						glint_image_px(img, x, y);
					for (int c = 0; c < 3; c++)
						l[c] += k[dx + 1] * k[dy + 1] *
							p[c];
				}
			}
			double *dst =
				t->cell +
				((size_t)(j / t->f) * t->cw + i / t->f) * 9;
			for (int c = 0; c < 3; c++) {
				double s = l[c] * env->scale;
				dst[3 * c] += s * mo.x;
				dst[3 * c + 1] += s * mo.y;
				dst[3 * c + 2] += s * mo.z;
			}
		}
	}
	free(col);
	return 0;
}

int glint_irradiance_build(const struct glint_envmap *env,
			   const unsigned char *exclude, int w, int nthreads,
			   struct glint_irradiance *ir)
{
	int W = env->img->width, H = env->img->height;
	struct irr_tree t = { 0 };
	int ret = 0;

	/* Cells of f x f texels; the last row and column of cells may be
	 * narrower when f does not divide the size (their moments are the
	 * sums of the texels they hold, so the sum stays exact). */
	t.w = W;
	t.h = H;
	t.f = W / MAX_CELLS > 1 ? W / MAX_CELLS : 1;
	t.cw = (W + t.f - 1) / t.f;
	t.ch = (H + t.f - 1) / t.f;
	t.rot = &env->rot;
	t.cell = calloc((size_t)t.cw * t.ch * 9, sizeof(double));
	ir->w = w;
	ir->h = w / 2;
	ir->e = calloc((size_t)ir->w * ir->h * 3, sizeof(double));
	if (!t.cell || !ir->e)
		goto nomem;
	if (cell_moments(env, exclude, &t) < 0 ||
	    add_node(&t, 0, 0, t.cw, t.ch) < 0 || build_node(&t, 0) < 0)
		goto nomem;
	struct irr_job job = { ir, &t };
	ret = glint_parallel_for(ir->h, 1, nthreads, irr_rows, &job);
	free(t.cell);
	free(t.node);
	if (ret < 0)
		glint_irradiance_free(ir);
	return ret;
nomem:
	free(t.cell);
	free(t.node);
	glint_irradiance_free(ir);
	return glint_error_set(ENOMEM, "out of memory");
}

/* Catmull-Rom weights of the four nodes around fraction s. */
static void cr_weights(double s, double wt[4])
{
	double s2 = s * s, s3 = s2 * s;

	wt[0] = 0.5 * (-s3 + 2 * s2 - s);
	wt[1] = 0.5 * (3 * s3 - 5 * s2 + 2);
	wt[2] = 0.5 * (-3 * s3 + 4 * s2 + s);
	wt[3] = 0.5 * (s3 - s2);
}

void glint_irradiance_lookup(const struct glint_irradiance *ir, struct vec3 n,
			     double e[3])
{
	double u, v, wx[4], wy[4];

	glint_latlong_dir_to_uv(n, &u, &v);
	double x = u * ir->w - 0.5, y = v * ir->h - 0.5;
	double fx = floor(x), fy = floor(y);
	cr_weights(x - fx, wx);
	cr_weights(y - fy, wy);
	e[0] = e[1] = e[2] = 0;
	for (int j = 0; j < 4; j++) {
		int yy = (int)fy + j - 1;
		yy = yy < 0 ? 0 : yy >= ir->h ? ir->h - 1 : yy;
		for (int i = 0; i < 4; i++) {
			int xx = (((int)fx + i - 1) % ir->w + ir->w) % ir->w;
			const double *p = ir->e + ((size_t)yy * ir->w + xx) * 3;
			for (int ch = 0; ch < 3; ch++)
				e[ch] += wx[i] * wy[j] * p[ch];
		}
	}
	/* the cubic can undershoot next to a dark region's edge */
	for (int ch = 0; ch < 3; ch++)
		e[ch] = e[ch] > 0 ? e[ch] : 0;
}

void glint_irradiance_free(struct glint_irradiance *ir)
{
	free(ir->e);
	ir->e = NULL;
}
