/* SPDX-License-Identifier: MIT */
/*
 * The light sources' part of the intervals: a compact source the probe
 * resolves coarsely (a lamp a pixel or two across on the chrome ball) has
 * a flux known to some per cent, and the answer leans on it.  For each
 * source the fit renders the source alone (the map's texels within its
 * radius, the rest black) over the fitted pixels of the photo whose map
 * holds it (a joint fit's other photos saw other lights), at the optimum, with
 * the fit's own sample counts, of the source's one-sigma flux error (its
 * shape in the map carrying each channel's sigma).  The photo is linear
 * in each source's flux, so that error moves the weighted residuals by
 * that render c, and the least-squares optimum by A^-1 J^T c to first
 * order (A = J^T J; the channels' errors taken as one).  Its size is the
 * source's standard uncertainty in each parameter, which joins the systematic
 * part; the largest per parameter names the light that limits it (result.c's
 * findings).
 */
#include "fit/internal.h"
#include "fit/fit_data.h"
#include "fit/optim/uncertainty.h"

#include "core/error.h"
#include "core/log.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The source's one-sigma flux error as a map: its shape (the map's texels
 * within its radius of its direction, at least the one it falls in, the
 * mean of their channels) carrying flux_sigma in each channel; NULL when
 * the map is black there.  Scaled so from the shape, a channel the map
 * holds no flux of (a sun's colour aliased in the probe's mosaic: blue 0
 * +- 53) still carries its sigma. */
static struct glint_image *
source_error(const struct glint_image *map,
	     const struct glint_fit_light_source *src)
{
	int w = map->width, h = map->height;
	struct vec3 d = v3(src->dir[0], src->dir[1], src->dir[2]);
	/* a texel's half-diagonal at the equator, so a source smaller than
	 * a texel keeps the one it falls in */
	double texel = M_PI / h,
	       radius = fmax(src->radius_deg * M_PI / 180, 0.75 * texel);
	double c = cos(radius), flux = 0;
	struct glint_image *img = glint_image_new(w, h);

	if (!img)
		return NULL;
	for (int y = 0; y < h; y++) {
		double dw = (2 * M_PI / w) * texel * sin((y + 0.5) * texel);
		for (int x = 0; x < w; x++) {
			struct vec3 t = glint_latlong_uv_to_dir((x + 0.5) / w,
								(y + 0.5) / h);
			if (v3_dot(t, d) < c)
				continue;
			const float *v = glint_image_px(map, x, y);
			double l = (v[0] + v[1] + v[2]) / 3;
			float *o = img->data + 3 * ((size_t)y * w + x);
			o[0] = o[1] = o[2] = (float)l;
			flux += l * dw;
		}
	}
	if (!(flux > 0)) {
		glint_image_free(img);
		return NULL;
	}
	for (size_t i = 0; i < (size_t)w * h; i++)
		for (int k = 0; k < 3; k++)
			img->data[3 * i + k] *=
				(float)(src->flux_sigma[k] / flux);
	return img;
}

/* The weighted render of source s's one-sigma flux error at ob->p, per
 * residual row, into out (3 * ob->nsel): over the rows of the photo whose
 * map holds it, 0 on a joint fit's other photos, whose light it is not;
 * 1 when it adds nothing. */
static int render_source(struct objective *ob,
			 const struct glint_fit_light_source *s, double *out)
{
	if (s->view < 0 || s->view >= ob->nviews)
		return 1;
	const struct view *vw = &ob->views[s->view];
	struct glint_renderer *r = vw->r;
	struct glint_image *img = source_error(r->env->img, s);
	struct glint_envmap *env = NULL;
	struct glint_shade_cache *cache = NULL;
	int nj = ob->m->bxdf->nlobes, n = 0, ret;

	if (!img)
		return 1;
	ret = glint_envmap_new(img, r->scene.env_rotation, r->env->scale,
			       "a light source's flux error", &env);
	if (ret < 0)
		return ret;
	struct glint_shade_cache_opts co = {
		.light_samples = ob->o->light_samples * ob->sample_scale,
		.lobe_samples = ob->o->lobe_samples * ob->sample_scale,
		.static_samples = ob->o->static_samples,
		.no_footprint =
			ob->o->no_footprint || r->scene.cam.aperture_radius > 0,
		.nthreads = ob->o->nthreads,
	};
	/* the view's rows: sel[] in its own cache's pixel numbers, row[]
	 * where each is among ob->sel */
	size_t cap = ob->nsel > 0 ? (size_t)ob->nsel : 1;
	int *sel = malloc(sizeof(int) * 2 * cap), *row = sel ? sel + cap : NULL;
	double *lobes = malloc(sizeof(double) * 3 * (size_t)nj * cap);
	ret = sel && lobes
		      ? glint_shade_cache_new(&r->gb, ob->d->pix + vw->off,
					      vw->n, env, ob->m, &co, &cache)
		      : glint_error_set(ENOMEM, "out of memory");
	for (int t = 0; t < ob->nsel && ret == 0; t++) {
		int i = ob->sel[t];
		out[3 * t] = out[3 * t + 1] = out[3 * t + 2] = 0;
		if (i < vw->off || i >= vw->off + vw->n)
			continue;
		sel[n] = i - vw->off;
		row[n++] = t;
	}
	if (ret == 0)
		glint_shade_cache_lobes_sel(cache, ob->p, sel, n, lobes);
	for (int k = 0; k < n && ret == 0; k++) {
		int t = row[k], i = ob->sel[t];
		for (int c = 0; c < 3; c++)
			out[3 * t + c] =
				ob->d->sw[3 * i + c] *
				fit_pixel_value(ob, ob->p, lobes, k, c);
	}
	free(sel);
	free(lobes);
	glint_shade_cache_free(cache);
	glint_envmap_free(env);
	return ret;
}

int fit_jtj_inverse(const double *jac, int rows, int n, double *ainv,
		    int *unseen)
{
	double a[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];

	for (int i = 0; i < n; i++)
		for (int j = 0; j <= i; j++) {
			double s = 0;
			for (int k = 0; k < rows; k++)
				s += jac[(size_t)k * n + i] *
				     jac[(size_t)k * n + j];
			a[i * n + j] = a[j * n + i] = s;
		}
	return glint_unc_normal_inverse(a, n, ainv, unseen);
}

int fit_source_terms(struct objective *ob, const double *jac,
		     struct glint_fit_result *res)
{
	const struct glint_fit_opts *o = ob->o;
	int n = ob->m->nparams, rows = 3 * ob->nsel, ret = 0;
	double ainv[GLINT_UNC_MAX_N * GLINT_UNC_MAX_N];
	int unseen[GLINT_UNC_MAX_N];

	res->nsources = 0;
	if (!o->nsources || !ob->cache || n > GLINT_UNC_MAX_N)
		return 0;
	ret = fit_jtj_inverse(jac, rows, n, ainv, unseen);
	double *c = malloc(sizeof(double) * (size_t)rows);
	if (!c)
		return glint_error_set(ENOMEM, "out of memory");
	for (int s = 0;
	     s < o->nsources && s < GLINT_FIT_MAX_SOURCES && ret == 0; s++) {
		const struct glint_fit_light_source *src = &o->sources[s];
		double *se = res->source_stderr[res->nsources];
		res->source[res->nsources++] = *src;
		memset(se, 0, sizeof(double) * GLINT_MAX_PARAMS);
		if (src->saturated)
			continue; /* no sigma: result.c says so */
		ret = render_source(ob, src, c);
		if (ret > 0) { /* black in the map: nothing to carry */
			ret = 0;
			continue;
		}
		if (ret < 0)
			break;
		double b[GLINT_UNC_MAX_N] = { 0 };
		for (int i = 0; i < rows; i++)
			for (int k = 0; k < n; k++)
				b[k] += jac[(size_t)i * n + k] * c[i];
		for (int k = 0; k < n; k++) {
			double d = 0;
			for (int j = 0; j < n; j++)
				d += ainv[k * n + j] * b[j];
			se[k] = unseen[k] ? 0 : fabs(d);
		}
	}
	free(c);
	return ret < 0 ? ret : 0;
}
