/* SPDX-License-Identifier: MIT */
/*
 * The model discrepancy (its calibrated systematic term) and the misfit regions
 * where a structure shows.
 */
#include "fit/internal.h"
#include "fit/fit_data.h"
#include "fit/misfit.h"
#include "fit/optim/anneal.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/suggest.h"
#include "core/log.h"
#include "core/pinhole.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * The systematic standard uncertainty of each parameter, from what the
 * light map is made of (map_pixel_deg, struct glint_fit_opts).
 *
 * The fast render against the reference renderer, under a map that is the
 * light itself: 0.1 % of the diffuse albedos, 0.5 % of the specular,
 * 1.3 % of roughness and 0.2 % of ior (an absolute 0.0002 floor on
 * albedos, whose small values make relative errors large), from the
 * coverage study (tests/sim/test_coverage.c, the full study under Venice,
 * fits of photos the reference renderer made until each pixel's relative
 * standard error was under 1 %, 27 values a class): the diffuse albedos'
 * term the 68th percentile of |fit - truth| / truth over noise-free fits, the
 * specular albedos' and ior's their 95th percentile over 1.96, since
 * their tails are heavier.  Roughness's noise-free 68th percentile is
 * 0.7 %, but at 0.7 % 8 of the 52 roughness intervals on dim photos (10 000
 * and 1 000 electrons) missed, 7 of them broad lobes (matte paint and
 * teflon), whose statistical part falls short of what the noise does to
 * a broad, faint highlight; at 1.3 % 3 miss (92-96 % covered) and the
 * noise-free median |error| / sigma is 0.47.  What the light's measurement adds
 * is carried by its own terms: the map's scale (light_scale_sigma) and
 * each compact source's flux, on every photo of a joint fit too
 * (fit/light_sources.c).  This term is one calibration for every map;
 * the render's error under this photo's light, as its residual shows it
 * region by region, is a term of its own beside it (fit/render_gain.c).
 *
 * A map unwrapped from a probe is that light seen through the probe's
 * pixels, and a highlight under a blurred map is broader, which the fit
 * answers with a smoother surface: the specular albedos keep 0.7 % and
 * ior 0.2 % (the simulated rig's), and roughness gains a term that grows
 * as the square of the probe pixel's angle (a lobe of width m fitted
 * under light blurred by b: m^2 - b^2 / 4 to first order), through the
 * two resolutions measured: roughness 2.5 % off at the 68th percentile of
 * the eleven materials on the simulated rig (bench/rig_materials.py, its
 * ball 96 px in radius: 1.69 degrees a pixel at 90 degrees from the
 * probe's axis) and 6.7 % with the ball at 60 px (2.70 degrees), whose
 * ratio less the fast render's 0.7 % is (2.70 / 1.69) to the power 2.2;
 * beside the 1.3 % above, 2.7 % on the shipped rig (6.3 % at 60 px).
 * A probe of unknown resolution
 * (a sources file without map_pixel_deg) gets 4.1 % for the blur.
 *
 * Coarser still, a relative term on roughness is not enough: on the
 * simulated rig at 160 x 120 (the probe's ball 48 px in radius, 3.37
 * degrees a pixel) the sun is not found as a compact source (its peak is
 * 6 times the ring around it, under the detector's 8), stays in the map
 * as a blob the camera's blur wide, and narrow lobes collapse under it:
 * yellow plastic (0.039) fits 0.0008, nickel (0.033) 0.007, semi-gloss
 * paint (0.054) 0.037.  To first order a lobe of width m under light
 * blurred by b fits m^2 - b^2 / 4, whatever m is: an absolute floor in
 * m^2.  The term is the larger of the relative one and
 * sqrt(m^2 + B^2) - m, B = FIT_SYS_LIGHT_FLOOR p^2 (p the probe pixel's
 * angle in radians): 0.0278 at 3.37 degrees, the least that covers those
 * three (semi-gloss paint needs 0.027), 0.018 at 2.70 degrees (where
 * aluminium bronze, 0.023, fits 0.029 with the sun found: its glow
 * within the 4-pixel aperture becomes a point) and 0.007 on the shipped
 * rig, under its relative term for every Table-1 lobe that the pixels
 * resolve.
 *
 * The sphere's own size biases the specular albedos and ior: the fit of
 * the simulated rig's 160 x 120 photo (a sphere 39 px in radius by its
 * interior pixels) under the 320 x 240 probe's map gives yellow plastic's
 * specular 12 % high and ior 0.035 low, with the roughness right.  Over
 * the eleven materials, the specular term a 95 % interval needs, beside
 * the rest of it, is 0.7 % at 81 px (the shipped rig), about 1 % at 60,
 * 3.6 % at 50 and 5 % at 39: it switches on steeply below 60 px, and
 * FIT_SYS_SMALL / R^4 (3.6 % at 50 px, 9.6 % at 39, 0.5 % at 81) follows
 * it with margin at the smallest.  The bias runs along the specular/ior
 * ridge: 12 % more specular and 0.035 less ior leave specular x F0(ior)
 * where it was (F0 at 1.5 falls by 11 % for that ior), so the sphere pins
 * the highlight's brightness and its small rim, where the Fresnel rise
 * tells the two apart, misplaces the split.  So the term is one error
 * source shared by the specular albedos (that relative amount each) and
 * ior (the amount that keeps F0 x specular: -(n^2 - 1) / 4 times it), not
 * independent terms, which would hide the ridge from the correlations
 * (a front-lit sphere 52 px in radius would read corr(specular, ior)
 * -0.90 where the photo says -1).  The bias is measured on the rig's
 * camera, which blurs (a lens PSF, an optical low-pass filter, a Bayer
 * mosaic); the coverage study's photos (tests/sim/test_coverage.c: a
 * sphere 53 px in radius, no camera blur, the light exact) do not show
 * it (specular's relative error 0.3 % at the 68th percentile
 * noise-free), so the term applies to photos whose camera blurs alone
 * (fit_blurred_sphere_px()).  The other shape parameters (a second
 * lobe's width, Oren-Nayar's diffuse roughness), not measured on small
 * spheres, take FIT_SYS_SMALL_SHAPE of it, on their own.  Below 38 px
 * (FIT_SYS_SMALLEST_PX; the smallest measured is 38.9) the terms are
 * extrapolated, and the fit says so (fit.c).
 *
 * Under a probe's light the diffuse albedos also take up part of what the
 * map gets wrong about the specular lobe's light: on the simulated rig,
 * its photos fitted in their measured colours (fit_data.c), every
 * material's red diffuse came out low, paints' by 0.3-0.5 % and the
 * metals' diffuse by 0.0005-0.0016, 2-3 % of it, growing with the
 * specular albedo (copper, nickel: 0.0009-0.0016 where the specular's
 * mean is 0.54 and 0.77).  A diffuse albedo's term gains 0.25 % of the
 * mean of the varying lobes' albedos, the largest of those ratios.
 */
void fit_systematic(const struct glint_model *m, const double *p,
		    double map_pixel_deg, double sphere_px, double *sys,
		    double *shared)
{
	int probe = map_pixel_deg != 0;
	double blur = map_pixel_deg > 0 ? 0.024 * pow(map_pixel_deg / 1.69, 2)
					: 0.041;
	double pix = map_pixel_deg > 0 ? map_pixel_deg * M_PI / 180 : 0;
	double floor_m = FIT_SYS_LIGHT_FLOOR * pix * pix;
	double small = sphere_px > 0 ? FIT_SYS_SMALL / pow(sphere_px, 4) : 0;
	double ridge[GLINT_MAX_PARAMS] = { 0 };
	double lobe_mean = 0;
	int nvary = 0;
	for (int j = 0; j < m->bxdf->nlobes; j++) {
		if (!m->lobes->varies[j])
			continue;
		for (int c = 0; c < 3; c++)
			lobe_mean += fabs(p[m->lobes->param[j] + c]) / 3;
		nvary++;
	}
	lobe_mean = nvary ? lobe_mean / nvary : 0;
	for (int k = 0; k < m->nparams; k++) {
		double rel = 0.002, floor = 0, cross = 0;
		for (int j = 0; j < m->bxdf->nlobes; j++)
			if (k >= m->lobes->param[j] &&
			    k < m->lobes->param[j] + 3) {
				rel = !m->lobes->varies[j] ? 0.001
				      : probe		   ? 0.007
							   : 0.005;
				if (m->lobes->varies[j])
					ridge[k] = small * p[k];
				floor = 0.0002;
				if (probe && !m->lobes->varies[j])
					cross = 0.0025 * lobe_mean;
			}
		if (k == m->lobes->roughness_param)
			rel = probe ? hypot(0.013, blur) : 0.013;
		else if (!(floor > 0) && !strcmp(m->params[k].name, "ior"))
			ridge[k] =
				p[k] > 1 ? -small * (p[k] * p[k] - 1) / 4 : 0;
		else if (!(floor > 0)) /* another shape parameter */
			rel = hypot(rel, FIT_SYS_SMALL_SHAPE * small);
		sys[k] = hypot(hypot(rel * fabs(p[k]), floor), cross);
		/* the light's structure below the probe's pixel: m^2 known to
		 * floor_m^2 (see above) */
		if (k == m->lobes->roughness_param)
			sys[k] =
				fmax(sys[k], hypot(p[k], floor_m) - fabs(p[k]));
		if (shared)
			shared[k] = ridge[k];
		else
			sys[k] = hypot(sys[k], ridge[k]);
	}
}

/* The smallest sphere's radius over the views (blurred: those whose
 * camera blurs alone), 0 when none. */
static double smallest_sphere_px(const struct objective *ob, int blurred)
{
	double r = 0;
	for (int v = 0; v < ob->nviews; v++) {
		const struct glint_pinhole *cam = &ob->views[v].r->scene.cam;
		double rv = sqrt(ob->views[v].interior / M_PI);
		if (blurred && !glint_pixel_filter_on(cam) && cam->cfa[0] < 0)
			continue;
		if (rv > 0 && (r == 0 || rv < r))
			r = rv;
	}
	return r;
}

double fit_blurred_sphere_px(const struct objective *ob)
{
	return smallest_sphere_px(ob, 1);
}

double fit_sphere_px(const struct objective *ob)
{
	return smallest_sphere_px(ob, 0);
}

double glint_fit_discrepancy_scale(const struct glint_model *m, const double *p,
				   int k, int *cls)
{
	*cls = k == m->lobes->roughness_param ? 2 : 3;
	for (int j = 0; j < m->bxdf->nlobes && *cls == 3; j++) {
		int a = m->lobes->param[j];
		if (k < a || k >= a + 3)
			continue;
		*cls = m->lobes->varies[j] ? 1 : 0;
		double mean =
			(fabs(p[a]) + fabs(p[a + 1]) + fabs(p[a + 2])) / 3;
		return fmax(fabs(p[k]), mean);
	}
	return fabs(p[k]);
}

/*
 * The model-discrepancy standard uncertainty of each parameter when the
 * model misses the photo with structure (misfit_regions()): for a material
 * the model does not hold, the answer is the model that best imitates it
 * under this light, and moves under another; the jackknife over regions
 * sees that only where regions of one photo disagree, not where every
 * region leans the same way (one sun: every pixel sees the lobe at the
 * same half-angle).  u = c x share x scale (glint_fit_discrepancy_scale()),
 * share the structure's part of the relative RMSE.  How far answers move
 * was measured (bench/misfit) on six materials none of glint's models
 * (Phong, Ward, GGX over Lambert, a Blinn-Phong metal, Oren-Nayar's rough
 * diffuse under a Blinn-Phong lobe, Burley's diffuse under GGX) under four
 * maps at four headings: per material and class, the 95th percentile over
 * pairs of lights of the c that puts the two answers within their combined
 * interval; c is the largest over the materials (each of the six gets its
 * pairs' 95 %).  Held out: the Ashikhmin-Shirley sphere of
 * tests/sim/test_tabulated.c.
 */
void fit_discrepancy(const struct glint_model *m, const double *p, double share,
		     double *u)
{
	/* diffuse albedo, specular albedo, roughness, other */
	static const double coef[4] = { 1.15, 0, 2.79, 0.42 };

	for (int k = 0; k < m->nparams; k++) {
		int cl;
		double s = glint_fit_discrepancy_scale(m, p, k, &cl);
		u[k] = coef[cl] * share * s;
	}
}

/* Per region of misfit_regions(): the sums of its pixels' residual in
 * radiance (the mean over their channels), of its square, and of the
 * photo's values, and the pixel count. */
struct region_sums {
	double e, e2, y;
	long n;
};

static void region_add(struct region_sums *g, const struct fit_data *d,
		       const double *r, int px)
{
	double e = 0, y = 0;
	int nc = 0;

	for (int c = 0; c < 3; c++) {
		double sw = d->sw[3 * px + c];
		if (!(sw > 0))
			continue;
		e += r[c] / sw;
		y += d->y[3 * px + c];
		nc++;
	}
	if (!nc)
		return;
	g->e += e / nc;
	g->e2 += e * e / (nc * nc);
	g->y += y / nc;
	g->n++;
}

/* The structure's share of the signal: the regions' mean residuals, each
 * less its own noise (the spread within it), as an RMS over the pixels,
 * over the photo's mean there.  Unbiased in the square (no region's term
 * clipped; only the total, at 0), so the right model's is about 0. */
static double structure_share(const struct region_sums *g, int ng)
{
	double st = 0, sy = 0;
	long n = 0;

	for (int k = 0; k < ng; k++) {
		if (g[k].n < 2)
			continue;
		double mean = g[k].e / g[k].n,
		       var = (g[k].e2 - g[k].e * mean) / (g[k].n - 1);
		st += g[k].n * (mean * mean - var / g[k].n);
		sy += g[k].y;
		n += g[k].n;
	}
	return n && sy > 0 && st > 0 ? sqrt(st / n) / (sy / n) : 0;
}

/*
 * The regions of the model-error jackknife (fit/optim/uncertainty.h) for
 * the residuals r (3 per fitted pixel) when they show structure, as
 * fit/misfit.h judges it (a band of either angle more than 5 standard
 * errors off zero, and with a real noise model a chi^2 above 1.5); each
 * pixel's region is its band of the angle from the mirror direction to
 * the brightest light and its third of the view angle (0-30, 30-60,
 * 60-90 degrees), per photo (-1: no hits).  Returns the number of
 * regions, or 0 when the residual shows no structure; *share is the
 * structure's share of the signal (structure_share()) either way: a
 * structure under a noisy photo's chi^2 is still one (the tabulated
 * sphere under the studio map: 11 % of the signal at chi^2 1.4).
 */
int fit_misfit_regions(const struct objective *ob, const struct selections *sl,
		       const double *r, int *region, double *share)
{
	enum { B = GLINT_MISFIT_BANDS, R = 3 * B };
	const struct fit_data *d = ob->d;
	double s[2][B] = { { 0 } }, s2[2][B] = { { 0 } }, c2 = 0;
	long cnt[2][B] = { { 0 } };
	int ids[GLINT_FIT_MAX_VIEWS * R], nr = 0;
	struct region_sums sums[GLINT_FIT_MAX_VIEWS * R];
	struct vec3 light[GLINT_FIT_MAX_VIEWS];

	memset(sums, 0, sizeof(sums));
	for (int v = 0; v < ob->nviews; v++)
		light[v] = glint_misfit_light(ob->views[v].r->env);
	for (int k = 0; k < ob->nviews * R; k++)
		ids[k] = -1;
	for (int t = 0; t < sl->nall; t++) {
		int px = sl->all[t], v = fit_view_of(ob, px), kv, km;
		const struct glint_gbuffer *gb = &ob->views[v].r->gb;
		const struct glint_hit *hs =
			glint_gbuffer_pixel(gb, (size_t)d->pix[px]);
		double z = (r[3 * t] + r[3 * t + 1] + r[3 * t + 2]) / 3;
		for (int c = 0; c < 3; c++)
			c2 += r[3 * t + c] * r[3 * t + c];
		if (!hs) {
			region[3 * t] = region[3 * t + 1] = region[3 * t + 2] =
				-1;
			continue;
		}
		glint_misfit_bands(hs, gb->spp, light[v], &kv, &km);
		int b[2] = { kv, km };
		for (int a = 0; a < 2; a++) {
			s[a][b[a]] += z;
			s2[a][b[a]] += z * z;
			cnt[a][b[a]]++;
		}
		int g = v * R + km * 3 + kv / 3;
		if (ids[g] < 0)
			ids[g] = nr++;
		for (int c = 0; c < 3; c++)
			region[3 * t + c] = ids[g];
		region_add(&sums[g], d, r + 3 * t, px);
	}
	double zmax = 0;
	for (int a = 0; a < 2; a++)
		for (int k = 0; k < B; k++) {
			long n = cnt[a][k];
			if (n < 20)
				continue;
			double mean = s[a][k] / n,
			       var = (s2[a][k] - s[a][k] * mean) / (n - 1);
			if (var > 0)
				zmax = fmax(zmax, fabs(mean) / sqrt(var / n));
		}
	int noisy = !d->noise_model || c2 / (3.0 * sl->nall) > 1.5;
	*share = structure_share(sums, ob->nviews * R);
	return zmax > 5 && noisy ? nr : 0;
}
