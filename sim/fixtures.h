/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_FIXTURES_H
#define GLINT_SIM_FIXTURES_H

/*
 * The simulated captures the fitting benchmarks and tests share: the 512 px
 * scene (a 10 cm sphere 180 / 512 of the width in radius under the Venice map),
 * its reference photos (cached in bench-out/), box-averaged lower
 * resolutions, and one noisy exposure of the sensor model.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: called from one test thread.  Who
 * frees: images with glint_image_free(), renderers with
 * glint_renderer_release().
 */

#include "core/error.h"
#include "fit/render/render.h"
#include "capture/probe/probe.h"
#include "fit/scene/envmap.h"
#include "sim/light_class.h"
#include "sim/reference.h"
#include "sim/sensor.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A w x w photo, the sphere 180 / 512 of the width in radius; env NULL:
 * the Venice map; a 100 mm lens at f_number (0: a pinhole) focused on the
 * sphere's front. */
static inline void fixture_scene_lens(struct glint_scene *s, int w,
				      const char *env, double fnum)
{
	glint_scene_defaults(s);
	double fpx = 1422.2 * w / 512, dist = 0.05 * 1422.2 / 180;
	glint_pinhole_init(&s->cam, w, w, fpx * 0.036 / w, 0.036 / w, fnum,
			   dist - 0.05, v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
	s->sphere_radius = 0.05;
	s->sphere_centre = v3(0, 0, -0.05 * 1422.2 / 180);
	snprintf(s->env_path, sizeof(s->env_path), "%s",
		 env ? env : GLINT_DATA_DIR "/env/venice_sunset_1k.hdr");
	s->env_rotation[1] = -114;
	s->env_scale = 1;
}

/* A w x w/2 lat-long map: a disc of radius_deg about d whose irradiance at
 * normal incidence is pi (a Lambertian sphere of albedo a then shows
 * a n.l), over a uniform sky of radiance `sky`. */
static inline struct glint_image *
fixture_disc_map(struct vec3 d, int w, double radius_deg, double sky)
{
	const int h = w / 2;
	const double cosr = cos(radius_deg * M_PI / 180);
	struct glint_image *img = glint_image_new(w, h);
	double solid = 0;

	if (!img)
		return NULL;
	for (int pass = 0; pass < 2; pass++)
		for (int j = 0; j < h; j++)
			for (int i = 0; i < w; i++) {
				struct vec3 t = glint_latlong_uv_to_dir(
					(i + 0.5) / w, (j + 0.5) / h);
				float *px = img->data + ((size_t)j * w + i) * 3;
				int in = v3_dot(t, d) >= cosr;
				if (pass == 0 && in)
					solid += (2 * M_PI / w) * (M_PI / h) *
						 sin((j + 0.5) * M_PI / h) *
						 v3_dot(t, d);
				if (pass == 1)
					px[0] = px[1] = px[2] =
						(float)(in ? M_PI / solid
							   : sky);
			}
	return img;
}

static inline void fixture_scene(struct glint_scene *s, int w, const char *env)
{
	fixture_scene_lens(s, w, env, 0);
}

/* Box-average by an integer factor. */
static inline struct glint_image *fixture_shrink(const struct glint_image *src,
						 int f)
{
	return glint_image_downsample(src, f);
}

/* The 512 px reference photo of a material through a lens at fnum (0: a
 * pinhole; rendered once, cached). */
static inline struct glint_image *
bench_photo_512_lens(const char *mat, const struct glint_model *m,
		     const double *truth, double fnum)
{
	char path[256];
	struct glint_image *img = NULL;
	if (fnum > 0)
		snprintf(path, sizeof(path), "bench-out/photo-%s-f%g-512.exr",
			 mat, fnum);
	else
		snprintf(path, sizeof(path), "bench-out/photo-%s-512.exr", mat);
	if (glint_image_read(path, &img) == 0)
		return img;
	struct glint_scene sc;
	struct glint_renderer r;
	fixture_scene_lens(&sc, 512, NULL, fnum);
	if (glint_renderer_init(&r, &sc, 0, NULL) < 0)
		return NULL;
	struct glint_reference_opts ro;
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	img = glint_image_new(512, 512);
	fprintf(stderr, "bench: reference photo of %s (cached in %s)\n", mat,
		path);
	if (glint_reference_render(&sc, r.env, m, truth, &ro, img) < 0 ||
	    glint_image_write(path, img, NULL) < 0) {
		glint_image_free(img);
		img = NULL;
	}
	glint_renderer_release(&r);
	return img;
}

/* The same through a pinhole. */
static inline struct glint_image *bench_photo_512(const char *mat,
						  const struct glint_model *m,
						  const double *truth)
{
	return bench_photo_512_lens(mat, m, truth, 0);
}

/* One exposure of the sensor model, exposed so that the mean radiance
 * sits at fraction `level` of the ADC range (0.1: a normal exposure; less
 * is darker and noisier), back to radiance with 1/variance weights (0
 * where clipped). */
static inline int fixture_add_noise_seed(struct glint_image *photo,
					 struct glint_image **weight,
					 double level, uint64_t seed)
{
	struct glint_sensor s;
	struct glint_image *dn = glint_image_new(photo->width, photo->height);
	*weight = glint_image_new(photo->width, photo->height);
	glint_sensor_default(&s);
	s.seed = seed;
	double mean = 0;
	for (int i = 0; i < photo->width * photo->height * 3; i++)
		mean += photo->data[i];
	mean /= photo->width * photo->height * 3.0;
	s.exposure_s = glint_sensor_exposure_for(&s, mean, level);
	int ret = glint_sensor_capture(&s, photo, dn);
	if (!ret)
		ret = glint_sensor_to_radiance(&s, dn, photo, *weight);
	glint_image_free(dn);
	return ret;
}

/* The same with the sensor's default seed. */
static inline int fixture_add_noise(struct glint_image *photo,
				    struct glint_image **weight, double level)
{
	return fixture_add_noise_seed(photo, weight, level, 1);
}

/* The largest difference of Torrance-Sparrow parameters p from q in units
 * of the fitting tolerances (albedo 0.01, roughness 5 % relative, ior
 * 0.05): <= 1 meets them all. */
static inline double fixture_tolerance_error(const double *p, const double *q)
{
	double e = 0;
	for (int k = 0; k < 6; k++)
		e = fmax(e, fabs(p[k] - q[k]) / 0.01);
	e = fmax(e, fabs(p[6] / q[6] - 1) / 0.05);
	return fmax(e, fabs(p[7] - q[7]) / 0.05);
}

/*
 * The scene's map: class:NAME one of sim/light_class.h's lighting
 * classes at 1024 px, unrotated (sc's rotation set to none); a lat-long
 * one as it is; a square one an angular light probe (Debevec's format, as
 * the shared campus probe), converted to lat-long at its angular
 * resolution (capture/probe/probe.h) as `glint probe convert` would, in
 * memory.
 */
static inline int fixture_load_map(const char *map, struct glint_scene *sc,
				   struct glint_envmap **env)
{
	struct glint_image *img = NULL, *ll = NULL;

	if (!strncmp(map, "class:", 6)) {
		/* they face the camera unrotated */
		memset(sc->env_rotation, 0, sizeof(sc->env_rotation));
		if (glint_sim_light_class(map + 6, 1024, &img) < 0)
			return -1;
		return glint_envmap_new(img, sc->env_rotation, sc->env_scale,
					map, env);
	}
	if (glint_image_read(map, &img) < 0)
		return -1;
	if (img->width == img->height) {
		int ret = glint_probe_convert(img, GLINT_PROBE_ANGULAR,
					      GLINT_PROBE_LATLONG, 0, 0, &ll);
		glint_image_free(img);
		if (ret < 0)
			return ret;
		img = ll;
	}
	return glint_envmap_new(img, sc->env_rotation, sc->env_scale, map, env);
}

#endif
