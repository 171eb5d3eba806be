/* SPDX-License-Identifier: MIT */
/*
 * The accuracy matrix: every shared light probe x every opaque Table-1
 * material, photos from the independent reference renderer (sim/) at
 * 256 px (64 jittered samples per pixel, 16 per technique: 1024 a pixel,
 * enough that the photo's own Monte Carlo noise does not move roughness;
 * a camera's pixel integrates its area, and 4 samples per pixel alias a
 * near-mirror's sun into a photo no camera takes), noise-free and
 * through the sensor model twice: as glint's rig takes a photo (a bracket
 * planned by glint's own bracket planner on the sphere, merged by glint's
 * raw merge: bracket_photo()) and
 * as one frame with the whole image's mean at 10 % of the ADC range (under
 * a map whose lights are in view the sphere sits far below it), both with
 * their 1/variance weights; each fitted with glint's defaults.
 *
 * Per case it reports
 *   bias     the fitter's own objective at the TRUE parameters (its
 *            default 8 + 8 samples, one set) against the noise-free photo: its
 * RMSE over the photo's Monte Carlo noise (estimated from a second reference
 * render with another seed, on the same pixels).  About 1 when the fast path's
 * estimate is unbiased and quiet; above it, the fitter's sampling shows; within
 * every parameter within the tolerances (albedo 0.01, roughness 5 %, ior 0.05);
 *            or (within<, "(bound)" in the table) roughness below
 *            the pixel footprint under the upper bound glint reports
 *            for it and every other parameter within;
 *   flagged  outside them, but glint itself said so: the interval holds
 *            the truth or the parameter is reported undetermined;
 *   refused  the fit failed (no answer at all);
 *   wrong    outside the tolerances, and the interval misses the truth;
 *   ideal    the chance that an unbiased fitter at the photo's noise (the
 *            noise part of glint's covariance) lands within: what the
 *            photo allows any fitter (ideal_within()).
 * and the truth's cost over the fit's on the fit's own objective (below 1:
 * the fit stopped short of the truth's basin; above: the fitter's model
 * or the photo's noise prefers the fit).
 *
 * and, per map and over all, each parameter class's interval coverage
 * (the share of fits whose 95 % interval holds the truth), the median of
 * |error| / standard error (about 0.67 for an honest interval; far below,
 * intervals wider than the errors need) and how many fits reported the
 * parameter undetermined.
 *
 *   bench/accuracy [quick|slice] [classes] [--check|--no-refusals|--within]
 *                  [MAP...]
 * No maps: every map in ../shared/data/probes and data/env (the angular
 * campus probe converted to lat-long: fixture_load_map()).  classes: the six
 * procedural lighting classes of sim/light_class.h instead (a map named
 * class:NAME is one of them, 1024 px, unrotated).
 * quick: four materials (yellow plastic, nylon, silver, copper); slice:
 * silver (the sim suite's `accuracy-slice`: a map with a sun, where the
 * fit raises its samples; yellow plastic is bench/fit's and the sim
 * fits' material already).
 * --within: exit 1 unless every case is within the tolerances (a case
 * known to be reachable, as the sim suite's `accuracy-plateau`);
 * --check: exit 1 when a case is refused or wrong; --no-refusals: when a
 * case is refused (the slow suite's `accuracy-matrix`: no correct photo
 * may be refused).  These three write no CSV.
 * Writes bench-out/accuracy.csv; prints a line per case and a table per
 * map.  For studies: ACCURACY_ONLY=MATERIAL[,MATERIAL...] (those of the
 * list alone), ACCURACY_LOG=1 (the fits' own log on stderr: when they
 * raise their samples and why), ACCURACY_KEEP_LEAN=1 (the fit's
 * sampling lean left in its answer: fit.c, remove_lean()),
 * ACCURACY_SAMPLES=N (the
 * fit's light and lobe samples per set), ACCURACY_REF_SAMPLES=N and
 * ACCURACY_REF_SPP=N (the reference photos'), ACCURACY_CACHE=DIR (the
 * reference photos kept there and read back on the next run: reference()),
 * ACCURACY_PASSES=1 (each fit's passes and costs), ACCURACY_PROFILE=1
 * (the fit's objective along roughness, 1e-4 to 0.03, at the fit's and
 * at the truth's other parameters), ACCURACY_SPP=N (the fitter's
 * primary samples per pixel), ACCURACY_NO_FOOTPRINT=1 (the fitter's hot
 * texels on its hits alone, as before the footprint integral:
 * shade_cache.h), ACCURACY_DUMP=DIR (each clean reference photo
 * written there as MAP-MATERIAL.exr, to fit again with glint fit: the
 * scene is sim/fixtures.h's fixture_scene at 256 px),
 * ACCURACY_REF_SEED=S (the reference photo's seed, 1 unless given; the
 * bias ratio's second photo S + 1), ACCURACY_REF_MEAN=N (the photo the
 * mean of N reference renders, seeds S .. S + N - 1: 1/N of one
 * render's Monte Carlo variance; the bias ratio's noise from the first
 * two, no second photo), ACCURACY_SENSOR_SEED=S (the sensor's noise
 * draw, 1 unless given), ACCURACY_SENSOR_LEVEL=F (the whole image's
 * mean at F of the ADC range, 0.1 unless given), ACCURACY_NO_WEIGHTS=1
 * (the sensor's photos fitted without their 1/variance weights: glint's
 * default variance model), ACCURACY_PHOTOS=clean, bracket or noisy (a
 * comma-separated list: those alone; bracket: the sensor seed draws its
 * frames),
 * ACCURACY_NO_BIAS=1 (no bias ratio: no second photo), ACCURACY_SE=1 (each
 * fit's structure share, its sampling checks (fit/intervals.c,
 * more_samples()) and standard errors: reported, the noise part, the
 * sample sets' part, the systematic; the sampling lean, its standard
 * error and what was taken off the answer).
 */
#define _DEFAULT_SOURCE
#include "bench.h"
#include "sim/fixtures.h"

#include "core/clock.h"
#include "core/error.h"
#include "capture/camera/bracket.h"
#include "capture/hdr/hdr_linear.h"
#include "capture/probe/probe.h"
#include "core/log.h"
#include "fit/fit.h"
#include "fit/job.h"
#include "sim/light_class.h"
#include "sim/reference.h"

#include <errno.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *const all_mats[] = {
	"satin-paint",	  "semi-gloss-paint", "matte-paint",
	"yellow-plastic", "teflon",	      "nylon",
	"silver",	  "green-acrylic",    "aluminium-bronze",
	"copper",	  "nickel",
};
static const char *const quick_mats[] = { "yellow-plastic", "nylon", "silver",
					  "copper" };
static const char *const slice_mats[] = { "silver" };

static const char *const default_maps[] = {
	GLINT_DATA_DIR "/env/venice_sunset_1k.hdr",
	GLINT_SHARED_DATA "/probes/polyhaven_1k/quarry_01_1k.hdr",
	GLINT_SHARED_DATA "/probes/polyhaven_1k/royal_esplanade_1k.hdr",
	GLINT_SHARED_DATA "/probes/blender_studiolights/studio.exr",
	GLINT_SHARED_DATA "/probes/blender_studiolights/courtyard.exr",
	GLINT_SHARED_DATA "/probes/probulator_small/grace.hdr",
	GLINT_SHARED_DATA "/probes/probulator_small/uffizi.hdr",
	GLINT_SHARED_DATA "/probes/probulator_small/pisa.hdr",
	GLINT_SHARED_DATA "/probes/probulator_small/ennis.hdr",
	GLINT_SHARED_DATA "/probes/probulator_small/wells.hdr",
	GLINT_SHARED_DATA "/probes/campus_probe.hdr",
};

/* The sensor photo: the image's mean at this fraction of the ADC range. */
#define SENSOR_LEVEL 0.1

enum { WITHIN, FLAGGED, WRONG, REFUSED, NOUT };
/* The photos of a case: noise-free; through the sensor as glint's rig
 * takes it (bracket_photo()); one frame metered on the whole image
 * (fixture_add_noise_seed(): the mean at SENSOR_LEVEL of the ADC range),
 * which under a map whose lights are in view leaves the sphere at a
 * fraction of a per cent of the range. */
enum { CLEAN, BRACKET, NOISY, NPHOTO };
static const char *const photo_names[NPHOTO] = { "clean", "bracket", "noisy" };
static const char *const photo_what[NPHOTO] = {
	"c: noise-free", "b: bracketed on the sphere as glint's rig takes it",
	"n: one frame metered on the whole image"
};
static const char *const outcome_names[NOUT] = { "within", "flagged", "wrong",
						 "refused" };

struct map_tally {
	int n[NOUT];
	int bound;    /* of n[WITHIN]: roughness under glint's upper bound */
	double worst; /* largest error in tolerance units */
	char worst_case[96];
	double bias[64];
	int nbias;
	double ideal; /* expected within count of an ideal fitter */
	int kind_n[NPHOTO], kind_within[NPHOTO];
	int bad_weights; /* bracket photos not made, or whose weights are not
			    1/variance */
	/* Per parameter class (diffuse, specular, roughness, ior): fits
	 * with an interval, those whose interval holds the truth, those
	 * reported undetermined, and |error| / standard error. */
	int cls_n[4], cls_in[4], cls_undet[4];
	double cls_z[4][1024];
	int cls_nz[4];
};

static const char *const class_names[4] = { "diffuse", "specular", "roughness",
					    "ior" };

static int param_class(int k)
{
	return k < 3 ? 0 : k < 6 ? 1 : k == 6 ? 2 : 3;
}

/* The intervals of a fit against the truth, by parameter class. */
static void tally_intervals(struct map_tally *t, const struct glint_model *m,
			    const double *truth,
			    const struct glint_fit_result *res)
{
	for (int k = 0; k < m->nparams && k < 8; k++) {
		int c = param_class(k);
		int undet = !isfinite(res->se[k]) ||
			    res->unc.hi[k] - res->unc.lo[k] >=
				    0.5 * (m->params[k].hi - m->params[k].lo);
		if (!res->unc.n)
			continue;
		if (undet) {
			t->cls_undet[c]++;
			continue;
		}
		t->cls_n[c]++;
		t->cls_in[c] += truth[k] >= res->unc.lo[k] &&
				truth[k] <= res->unc.hi[k];
		if (res->se[k] > 0 && t->cls_nz[c] < 1024)
			t->cls_z[c][t->cls_nz[c]++] =
				fabs(res->p[k] - truth[k]) / res->se[k];
	}
}

static const char *base(const char *path)
{
	const char *s = strrchr(path, '/');
	return s ? s + 1 : path;
}

/* Reference photo of material (m, p) under map with a given seed; with
 * ACCURACY_CACHE=DIR read from DIR when an earlier run wrote it there
 * (named by map, material, seed, the reference's samples and its
 * renderer's GLINT_REFERENCE_VERSION), else
 * rendered and written there: the renders are most of a run's time, and
 * a study of the fitter needs the same photos again. */
static struct glint_image *reference(const struct glint_renderer *r,
				     const char *map, const char *material,
				     const struct glint_model *m,
				     const double *p, uint32_t seed)
{
	struct glint_image *img = NULL;
	struct glint_reference_opts ro;
	const char *dir = getenv("ACCURACY_CACHE");
	char path[1024];

	glint_reference_default_opts(&ro);
	ro.spp = getenv("ACCURACY_REF_SPP") ? atoi(getenv("ACCURACY_REF_SPP"))
					    : 64;
	ro.samples = getenv("ACCURACY_REF_SAMPLES")
			     ? atoi(getenv("ACCURACY_REF_SAMPLES"))
			     : 16;
	ro.seed = seed;
	if (dir) {
		snprintf(path, sizeof(path), "%s/%s-%s-%u-%dx%d-v%d.exr", dir,
			 base(map), material, (unsigned)seed, ro.spp,
			 ro.samples, GLINT_REFERENCE_VERSION);
		if (access(path, R_OK) == 0) {
			if (glint_image_read(path, &img) < 0)
				return NULL;
			if (img->width == r->scene.cam.width &&
			    img->height == r->scene.cam.height)
				return img;
			glint_image_free(img);
			glint_error_set(EINVAL, "%s: not %dx%d", path,
					r->scene.cam.width,
					r->scene.cam.height);
			return NULL;
		}
	}
	img = glint_image_new(r->scene.cam.width, r->scene.cam.height);
	if (img &&
	    glint_reference_render(&r->scene, r->env, m, p, &ro, img) < 0) {
		glint_image_free(img);
		img = NULL;
	}
	if (dir && mkdir(dir, 0777) < 0 && errno != EEXIST) {
		glint_error_set(errno, "%s: cannot make the cache folder", dir);
		glint_image_free(img);
		return NULL;
	}
	if (img && dir && glint_image_write(path, img, NULL) < 0) {
		glint_image_free(img);
		img = NULL;
	}
	return img;
}

/* Over the sphere's interior (2 px in from its outline): the mean of
 * a's values, or with b the rms of a - b. */
static double sphere_stat(const struct glint_renderer *r,
			  const struct glint_image *a,
			  const struct glint_image *b)
{
	const struct glint_scene *sc = &r->scene;
	double rad = sc->cam.fpx * sc->sphere_radius / -sc->sphere_centre.z - 2;
	double cx = sc->cam.cx, cy = sc->cam.cy, s = 0;
	long n = 0;

	for (int y = 0; y < a->height; y++)
		for (int x = 0; x < a->width; x++) {
			double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
			if (dx * dx + dy * dy > rad * rad)
				continue;
			const float *pa = glint_image_px(a, x, y);
			const float *pb = b ? glint_image_px(b, x, y) : NULL;
			for (int c = 0; c < 3; c++, n++)
				s += pb ? (pa[c] - pb[c]) * (pa[c] - pb[c])
					: pa[c];
		}
	return !n ? NAN : b ? sqrt(s / n) : s / n;
}

/* The photo's own Monte Carlo noise: rms(a - b) / sqrt 2 on the sphere. */
static double mc_noise(const struct glint_renderer *r,
		       const struct glint_image *a, const struct glint_image *b)
{
	return sphere_stat(r, a, b) / sqrt(2);
}

/* The mean of n reference photos, seeds seed .. seed + n - 1: a photo
 * with 1/n of one photo's Monte Carlo variance (ACCURACY_REF_MEAN=n;
 * ACCURACY_REF_SEED the first; the cache keeps each).  With n >= 2 and
 * noise, *noise is the mean's Monte Carlo noise on the sphere, from the
 * first two: rms(a - b) / sqrt(2 n). */
static struct glint_image *reference_mean(const struct glint_renderer *r,
					  const char *map, const char *material,
					  const struct glint_model *m,
					  const double *p, uint32_t seed, int n,
					  double *noise)
{
	struct glint_image *sum = reference(r, map, material, m, p, seed);

	for (int k = 1; sum && k < n; k++) {
		struct glint_image *img =
			reference(r, map, material, m, p, seed + (uint32_t)k);
		if (!img) {
			glint_image_free(sum);
			return NULL;
		}
		if (k == 1 && noise)
			*noise = sphere_stat(r, sum, img) / sqrt(2.0 * n);
		for (size_t i = 0; i < (size_t)sum->width * sum->height * 3;
		     i++)
			sum->data[i] += img->data[i];
		glint_image_free(img);
	}
	if (!sum)
		return NULL;
	for (size_t i = 0; i < (size_t)sum->width * sum->height * 3; i++)
		sum->data[i] /= (float)n;
	return sum;
}

/* Where the sensor photo's exposure puts the sphere: its mean as a
 * fraction of the ADC range, fixture_add_noise() putting the whole image's
 * mean at `level` (a map whose bright lights are in view leaves the
 * sphere far below it). */
static double sphere_level(const struct glint_renderer *r,
			   const struct glint_image *a, double level)
{
	double mean = 0;
	for (int i = 0; i < a->width * a->height * 3; i++)
		mean += a->data[i];
	mean /= a->width * a->height * 3.0;
	return level * sphere_stat(r, a, NULL) / mean;
}

/*
 * A camera that photographs the bench's photo: a backend of
 * capture/camera/camera.h local to this program, so that glint's own
 * bracket planner (glint_bracket_capture()) chooses the exposures the
 * matrix measures.  Its frames go through the sensor model (sim/sensor.h,
 * each frame its own draw) with a pixel's three channels as three
 * photosites of a mono frame (width 3 w); any exposure from 1 us to an
 * hour, gain 1, no latency.  glint_camera_open() passes a device string
 * only: the photo and the draw's seed are this program's (photo_src).
 */
static struct {
	const struct glint_image *photo;
	uint64_t seed;
} photo_src;

struct photo_cam {
	const struct glint_image *radiance;
	struct glint_sensor s;
	struct glint_image *dn;
	const struct glint_clock *clock;
	uint64_t seed;
	int n;
	double exposure_s;
};

static int photo_open(const char *device, const struct glint_clock *clock,
		      void **priv)
{
	struct photo_cam *c = calloc(1, sizeof(*c));

	(void)device;
	*priv = NULL;
	if (!c || !photo_src.photo ||
	    !(c->dn = glint_image_new(photo_src.photo->width,
				      photo_src.photo->height))) {
		free(c);
		return glint_error_set(ENOMEM, "photo camera: out of memory");
	}
	c->radiance = photo_src.photo;
	c->seed = photo_src.seed;
	c->clock = clock;
	glint_sensor_default(&c->s);
	c->exposure_s = c->s.exposure_s;
	*priv = c;
	return 0;
}

static void photo_close(void *priv)
{
	struct photo_cam *c = priv;

	if (c)
		glint_image_free(c->dn);
	free(c);
}

static int photo_describe(void *priv, struct glint_camera_info *in)
{
	const struct photo_cam *c = priv;

	memset(in, 0, sizeof(*in));
	snprintf(in->backend, sizeof(in->backend), "bench-photo");
	snprintf(in->name, sizeof(in->name), "the accuracy matrix's photo");
	in->width = 3 * c->radiance->width;
	in->height = c->radiance->height;
	in->nformats = 1;
	snprintf(in->formats[0], sizeof(in->formats[0]), "MONO16");
	in->bit_depth = c->s.bits;
	in->manual_exposure = 1;
	in->exposure_min_s = 1e-6;
	in->exposure_max_s = 3600;
	in->gain_min = in->gain_max = 1;
	in->frame_period_min_s = 1.0 / 30;
	return 0;
}

static int photo_configure(void *priv)
{
	(void)priv;
	return 0;
}

static int photo_set_exposure(void *priv, double *exposure_s, double *gain)
{
	struct photo_cam *c = priv;

	c->exposure_s = *exposure_s;
	*gain = 1;
	return 0;
}

static int photo_grab(void *priv, struct glint_frame *f)
{
	struct photo_cam *c = priv;
	int w = c->radiance->width, h = c->radiance->height, ret;
	size_t n = (size_t)3 * w * h;

	c->s.exposure_s = c->exposure_s;
	c->s.seed = c->seed * 64 + (uint64_t)c->n++;
	if ((ret = glint_sensor_capture(&c->s, c->radiance, c->dn)) < 0)
		return ret;
	memset(f, 0, sizeof(*f));
	if (!(f->data = malloc(n * sizeof(*f->data))))
		return glint_error_set(ENOMEM, "photo camera: out of memory");
	for (size_t i = 0; i < n; i++)
		f->data[i] = (uint16_t)c->dn->data[i];
	f->width = 3 * w;
	f->height = h;
	snprintf(f->format, sizeof(f->format), "MONO16");
	f->channels = 1;
	f->bit_depth = c->s.bits;
	f->linear = 1;
	f->exposure_s = c->exposure_s;
	f->gain = 1;
	f->black_level = c->s.black_level;
	double t = glint_clock_now(c->clock);
	glint_clock_sleep(c->clock, fmax(c->exposure_s, 1.0 / 30));
	f->t_start = t;
	f->t_end = t + c->exposure_s;
	f->sequence = (uint64_t)c->n;
	return 0;
}

static const struct glint_camera_ops photo_cam_ops = {
	.name = "bench-photo",
	.open = photo_open,
	.close = photo_close,
	.describe = photo_describe,
	.configure = photo_configure,
	.set_exposure = photo_set_exposure,
	.grab = photo_grab,
};

/*
 * The photo as glint's rig takes it: a bracket of the photo camera
 * (above) planned by glint's own planner (capture/camera/bracket.c, its
 * default options) on the sphere's region (its bounding square, 2 px of
 * margin: the rig's "sample" ROI), merged by glint's raw merge
 * (capture/hdr/hdr_linear.c: inverse-variance weights, the variance at
 * the merged value, a sample clipped in one frame left out of it).  A
 * bracket the planner does not call whole is an error.  photo becomes
 * the merged radiance, *weight its 1/variance (0 where clipped in every
 * frame); *nframes the bracket's length, *zrms the rms of the merged
 * values' errors over the region in their own standard deviations (1
 * when the weights are honest).
 */
static int bracket_photo(const struct glint_renderer *r,
			 struct glint_image *photo, struct glint_image **weight,
			 uint64_t seed, int *nframes, double *zrms)
{
	static const struct glint_camera_ops *const backends[] = {
		&photo_cam_ops, NULL
	};
	const struct glint_scene *sc = &r->scene;
	double rad = sc->cam.fpx * sc->sphere_radius / -sc->sphere_centre.z + 2;
	int w = photo->width, h = photo->height, ret = 0;
	int x0 = (int)fmax(0, floor(sc->cam.cx - rad));
	int x1 = (int)fmin(w, ceil(sc->cam.cx + rad));
	int y0 = (int)fmax(0, floor(sc->cam.cy - rad));
	int y1 = (int)fmin(h, ceil(sc->cam.cy + rad));
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam = NULL;
	struct glint_bracket br;
	struct glint_bracket_opts bo;
	struct glint_noise_model nm;
	struct glint_raw_hdr hdr = { 0 };
	struct glint_sensor s;

	*weight = NULL;
	*nframes = 0;
	memset(&br, 0, sizeof(br));
	if (x1 <= x0 || y1 <= y0)
		return glint_error_set(EINVAL, "bracket: the sphere is not in "
					       "the frame");
	glint_sensor_default(&s);
	glint_bracket_default_opts(&bo);
	glint_noise_default(&nm);
	/* The camera's time is simulated: no cap on it. */
	bo.max_time_s = INFINITY;
	photo_src.photo = photo;
	photo_src.seed = seed;
	glint_camera_backends_set(backends);
	struct glint_roi roi = { 3 * x0, y0, 3 * x1, y1 };
	ret = glint_camera_open("bench-photo", NULL, &clk, &cam);
	if (!ret)
		ret = glint_bracket_capture(cam, &roi, &bo, &clk, &br);
	if (!ret)
		ret = glint_bracket_verdict(&br, &bo);
	if (!ret)
		ret = glint_hdr_merge_raw(br.frames, br.n, &nm, &hdr, NULL);
	if (!ret && !(*weight = glint_image_new(w, h)))
		ret = glint_error_set(ENOMEM, "bracket: out of memory");
	if (ret < 0)
		goto out;
	/* x = (DN - black) / t in DN per second = gain k L */
	double scale = 1 / (s.gain * s.k), zz = 0;
	long nz = 0;
	for (size_t i = 0; i < (size_t)3 * w * h; i++) {
		double x = hdr.x[i] * scale, var = hdr.var[i] * scale * scale;
		size_t px = i / 3;
		int in = (int)(px % (size_t)w) >= x0 &&
			 (int)(px % (size_t)w) < x1 &&
			 (int)(px / (size_t)w) >= y0 &&
			 (int)(px / (size_t)w) < y1;
		(*weight)->data[i] =
			hdr.valid[i] && var > 0 ? (float)(1 / var) : 0.0f;
		if (in && (*weight)->data[i] > 0) {
			zz += (x - photo->data[i]) * (x - photo->data[i]) / var;
			nz++;
		}
		photo->data[i] = (float)x;
	}
	*nframes = br.n;
	*zrms = nz ? sqrt(zz / nz) : NAN;
out:
	glint_bracket_release(&br);
	glint_camera_close(cam);
	photo_src.photo = NULL;
	glint_raw_hdr_release(&hdr);
	if (ret < 0) {
		glint_image_free(*weight);
		*weight = NULL;
	}
	return ret;
}

/* The chance that an ideal fitter (unbiased, at the photo's noise) lands
 * within every tolerance: the fraction of draws from N(truth, C) inside
 * the tolerance box, C the noise part of the fit's covariance (the
 * cluster-robust one; not the fitter's own sampling, the systematic term
 * or the model error, which are the fitter's, not the photo's).  A
 * parameter the photo cannot see gives 0; roughness is left out where
 * glint reports an upper bound that holds the truth (judge() counts such
 * a fit within on the other parameters).  What the photo's noise allows
 * any fitter: the within fraction such a fitter reaches on average.
 * (For a clean photo the noise is the reference render's Monte Carlo
 * noise, with the fast render's bias, if any, counted as noise too.) */
static double ideal_within(const struct glint_model *m, const double *truth,
			   const struct glint_fit_result *res)
{
	int n = m->nparams, box[GLINT_MAX_PARAMS], nb = 0;
	double tol[GLINT_MAX_PARAMS];

	if (res->unc.n != n)
		return NAN;
	for (int k = 0; k < n; k++) {
		if (k == 6 && truth[6] <= glint_fit_roughness_bound(res))
			continue;
		if (!isfinite(res->unc.se[k]))
			return 0;
		tol[nb] = k < 6 ? 0.01 : k == 6 ? 0.05 * truth[6] : 0.05;
		box[nb++] = k;
	}
	gsl_matrix *c = gsl_matrix_alloc(nb, nb), *v = gsl_matrix_alloc(nb, nb);
	gsl_vector *l = gsl_vector_alloc(nb);
	gsl_eigen_symmv_workspace *w = gsl_eigen_symmv_alloc(nb);
	gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
	/* As fit/optim/uncertainty.c: the cluster-robust part, never
	 * below the textbook one. */
	double sc[GLINT_MAX_PARAMS];
	for (int i = 0; i < nb; i++) {
		double b = res->unc.cov_blocks[box[i] * n + box[i]],
		       t = res->unc.cov_textbook[box[i] * n + box[i]];
		sc[i] = b > 0 && t > b ? sqrt(t / b) : 1;
	}
	for (int i = 0; i < nb; i++)
		for (int j = 0; j < nb; j++)
			gsl_matrix_set(c, i, j,
				       sc[i] * sc[j] *
					       res->unc.cov_blocks[box[i] * n +
								   box[j]]);
	gsl_eigen_symmv(c, l, v, w);
	enum { DRAWS = 20000 };
	int in = 0;
	for (int d = 0; d < DRAWS; d++) {
		double z[GLINT_MAX_PARAMS];
		for (int j = 0; j < nb; j++)
			z[j] = gsl_ran_ugaussian(rng) *
			       sqrt(fmax(0, gsl_vector_get(l, j)));
		int ok = 1;
		for (int i = 0; i < nb && ok; i++) {
			double x = 0;
			for (int j = 0; j < nb; j++)
				x += gsl_matrix_get(v, i, j) * z[j];
			ok = fabs(x) <= tol[i];
		}
		in += ok;
	}
	gsl_rng_free(rng);
	gsl_eigen_symmv_free(w);
	gsl_vector_free(l);
	gsl_matrix_free(v);
	gsl_matrix_free(c);
	return (double)in / DRAWS;
}

/* Outcome of a fit against the truth; why: for a wrong one, the
 * parameter whose interval misses. */
static int judge(const struct glint_model *m, const double *truth,
		 const struct glint_fit_result *res, double *err, int *bound,
		 char *why, size_t nwhy)
{
	*err = fixture_tolerance_error(res->p, truth);
	*bound = 0;
	if (*err <= 1)
		return WITHIN;
	/* Roughness below the pixel footprint: glint reports an upper
	 * bound, not a value (near-mirrors within tolerance on albedos,
	 * specular and ior, roughness under its bound). */
	double p[GLINT_MAX_PARAMS];
	memcpy(p, res->p, sizeof(p));
	p[6] = truth[6];
	if (truth[6] <= glint_fit_roughness_bound(res) &&
	    fixture_tolerance_error(p, truth) <= 1) {
		*bound = 1;
		*err = fixture_tolerance_error(p, truth);
		return WITHIN;
	}
	for (int k = 0; k < m->nparams; k++) {
		double tol = k < 6 ? 0.01 : k == 6 ? 0.05 * truth[6] : 0.05;
		if (fabs(res->p[k] - truth[k]) <= tol)
			continue;
		int undet = !isfinite(res->se[k]) ||
			    res->unc.hi[k] - res->unc.lo[k] >=
				    0.5 * (m->params[k].hi - m->params[k].lo);
		int covered = res->unc.n && truth[k] >= res->unc.lo[k] &&
			      truth[k] <= res->unc.hi[k];
		if (!undet && !covered) {
			snprintf(why, nwhy, "  (%s %.4f outside %.4f .. %.4f)",
				 m->params[k].name, truth[k], res->unc.lo[k],
				 res->unc.hi[k]);
			return WRONG;
		}
	}
	return FLAGGED;
}

/* The fit's objective (weighted cost) at parameters p with roughness
 * set to rough: ACCURACY_PROFILE's points; NAN where it fails. */
static double cost_at(struct glint_renderer *r, const struct glint_model *m,
		      const struct glint_image *photo,
		      const struct glint_image *w,
		      const struct glint_fit_opts *o, const double *p,
		      double rough)
{
	double q[GLINT_MAX_PARAMS];
	struct glint_fit_result e;

	memcpy(q, p, sizeof(q));
	q[6] = rough;
	return glint_fit_evaluate(r, m, photo, w, o, q, &e) == 0 ? e.wcost
								 : NAN;
}

/* Whether material is in the comma-separated list (NULL: all). */
static int selected(const char *list, const char *material)
{
	size_t n = strlen(material);

	if (!list)
		return 1;
	for (const char *s = list; *s;) {
		size_t k = strcspn(s, ",");
		if (k == n && !strncmp(s, material, n))
			return 1;
		s += k + (s[k] == ',');
	}
	return 0;
}

/* The map's index in the run (the chart's x position: write_chart()). */
static int map_index;

/* with_bias 0: no second reference photo, and no bias ratio (the tests,
 * which judge the fits alone: one render per case less). */
static void one_map(const char *map, const char *const *mats, int nmats,
		    int with_bias, FILE *csv, struct map_tally *t)
{
	struct glint_scene sc;
	struct glint_renderer r;

	struct glint_envmap *env = NULL;

	uint32_t seed0 = getenv("ACCURACY_REF_SEED")
				 ? (uint32_t)atoi(getenv("ACCURACY_REF_SEED"))
				 : 1;
	int nref = getenv("ACCURACY_REF_MEAN")
			   ? atoi(getenv("ACCURACY_REF_MEAN"))
			   : 1;

	uint64_t sensor_seed =
		getenv("ACCURACY_SENSOR_SEED")
			? (uint64_t)atoll(getenv("ACCURACY_SENSOR_SEED"))
			: 1;

	double level = getenv("ACCURACY_SENSOR_LEVEL")
			       ? atof(getenv("ACCURACY_SENSOR_LEVEL"))
			       : SENSOR_LEVEL;

	if (nref < 1)
		nref = 1;
	if (getenv("ACCURACY_NO_BIAS"))
		with_bias = 0;
	memset(t, 0, sizeof(*t));
	fixture_scene(&sc, 256, map);
	if (getenv("ACCURACY_SPP"))
		sc.spp = atoi(getenv("ACCURACY_SPP"));
	if (fixture_load_map(map, &sc, &env) < 0 ||
	    glint_renderer_init_env(&r, &sc, env, 0, NULL) < 0) {
		fprintf(stderr, "%s: %s\n", map, glint_error_msg());
		return;
	}
	for (int i = 0; i < nmats; i++) {
		const struct glint_model *m;
		double truth[GLINT_MAX_PARAMS];
		if (!selected(getenv("ACCURACY_ONLY"), mats[i]))
			continue;
		if (glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
					mats[i], &m, truth) < 0)
			continue;
		double noise = NAN;
		struct glint_image *a = reference_mean(
			&r, map, mats[i], m, truth, seed0, nref, &noise);
		struct glint_image *b = with_bias && nref == 1
						? reference(&r, map, mats[i], m,
							    truth, seed0 + 1)
						: NULL;
		if (!a || (with_bias && nref == 1 && !b)) {
			fprintf(stderr, "%s\n", glint_error_msg());
			glint_image_free(a);
			glint_image_free(b);
			continue;
		}
		if (b)
			noise = mc_noise(&r, a, b);
		if (!with_bias)
			noise = NAN;
		if (getenv("ACCURACY_DUMP")) {
			char path[1024];
			snprintf(path, sizeof(path), "%s/%s-%s.exr",
				 getenv("ACCURACY_DUMP"), base(map), mats[i]);
			if (glint_image_write(path, a, NULL) < 0)
				fprintf(stderr, "%s\n", glint_error_msg());
		}
		struct glint_fit_opts o;
		struct glint_fit_result ev;
		glint_fit_default_opts(&o);
		o.mc_draws = 0;
		if (getenv("ACCURACY_SAMPLES"))
			o.light_samples = o.lobe_samples =
				atoi(getenv("ACCURACY_SAMPLES"));
		o.no_footprint = getenv("ACCURACY_NO_FOOTPRINT") != NULL;
		double bias = NAN;
		if (isfinite(noise) &&
		    glint_fit_evaluate(&r, m, a, NULL, &o, truth, &ev) == 0)
			bias = ev.rmse / noise;
		if (isfinite(noise) && t->nbias < 64)
			t->bias[t->nbias++] = bias;
		for (int lv = 0; lv < NPHOTO; lv++) {
			struct glint_image *photo = glint_image_dup(a);
			struct glint_image *w = NULL;
			struct glint_fit_result res;
			double err = INFINITY, t0 = glint_clock_monotonic();
			int out = REFUSED, bound = 0, nframes = 0;
			double zrms = NAN;
			char why[128] = "";
			if (!selected(getenv("ACCURACY_PHOTOS"),
				      photo_names[lv]))
				goto next;
			if (lv == NOISY &&
			    fixture_add_noise_seed(photo, &w, level,
						   sensor_seed) < 0)
				goto next;
			if (lv == BRACKET &&
			    bracket_photo(&r, photo, &w, sensor_seed, &nframes,
					  &zrms) < 0) {
				fprintf(stderr, "%s\n", glint_error_msg());
				t->bad_weights++; /* a case that did not run */
				goto next;
			}
			if (lv != CLEAN && getenv("ACCURACY_NO_WEIGHTS")) {
				glint_image_free(w);
				w = NULL;
			}
			glint_fit_default_opts(&o);
			if (getenv("ACCURACY_SAMPLES"))
				o.light_samples = o.lobe_samples =
					atoi(getenv("ACCURACY_SAMPLES"));
			if (getenv("ACCURACY_MAX_SAMPLES"))
				o.max_samples =
					atoi(getenv("ACCURACY_MAX_SAMPLES"));
			o.no_footprint =
				getenv("ACCURACY_NO_FOOTPRINT") != NULL;
			o.keep_lean = getenv("ACCURACY_KEEP_LEAN") != NULL;
			struct glint_fit_verdict v = { 0 };
			if (glint_fit(&r, m, photo, w, &o, &res) == 0 &&
			    glint_fit_judge(&res, 0, &v))
				out = judge(m, truth, &res, &err, &bound, why,
					    sizeof(why));
			t->n[out]++;
			if (out != REFUSED)
				tally_intervals(t, m, truth, &res);
			t->kind_n[lv]++;
			t->kind_within[lv] += out == WITHIN;
			t->bound += bound;
			double ideal = out == REFUSED
					       ? NAN
					       : ideal_within(m, truth, &res);
			if (isfinite(ideal))
				t->ideal += ideal;
			if (err > t->worst || out == REFUSED) {
				t->worst = out == REFUSED ? INFINITY : err;
				snprintf(t->worst_case, sizeof(t->worst_case),
					 "%s %s", mats[i], photo_names[lv]);
			}
			int smp = out == REFUSED ? 0 : res.light_samples;
			/* The truth on the fit's own objective (weights at
			 * the fit's prediction): above 1, the fit found a
			 * lower cost than the truth's (the model or the photo
			 * biases it); below, it stopped short of it. */
			double ratio = NAN;
			struct glint_fit_result at_truth;
			o.weights_at = res.p;
			if (out != REFUSED) {
				o.light_samples = res.light_samples;
				o.lobe_samples = res.lobe_samples;
			}
			if (out != REFUSED &&
			    glint_fit_evaluate(&r, m, photo, w, &o, truth,
					       &at_truth) == 0)
				ratio = at_truth.wcost / res.wcost;
			o.weights_at = NULL;
			printf("%-26s %-17s %-7s bias %5.2f  %-8s err %6.2f "
			       "tol  rel.rmse %.3f  truth/fit cost %5.2f  "
			       "ideal "
			       "%.2f  %2d smp %5.1f s",
			       base(map), mats[i], photo_names[lv], bias,
			       bound ? "within<" : outcome_names[out], err,
			       out == REFUSED ? NAN : res.rel_rmse, ratio,
			       ideal, smp, glint_clock_monotonic() - t0);
			if (getenv("ACCURACY_PROFILE") && out != REFUSED)
				for (int g = 0; g < 13; g++) {
					double rough =
						1e-4 * pow(300, g / 12.0);
					double c1 = cost_at(&r, m, photo, w, &o,
							    res.p, rough);
					double c2 = cost_at(&r, m, photo, w, &o,
							    truth, rough);
					printf("\n  rough %.5f  at fit %.5g  "
					       "at truth %.5g",
					       rough, c1, c2);
				}
			if (getenv("ACCURACY_PASSES"))
				for (int k = 0; k < res.npasses; k++)
					printf("\n    %-16s %6d px %3d it cost "
					       "%.6g -> %.6g",
					       res.passes[k].name,
					       res.passes[k].pixels,
					       res.passes[k].iterations,
					       res.passes[k].cost0,
					       res.passes[k].cost);
			if (out == REFUSED)
				printf("  (%s)", v.verdict[0]
							 ? v.verdict
							 : glint_error_msg());
			else
				for (int k = 0; k < m->nparams; k++)
					printf(" %s %.4f/%.4f",
					       m->params[k].name, res.p[k],
					       truth[k]);
			/* ACCURACY_SE=1: each parameter's reported standard
			 * error and its parts: the photo's noise (the blocks'
			 * sandwich, raised to the textbook or the regions'
			 * where larger: what the interval uses), the sample
			 * sets' and the systematic one; what a study over
			 * photo seeds compares with the answers' spread. */
			if (getenv("ACCURACY_SE") && out != REFUSED)
				printf("\n    structure's share %.4f; the "
				       "fit's "
				       "sampling against the noise %.3f per "
				       "parameter, %.3f per value",
				       res.misfit_share, res.mc_over_noise,
				       res.model_noise);
			if (getenv("ACCURACY_SE") && out != REFUSED)
				for (int k = 0; k < res.unc.n; k++) {
					const struct glint_uncertainty *u =
						&res.unc;
					double mc = u->cov_mc[k * u->n + k],
					       sys = u->sys[k] * u->sys[k];
					printf("\n    %-11s se %.5f  noise %.5f"
					       "  sets %.5f  sys %.5f  lean "
					       "%+.5f +- %.5f (removed %+.5f)",
					       m->params[k].name, u->se[k],
					       sqrt(fmax(0,
							 u->se[k] * u->se[k] -
								 mc - sys)),
					       sqrt(mc), u->sys[k], u->lean[k],
					       u->lean_se[k],
					       res.lean_removed[k]);
				}
			if (lv == NOISY)
				printf("  sphere at %.2f %% of the ADC range",
				       100 * sphere_level(&r, a, level));
			if (lv == BRACKET) {
				printf("  %d frames, their merge's errors "
				       "%.3f of its sd",
				       nframes, zrms);
				if (!(fabs(zrms - 1) < 0.1))
					t->bad_weights++;
			}
			printf("%s\n", why);
			fflush(stdout);
			if (csv)
				fprintf(csv,
					"%s,%s,%s,%.4f,%s,%.4f,%.5f,%d,%.3f,"
					"%.3f\n",
					base(map), mats[i], photo_names[lv],
					bias,
					bound ? "within-bound"
					      : outcome_names[out],
					err,
					out == REFUSED ? NAN : res.rel_rmse,
					smp, ideal,
					map_index + 0.1 +
						0.8 * (i + 0.5) / nmats);
		next:
			glint_image_free(photo);
			glint_image_free(w);
		}
		glint_image_free(a);
		glint_image_free(b);
	}
	glint_renderer_release(&r);
}

/* bench-out/accuracy.png: each case's worst error in tolerance units
 * (log scale; at or under 1 meets every tolerance) by map, the materials
 * side by side within a map's column, one colour per kind of photo. */
static void write_chart(const char *const *maps, int nmaps)
{
	FILE *gp = fopen("bench-out/accuracy.gp", "w");
	if (!gp)
		return;
	fprintf(gp,
		"set terminal pngcairo noenhanced size 1100,460\n"
		"set output 'bench-out/accuracy.png'\n"
		"set datafile separator ','\nset key outside right top\n"
		"set logscale y\nset yrange [0.01:100]\n"
		"set ylabel 'worst error (tolerance units)'\n"
		"set title 'glint fits of reference photos: each "
		"material under each map'\n"
		"set xrange [0:%d]\nset xtics rotate by -30 (",
		nmaps);
	for (int i = 0; i < nmaps; i++)
		fprintf(gp, "%s'%s' %.1f", i ? ", " : "", base(maps[i]),
			i + 0.5);
	fprintf(gp, ")\nset grid ytics\n"
		    "k(s, want) = s eq want ? 1 : NaN\nplot ");
	for (int k = 0; k < NPHOTO; k++)
		fprintf(gp,
			"'bench-out/accuracy.csv' skip 1 using 10:($6 * "
			"k(strcol(3), '%s')) with points pt %d ps 1.2 "
			"title '%s', ",
			photo_names[k], 7 - 2 * k, photo_names[k]);
	fprintf(gp, "1 with lines dt 2 lc 'black' title 'tolerance'\n");
	fclose(gp);
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/accuracy.gp") == 0)
		printf("plot: bench-out/accuracy.png\n");
}

int main(int argc, char **argv)
{
	static const char usage[] = "bench/accuracy [quick|slice] [classes] "
				    "[--check|--no-refusals|--within] [MAP...]";
	bench_help(argc, argv, usage);
	const char *const *mats = all_mats;
	int nmats = 11, check = 0, no_refusals = 0, within = 0, a = 1;
	const char *const *maps = default_maps;
	int nmaps = (int)(sizeof(default_maps) / sizeof(*default_maps));
	static struct map_tally tally[32];
	static const char *class_maps[8];

	for (; a < argc; a++) {
		if (!strcmp(argv[a], "quick"))
			mats = quick_mats, nmats = 4;
		else if (!strcmp(argv[a], "slice"))
			mats = slice_mats, nmats = 1;
		else if (!strcmp(argv[a], "classes")) {
			static char names[8][32];
			for (nmaps = 0; glint_sim_light_classes[nmaps];
			     nmaps++) {
				snprintf(names[nmaps], sizeof(names[nmaps]),
					 "class:%s",
					 glint_sim_light_classes[nmaps]);
				class_maps[nmaps] = names[nmaps];
			}
			maps = class_maps;
		} else if (!strcmp(argv[a], "--check"))
			check = 1;
		else if (!strcmp(argv[a], "--within"))
			within = 1;
		else if (!strcmp(argv[a], "--no-refusals"))
			no_refusals = 1;
		else
			break;
	}
	if (argc > a && argv[a][0] == '-')
		bench_refuse(argv[a], usage);
	if (argc > a) {
		maps = (const char *const *)argv + a;
		nmaps = argc - a < 32 ? argc - a : 32;
	}
	for (int i = 0; i < nmaps; i++) {
		struct stat st;
		if (strncmp(maps[i], "class:", 6) && stat(maps[i], &st) < 0) {
			printf("%s: absent; skipped\n", maps[i]);
			return 77;
		}
	}
	if (!getenv("ACCURACY_LOG"))
		glint_log_set_mode(GLINT_LOG_QUIET);
	FILE *csv = NULL;
	if (!check && !no_refusals && !within) {
		mkdir("bench-out", 0777);
		csv = fopen("bench-out/accuracy.csv", "w");
		if (!csv) {
			perror("bench-out/accuracy.csv");
			return 1;
		}
		fprintf(csv, "map,material,noise,bias_ratio,outcome,error_tol,"
			     "relative_rmse,light_samples,ideal_within,x\n");
	}
	for (int i = 0; i < nmaps; i++) {
		map_index = i;
		one_map(maps[i], mats, nmats, !check && !within, csv,
			&tally[i]);
	}
	if (csv) {
		fclose(csv);
		write_chart(maps, nmaps);
	}

	printf("\n%-26s %6s %7s %7s %6s %7s %5s %7s %11s %17s  %s\n", "map",
	       "cases", "within", "(bound)", "ideal", "flagged", "wrong",
	       "refused", "bias median", "within: c / b / n",
	       "worst case (tolerance units)");
	int tot[NOUT] = { 0 }, tot_bound = 0;
	double tot_ideal = 0;
	for (int i = 0; i < nmaps; i++) {
		struct map_tally *t = &tally[i];
		int n = 0;
		for (int k = 0; k < NOUT; k++) {
			n += t->n[k];
			tot[k] += t->n[k];
		}
		double med = t->nbias ? bench_median(t->bias, t->nbias) : NAN;
		tot_bound += t->bound;
		tot_ideal += t->ideal;
		char kinds[64];
		snprintf(kinds, sizeof(kinds), "%d/%d %d/%d %d/%d",
			 t->kind_within[CLEAN], t->kind_n[CLEAN],
			 t->kind_within[BRACKET], t->kind_n[BRACKET],
			 t->kind_within[NOISY], t->kind_n[NOISY]);
		printf("%-26s %6d %7d %7d %6.1f %7d %5d %7d %11.2f %17s  %s "
		       "(%.1f)\n",
		       base(maps[i]), n, t->n[WITHIN], t->bound, t->ideal,
		       t->n[FLAGGED], t->n[WRONG], t->n[REFUSED], med, kinds,
		       t->worst_case, t->worst);
	}
	printf("\nintervals (95 %%) by parameter class: coverage of the truth, "
	       "median |error| / standard error (an honest interval: about "
	       "0.67), undetermined\n");
	printf("%-26s", "map");
	for (int c = 0; c < 4; c++)
		printf(" %26s", class_names[c]);
	printf("\n");
	struct map_tally all_cls = { 0 };
	for (int i = 0; i <= nmaps; i++) {
		struct map_tally *t = i < nmaps ? &tally[i] : &all_cls;
		printf("%-26s", i < nmaps ? base(maps[i]) : "all");
		for (int c = 0; c < 4; c++) {
			char cell[40];
			snprintf(cell, sizeof(cell),
				 "%3d/%-3d %5.1f %% %4.2f %2d", t->cls_in[c],
				 t->cls_n[c],
				 t->cls_n[c]
					 ? 100.0 * t->cls_in[c] / t->cls_n[c]
					 : NAN,
				 t->cls_nz[c] ? bench_median(t->cls_z[c],
							     t->cls_nz[c])
					      : NAN,
				 t->cls_undet[c]);
			printf(" %26s", cell);
			if (i == nmaps)
				continue;
			all_cls.cls_n[c] += t->cls_n[c];
			all_cls.cls_in[c] += t->cls_in[c];
			all_cls.cls_undet[c] += t->cls_undet[c];
			for (int z = 0;
			     z < t->cls_nz[c] && all_cls.cls_nz[c] < 1024; z++)
				all_cls.cls_z[c][all_cls.cls_nz[c]++] =
					t->cls_z[c][z];
		}
		printf("\n");
	}
	int all = tot[0] + tot[1] + tot[2] + tot[3];
	for (int k = 0; k < NPHOTO; k++) {
		int n = 0, in = 0;
		for (int i = 0; i < nmaps; i++) {
			n += tally[i].kind_n[k];
			in += tally[i].kind_within[k];
		}
		if (n)
			printf("%s photos (%s): within %d of %d\n",
			       photo_names[k], photo_what[k], in, n);
	}
	printf("all: %d cases, %.1f %% within tolerance (%d of them with "
	       "roughness under glint's upper bound), %.1f %% flagged by "
	       "glint, %d wrong, %d refused; an ideal fitter at the photos' "
	       "noise: %.1f %% within; peak memory %.0f MiB\n",
	       all, all ? 100.0 * tot[WITHIN] / all : 0, tot_bound,
	       all ? 100.0 * tot[FLAGGED] / all : 0, tot[WRONG], tot[REFUSED],
	       all ? 100.0 * tot_ideal / all : 0, bench_peak_mib());
	if ((check || no_refusals) && tot[REFUSED]) {
		printf("FAIL: %d correct photos refused\n", tot[REFUSED]);
		return 1;
	}
	int bad = 0;
	for (int i = 0; i < nmaps; i++)
		bad += tally[i].bad_weights;
	if (check && bad) {
		printf("FAIL: %d bracketed photos not made or with errors not "
		       "at their merge's standard deviations (rms outside "
		       "0.9 .. 1.1)\n",
		       bad);
		return 1;
	}
	if (within && tot[WITHIN] < all) {
		printf("FAIL: %d of %d cases outside the tolerances\n",
		       all - tot[WITHIN], all);
		return 1;
	}
	if (check && tot[WRONG]) {
		printf("FAIL: %d fits outside the tolerances with intervals "
		       "that miss the truth\n",
		       tot[WRONG]);
		return 1;
	}
	return all ? 0 : 1;
}
