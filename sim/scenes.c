/* SPDX-License-Identifier: MIT */
/*
 * The sim camera's scenes (sim/camera_sim.h): the test card, the rig's
 * lamps and map, the chrome probe and the sample sphere, each rendered
 * independently of glint's fitter (sim/probe_sim.h, sim/reference.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "camera_sim.h"
#include "probe_sim.h"
#include "reference.h"
#include "world.h"

#include "core/error.h"
#include "core/path.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double glint_sim_lamp_turn(int k)
{
	static const double turn[GLINT_MAX_LIGHTS] = { 0, 240, 120, 180 };
	return k >= 1 && k <= GLINT_MAX_LIGHTS ? turn[k - 1] : 0;
}

int glint_sim_rig_map(unsigned lamps, struct glint_image **out)
{
	struct glint_image *src = NULL, *dst;
	char path[GLINT_PATH_MAX];
	int ret =
		glint_data_path(path, sizeof(path), "env/venice_sunset_1k.hdr");
	*out = NULL;
	if (ret == 0)
		ret = glint_image_read(path, &src);
	if (ret < 0)
		return ret;
	dst = glint_image_new(src->width, src->height);
	if (!dst) {
		glint_image_free(src);
		return glint_error_set(ENOMEM, "out of memory");
	}
	lamps &= (1u << GLINT_MAX_LIGHTS) - 1;
	if (!lamps)
		lamps = 1;
	/* Each lamp's map turned by a whole number of texel columns: a
	 * rotation about +Y that needs no resampling. */
	int w = src->width;
	for (int k = 1; k <= GLINT_MAX_LIGHTS; k++) {
		if (!(lamps & (1u << (k - 1))))
			continue;
		double turn = GLINT_SIM_RIG_MAP_TURN + glint_sim_lamp_turn(k);
		int shift = (int)lround(turn / 360.0 * w);
		for (int y = 0; y < src->height; y++)
			for (int x = 0; x < w; x++) {
				float *d = glint_image_px(dst, x, y);
				const float *p = glint_image_px(
					src, ((x + shift) % w + w) % w, y);
				for (int c = 0; c < 3; c++)
					d[c] += p[c];
			}
	}
	glint_image_free(src);
	*out = dst;
	return 0;
}

int glint_sim_probe_scene(int w, int h, unsigned lamps,
			  struct glint_image **out)
{
	struct glint_image *env = NULL;
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };
	int ret = glint_sim_rig_map(lamps, &env);
	*out = NULL;
	if (ret < 0)
		return glint_error_prefix(ret, "sim probe scene");
	/* Focal length 2 w px; the ball centred, 0.4 of the smaller side
	 * in radius: at distance d radii with f tan(asin(1 / d)) = r. */
	double f = glint_sim_probe_focal_px(w);
	double r = 0.4 * (w < h ? w : h);
	double d = 1 / sin(atan(r / f));
	ret = glint_sim_mirror_ball(env, w, h, f, v3(0, 0, -d), 1, n, k, 12,
				    out);
	glint_image_free(env);
	return ret;
}

void glint_sim_probe_pair_circle(int w, int h, int ball, double *cx, double *cy,
				 double *r)
{
	*cx = (ball ? 0.72 : 0.3) * w;
	*cy = 0.5 * h;
	*r = 0.25 * (w < h ? w : h);
}

/* The centre of a unit ball whose image circle is centred at pixel
 * (cx, cy) with radius r: on that pixel's ray, at the distance where it
 * subtends r (the off-axis image is an ellipse of about that size). */
static struct vec3 ball_centre(int w, int h, double f, double cx, double cy,
			       double r)
{
	struct vec3 d =
		v3_norm(v3((cx - w / 2.0) / f, -(cy - h / 2.0) / f, -1));
	return v3_scale(d, 1 / sin(atan(r / f)));
}

/* A matte gray ball of `albedo` whose image circle is (cx, cy, r), lit by
 * env, added to *out over what is there by the share of each pixel its
 * silhouette covers (4 x 4 rays); the reference renderer (Lambert), 9 x 64
 * samples a pixel. */
static int add_gray_ball(const struct glint_image *env, int w, int h, double f,
			 double cx, double cy, double r, double albedo,
			 struct glint_image *out)
{
	struct glint_image *gray = NULL, *copy = NULL;
	struct glint_envmap *em = NULL;
	struct glint_scene sc;
	struct glint_reference_opts ro;
	double p[GLINT_MAX_PARAMS] = { albedo, albedo, albedo };
	const struct glint_model *lambert = glint_model_find("lambert");
	struct vec3 c = ball_centre(w, h, f, cx, cy, r);
	glint_scene_defaults(&sc);
	int ret = glint_pinhole_init(&sc.cam, w, h, f * 1e-6, 1e-6, 0, 0,
				     v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
	sc.sphere_radius = 1;
	sc.sphere_centre = c;
	if (ret == 0 && !(copy = glint_image_dup(env)))
		ret = glint_error_set(ENOMEM, "sim gray ball: out of memory");
	double rot[3] = { 0, 0, 0 };
	if (ret == 0) {
		ret = glint_envmap_new(copy, rot, 1, "rig map", &em);
		copy = NULL; /* the map's now */
	}
	if (ret == 0 && !(gray = glint_image_new(w, h)))
		ret = glint_error_set(ENOMEM, "sim gray ball: out of memory");
	glint_reference_default_opts(&ro);
	ro.spp = 9;
	ro.samples = 64;
	if (ret == 0)
		ret = glint_reference_render(&sc, em, lambert, p, &ro, gray);
	for (int y = 0; ret == 0 && y < h; y++)
		for (int x = 0; x < w; x++) {
			if (hypot(x + 0.5 - cx, y + 0.5 - cy) > r + 2)
				continue;
			int hit = 0;
			for (int j = 0; j < 4; j++)
				for (int i = 0; i < 4; i++) {
					struct vec3 d = v3_norm(v3(
						(x + (i + 0.5) / 4 - w / 2.0) /
							f,
						-(y + (j + 0.5) / 4 - h / 2.0) /
							f,
						-1));
					double b = v3_dot(d, c);
					hit += b * b - v3_dot(c, c) + 1 > 0;
				}
			float *o = glint_image_px(out, x, y);
			const float *g = glint_image_px(gray, x, y);
			for (int q = 0; q < 3; q++)
				o[q] += (float)(hit / 16.0) * g[q];
		}
	glint_envmap_free(em);
	glint_image_free(copy);
	glint_image_free(gray);
	return ret;
}

int glint_sim_probe_pair_scene(int w, int h, unsigned lamps, double albedo,
			       struct glint_image **out)
{
	struct glint_image *env = NULL;
	double n[3] = { 3.2, 3.2, 3.2 }, k[3] = { 3.3, 3.3, 3.3 };
	double f = glint_sim_probe_focal_px(w), cx, cy, r;
	int ret = glint_sim_rig_map(lamps, &env);

	*out = NULL;
	if (ret < 0)
		return glint_error_prefix(ret, "sim probe pair");
	glint_sim_probe_pair_circle(w, h, 0, &cx, &cy, &r);
	ret = glint_sim_mirror_ball(env, w, h, f,
				    ball_centre(w, h, f, cx, cy, r), 1, n, k,
				    12, out);
	glint_sim_probe_pair_circle(w, h, 1, &cx, &cy, &r);
	if (ret == 0)
		ret = add_gray_ball(env, w, h, f, cx, cy, r, albedo, *out);
	glint_image_free(env);
	if (ret < 0) {
		glint_image_free(*out);
		*out = NULL;
	}
	return ret;
}

int glint_sim_reference_scene(int w, int h, unsigned lamps, double albedo,
			      struct glint_image **out)
{
	struct glint_image *env = NULL;
	double f = glint_sim_probe_focal_px(w);
	int ret = glint_sim_rig_map(lamps, &env);

	*out = NULL;
	if (ret < 0)
		return glint_error_prefix(ret, "sim reference ball");
	if (!(*out = glint_image_new(w, h)))
		ret = glint_error_set(ENOMEM,
				      "sim reference ball: out of memory");
	/* where the probe scene's chrome ball is (glint_sim_probe_scene) */
	if (ret == 0)
		ret = add_gray_ball(env, w, h, f, w / 2.0, h / 2.0,
				    0.4 * (w < h ? w : h), albedo, *out);
	glint_image_free(env);
	if (ret < 0) {
		glint_image_free(*out);
		*out = NULL;
	}
	return ret;
}

double glint_sim_probe_focal_px(int w)
{
	return 2.0 * w;
}

int glint_sim_sample_scene_def(int w, int h, struct glint_scene *sc)
{
	glint_scene_defaults(sc);
	/* Pixel pitch 1 um; only focal length / pitch matters to a pinhole. */
	double pitch = 1e-6, f = glint_sim_probe_focal_px(w);
	int ret = glint_pinhole_init(&sc->cam, w, h, f * pitch, pitch, 0, 0,
				     v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
	if (ret < 0)
		return ret;
	double r = 0.35 * (w < h ? w : h);
	sc->sphere_radius = 0.05;
	sc->sphere_centre = v3(0, 0, -0.05 / sin(atan(r / f)));
	return 0;
}

static int render_sample(int w, int h, const char *material, unsigned lamps,
			 struct glint_image **out);

/* The reference render takes seconds: the last one is kept for the
 * process (the rig daemon opens the camera once per capture). */
static struct {
	pthread_mutex_t lock;
	int w, h;
	unsigned lamps;
	char material[48];
	struct glint_image *img;
} sample_cache = { PTHREAD_MUTEX_INITIALIZER, 0, 0, 0, "", NULL };

static struct glint_image *image_copy(const struct glint_image *src)
{
	struct glint_image *d = glint_image_new(src->width, src->height);
	if (d)
		memcpy(d->data, src->data,
		       (size_t)src->width * src->height * 3 * sizeof(float));
	return d;
}

int glint_sim_sample_scene(int w, int h, const char *material, unsigned lamps,
			   struct glint_image **out)
{
	int ret = 0;
	pthread_mutex_lock(&sample_cache.lock);
	if (!sample_cache.img || sample_cache.w != w || sample_cache.h != h ||
	    sample_cache.lamps != lamps ||
	    strcmp(sample_cache.material, material) != 0) {
		struct glint_image *img = NULL;
		ret = render_sample(w, h, material, lamps, &img);
		if (ret == 0) {
			glint_image_free(sample_cache.img);
			sample_cache.img = img;
			sample_cache.w = w;
			sample_cache.h = h;
			sample_cache.lamps = lamps;
			snprintf(sample_cache.material,
				 sizeof(sample_cache.material), "%s", material);
		}
	}
	*out = NULL;
	if (ret == 0 && !(*out = image_copy(sample_cache.img)))
		ret = glint_error_set(ENOMEM, "out of memory");
	pthread_mutex_unlock(&sample_cache.lock);
	return ret;
}

static int render_sample(int w, int h, const char *material, unsigned lamps,
			 struct glint_image **out)
{
	struct glint_scene sc;
	struct glint_envmap *env = NULL;
	struct glint_image *map = NULL;
	const struct glint_model *model;
	double p[GLINT_MAX_PARAMS], rot[3] = { 0, 0, 0 };
	int ret = glint_sim_sample_scene_def(w, h, &sc);

	*out = NULL;
	char table[GLINT_PATH_MAX];
	if (!ret)
		ret = glint_data_path(table, sizeof(table),
				      "paper-table1.json");
	if (!ret)
		ret = glint_material_load(table, material, &model, p);
	if (!ret)
		ret = glint_sim_rig_map(lamps, &map);
	if (!ret)
		ret = glint_envmap_new(map, rot, 1, "sim rig map", &env);
	if (!ret && !(*out = glint_image_new(w, h)))
		ret = glint_error_set(ENOMEM, "out of memory");
	if (!ret) {
		struct glint_reference_opts ro;
		glint_reference_default_opts(&ro);
		ro.spp = 4;
		ret = glint_reference_render(&sc, env, model, p, &ro, *out);
	}
	glint_envmap_free(env);
	if (ret < 0) {
		glint_image_free(*out);
		*out = NULL;
		return glint_error_prefix(ret, "sim sample scene (%s)",
					  material);
	}
	return 0;
}

struct glint_image *glint_sim_test_card(int w, int h, double decades)
{
	struct glint_image *img = glint_image_new(w, h);
	if (!img)
		return NULL;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y);
			double l = 1e2 *
				   pow(10, decades * ((double)x / (w - 1) - 1));
			double dx = x - 0.7 * w, dy = y - 0.5 * h;
			if (dx * dx + dy * dy < 0.01 * w * w)
				l = 5e2;
			p[0] = (float)(0.8 * l);
			p[1] = (float)l;
			p[2] = (float)(0.6 * l);
		}
	return img;
}
