/* SPDX-License-Identifier: MIT */
/*
 * The simulated camera: the sensor model (sim/sensor.c) behind the camera
 * ops table.  It photographs a radiance image (today a built-in test card
 * spanning 6 decades with a bright disk; the rig's scene once the board
 * drives it), outputs 12-bit Bayer RGGB in uint16, applies a new exposure
 * `latency` frames after it is requested, as real sensors do, and keeps
 * real frame timing (frame period = max(exposure, fastest period)) on the
 * injected clock.
 *
 * Device string: "sim" or "sim:key=value,...", keys: width, height,
 * latency (frames), manual (0 = no manual exposure), seed, noise (0/1),
 * scene_scale (the probe, sample and rig scenes rendered at 1/N of the
 * width and height and interpolated up, bilinearly: a 12 MP frame's
 * reference render would take most of an hour, and a benchmark of the
 * pipeline's memory and time needs the pixels, not their detail),
 * scene (card, the default; probe: a chrome ball reflecting the Venice
 * map; sample: a sphere of a Table-1 material under the same map, see
 * sim/camera_sim.h), material (the sample's Table-1 name, default
 * yellow-plastic; rig: what the sim board put in view, sim/world.h),
 * gray (the probe a gray/chrome pair: a matte ball of this albedo beside
 * the chrome one, glint_sim_probe_pair_scene()), reference (scene=rig: a
 * matte ball of this albedo at the turntable's reference position,
 * glint_sim_reference_scene()), decades (the test card's
 * dynamic range, default 6, plus its bright disk), psf (the lens's Gaussian
 * blur in pixels, default 0.6) and olpf (the optical low-pass filter, default
 * 1: every view reaches the sensor through both, sim/sensor.h), timescale (real
 * seconds per simulated second, default 1: tests and demos run a 2 s exposure
 * in 20 ms with 0.01), world (scene=rig only: a file that says what is in view
 * instead of the sim board, for a rig whose board is real hardware: "LIGHTS
 * DEGREES", the lamps on (0 none, 1 the one lamp, bit k - 1 lamp k of a rig
 * with several) and the turntable's angle, 0 the probe, 180 the sample and 90
 * the reference ball; the file is read before each frame and replaced whole by
 * its writer; while it is missing the lab is dark).  It must come last: the
 * path runs to the end of the string.
 */
#define _POSIX_C_SOURCE 200809L
#include "camera_sim.h"
#include "capture/camera/camera.h"
#include "fit/brdf/model.h"
#include "sensor.h"

#include "scenario.h"
#include "world.h"

#include "core/error.h"
#include "core/json.h"
#include "core/path.h"

#include <math.h>
#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

struct sim_cam {
	struct glint_clock clock, outer;
	double timescale, decades;
	enum { SCENE_CARD, SCENE_PROBE, SCENE_SAMPLE, SCENE_RIG } scene;
	/* scene=rig: what the board's world shows (sim/world.h) */
	struct glint_image *probe_img, *sample_img, *reference_img;
	unsigned lamps; /* the lamps they are lit by (sim/world.h) */
	int views_made; /* rig_scenes has made them (or their thread) */
	/* the views out of sight, made on a thread of their own while the
	 * sensor streams (rig_ahead): owned by it until joined */
	pthread_t ahead;
	unsigned ahead_views; /* bit v: view v is the thread's */
	struct glint_image *ahead_img[3];
	int ahead_ret;
	char ahead_err[1024];
	/* the lights-off or empty view, made on first need */
	struct glint_image *scratch;
	const struct glint_image *view; /* what the sensor sees */
	int scene_scale;
	double gray;	   /* > 0: the probe is a gray/chrome pair */
	double reference;  /* > 0: a gray ball at the reference position */
	char material[48]; /* the sample's Table-1 name */
	char world[256];   /* scene=rig: what is in view, from this file */
	char scenario[GLINT_PATH_MAX]; /* sim/scenario.h; "" none */
	struct glint_sim_world *wobj;  /* the scenario's world */
	struct glint_sensor sensor;
	struct glint_image *radiance;
	int width, height, latency, manual;
	/* exposure pipeline: requested values land `latency` frames on */
	double pending_e[8], pending_g[8];
	double exposure_s, gain;
	double next_frame_t;
	uint64_t sequence;
};

/* A numeric option (the device string's key=value, or the scenario's
 * "camera" key); `where` names the device string or the file. */
static int set_number(struct sim_cam *s, const char *where, const char *key,
		      double v)
{
	if (!strcmp(key, "width") && v >= 2 && v <= 8192)
		s->width = (int)v;
	else if (!strcmp(key, "height") && v >= 2 && v <= 8192)
		s->height = (int)v;
	else if (!strcmp(key, "latency") && v >= 0 && v <= 7)
		s->latency = (int)v;
	else if (!strcmp(key, "manual"))
		s->manual = v != 0;
	else if (!strcmp(key, "seed"))
		s->sensor.seed = (uint64_t)v;
	else if (!strcmp(key, "noise"))
		s->sensor.noise = v != 0;
	else if (!strcmp(key, "decades") && v >= 0 && v <= 8)
		s->decades = v;
	else if (!strcmp(key, "timescale") && v > 0 && v <= 1)
		s->timescale = v;
	else if (!strcmp(key, "scene_scale") && v >= 1 && v <= 64)
		s->scene_scale = (int)v;
	else if (!strcmp(key, "psf") && v >= 0 && v <= 8)
		s->sensor.psf_sigma_px = v;
	else if (!strcmp(key, "olpf"))
		s->sensor.olpf = v != 0;
	else if (!strcmp(key, "gray") && v >= 0 && v <= 1)
		s->gray = v;
	else if (!strcmp(key, "reference") && v >= 0 && v <= 1)
		s->reference = v;
	else
		return glint_error_set(EINVAL,
				       "sim camera %s: option "
				       "%s=%g: expected width, height "
				       "(2..8192), latency (0..7), "
				       "manual, seed, noise, decades "
				       "(0..8), timescale (0..1], "
				       "scene_scale (1..64), psf (0..8 px), "
				       "olpf (0/1), gray or reference "
				       "(0..1)",
				       where, key, v);
	return 0;
}

static int set_scene(struct sim_cam *s, const char *where, const char *word)
{
	static const char *const names[] = { "card", "probe", "sample", "rig" };
	int k = 0;

	while (k < 4 && strcmp(word, names[k]))
		k++;
	if (k == 4)
		return glint_error_set(EINVAL,
				       "sim camera %s: scene '%s': expected "
				       "card, probe, sample or rig",
				       where, word);
	s->scene = k;
	return 0;
}

/* The scenario's "camera" (sim/scenario.h): the device string's keys as
 * JSON (numbers, booleans for manual and noise, strings for scene and
 * material). */
static int apply_scenario(struct sim_cam *s)
{
	static const char *const keys[] = {
		"width",       "height", "latency",   "manual",
		"seed",	       "noise",	 "decades",   "timescale",
		"scene_scale", "scene",	 "material",  "psf",
		"olpf",	       "gray",	 "reference", NULL
	};
	const char *f = s->scenario;
	json_t *doc, *cam, *v;
	const char *key;
	int ret = glint_sim_scenario_load(f, &doc);

	if (ret < 0)
		return ret;
	cam = json_object_get(doc, "camera");
	if (cam)
		ret = glint_json_known_keys(f, "camera", cam, keys);
	json_object_foreach(cam, key, v)
	{
		char where[GLINT_PATH_MAX + 16];
		if (ret < 0)
			break;
		snprintf(where, sizeof(where), "%s: camera", f);
		if (!strcmp(key, "scene") || !strcmp(key, "material")) {
			const char *str = json_string_value(v);
			if (!str)
				ret = glint_error_set(EINVAL,
						      "%s.%s: expected a "
						      "string",
						      where, key);
			else if (!strcmp(key, "scene"))
				ret = set_scene(s, where, str);
			else if (strlen(str) >= sizeof(s->material) ||
				 strspn(str, "abcdefghijklmnopqrstuvwxyz-") !=
					 strlen(str))
				ret = glint_error_set(EINVAL,
						      "%s.material: expected "
						      "a Table-1 name such as "
						      "yellow-plastic",
						      where);
			else
				snprintf(s->material, sizeof(s->material), "%s",
					 str);
		} else if (json_is_boolean(v) &&
			   (!strcmp(key, "manual") || !strcmp(key, "noise") ||
			    !strcmp(key, "olpf"))) {
			ret = set_number(s, where, key, json_is_true(v));
		} else if (json_is_number(v)) {
			ret = set_number(s, where, key, json_number_value(v));
		} else {
			ret = glint_error_set(
				EINVAL, "%s.%s: expected a number", where, key);
		}
	}
	json_decref(doc);
	return ret;
}

static int parse_device(const char *dev, struct sim_cam *s)
{
	const char *p;

	if (!dev || !strcmp(dev, "sim"))
		return 0;
	if (strncmp(dev, "sim:", 4) != 0)
		return glint_error_set(EINVAL,
				       "sim camera device '%s': expected 'sim' "
				       "or 'sim:key=value,...'",
				       dev);
	for (p = dev + 4; *p;) {
		char key[32];
		double v;
		int n = 0;
		if (!strncmp(p, "scene=", 6)) {
			char word[16] = "";
			if (sscanf(p + 6, "%15[a-z]%n", word, &n) != 1)
				n = 0;
			int ret = set_scene(s, dev, word);
			if (ret < 0)
				return ret;
			p += 6 + n;
			if (*p == ',')
				p++;
			continue;
		}
		if (!strncmp(p, "material=", 9)) {
			if (sscanf(p + 9, "%47[a-z-]%n", s->material, &n) != 1)
				return glint_error_set(
					EINVAL,
					"sim camera device '%s': "
					"material: expected a Table-1 name "
					"such as yellow-plastic",
					dev);
			p += 9 + n;
			if (*p == ',')
				p++;
			continue;
		}
		if (!strncmp(p, "scenario=", 9)) {
			if (!p[9] || strlen(p + 9) >= sizeof(s->scenario))
				return glint_error_set(
					EINVAL,
					"sim camera device '%s': scenario: "
					"expected a file's path (the last "
					"option)",
					dev);
			snprintf(s->scenario, sizeof(s->scenario), "%s", p + 9);
			return apply_scenario(s);
		}
		if (!strncmp(p, "world=", 6)) {
			if (!p[6] || strlen(p + 6) >= sizeof(s->world))
				return glint_error_set(
					EINVAL,
					"sim camera device '%s': world: "
					"expected a file's path (the last "
					"option)",
					dev);
			snprintf(s->world, sizeof(s->world), "%s", p + 6);
			break;
		}
		if (sscanf(p, "%31[a-z_]=%lf%n", key, &v, &n) != 2)
			return glint_error_set(EINVAL,
					       "sim camera device '%s': bad "
					       "option at '%s'",
					       dev, p);
		int ret = set_number(s, dev, key, v);
		if (ret < 0)
			return ret;
		p += n;
		if (*p == ',')
			p++;
	}
	return 0;
}

/* Simulated time runs 1/timescale times faster than the outer clock. */
static double scaled_now(void *ctx)
{
	struct sim_cam *s = ctx;
	return s->outer.now(s->outer.ctx) / s->timescale;
}

static void scaled_sleep_until(void *ctx, double t)
{
	struct sim_cam *s = ctx;
	s->outer.sleep_until(s->outer.ctx, t * s->timescale);
}

/* *img (w/k x h/k, rounded up) interpolated to w x h, bilinearly at the
 * pixel centres; it replaces *img. */
static int upscale(struct glint_image **img, int w, int h, int k)
{
	const struct glint_image *a = *img;
	struct glint_image *b = glint_image_new(w, h);
	if (!b)
		return glint_error_set(ENOMEM, "out of memory");
	for (int y = 0; y < h; y++) {
		double fy = fmin(fmax((y + 0.5) / k - 0.5, 0), a->height - 1);
		int y0 = (int)fy, y1 = y0 + (y0 + 1 < a->height);
		double ty = fy - y0;
		for (int x = 0; x < w; x++) {
			double fx = fmin(fmax((x + 0.5) / k - 0.5, 0),
					 a->width - 1);
			int x0 = (int)fx, x1 = x0 + (x0 + 1 < a->width);
			double tx = fx - x0;
			const float *p00 = glint_image_px(a, x0, y0);
			const float *p01 = glint_image_px(a, x1, y0);
			const float *p10 = glint_image_px(a, x0, y1);
			const float *p11 = glint_image_px(a, x1, y1);
			float *o = glint_image_px(b, x, y);
			for (int c = 0; c < 3; c++)
				o[c] = (float)((1 - ty) * ((1 - tx) * p00[c] +
							   tx * p01[c]) +
					       ty * ((1 - tx) * p10[c] +
						     tx * p11[c]));
		}
	}
	glint_image_free(*img);
	*img = b;
	return 0;
}

/* Views: 0 the probe, 1 the sample, 2 the gray reference ball. */
static const char *const view_names[3] = { "probe", "sample", "reference" };

/* A scene's radiance at the sensor's size, rendered at 1/scene_scale,
 * lit by s->lamps. */
static int render_view(const struct sim_cam *s, int sample,
		       struct glint_image **out)
{
	int k = s->scene_scale > 1 ? s->scene_scale : 1;
	int w = (s->width + k - 1) / k, h = (s->height + k - 1) / k;
	int ret = sample == 2 ? glint_sim_reference_scene(w, h, s->lamps,
							  s->reference, out)
		  : sample ? glint_sim_sample_scene(w, h, s->material, s->lamps,
						    out)
		  : s->gray > 0 ? glint_sim_probe_pair_scene(w, h, s->lamps,
							     s->gray, out)
				: glint_sim_probe_scene(w, h, s->lamps, out);
	if (ret == 0 && k > 1)
		ret = upscale(out, s->width, s->height, k);
	if (ret < 0) {
		glint_image_free(*out);
		*out = NULL;
	}
	return ret;
}

/* "size:mtime" of a file, for a cache key ("-" when it is missing). */
static void file_stamp(const char *path, char *buf, size_t n)
{
	struct stat st;
	if (stat(path, &st) == 0)
		snprintf(buf, n, "%lld:%lld.%09ld", (long long)st.st_size,
			 (long long)st.st_mtim.tv_sec, st.st_mtim.tv_nsec);
	else
		snprintf(buf, n, "-");
}

/* The folder views are cached in, made if need be: $GLINT_SIM_CACHE
 * ("off": none), else $XDG_CACHE_HOME/glint/sim, else
 * ~/.cache/glint/sim.  Returns 0 and "" when there is none. */
static int cache_dir(char *buf, size_t n)
{
	const char *env = getenv("GLINT_SIM_CACHE");
	const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
	int ret;

	buf[0] = '\0';
	if (env && (!*env || !strcmp(env, "off")))
		return 0;
	if (env)
		ret = glint_path_fmt(buf, n, "%s", env);
	else if (xdg && *xdg)
		ret = glint_path_fmt(buf, n, "%s/glint/sim", xdg);
	else if (home && *home)
		ret = glint_path_fmt(buf, n, "%s/.cache/glint/sim", home);
	else
		return 0;
	/* mkdir -p: each component in turn */
	for (char *p = buf + 1; ret == 0 && *p; p++) {
		if (*p != '/')
			continue;
		*p = '\0';
		mkdir(buf, 0777);
		*p = '/';
	}
	if (ret == 0 && mkdir(buf, 0777) < 0 && errno != EEXIST)
		buf[0] = '\0'; /* no cache: render every time */
	glint_error_clear();
	return 0;
}

/*
 * A view through the disk cache: the reference render of a rig view
 * takes tens of CPU-seconds, and a camera that renders at its first frame
 * stalls every capture that starts it.  The key is everything the render
 * depends on: the view, its size and scale, the lamps, the material, the
 * map and table files, and the renderer itself (this program's file), so
 * that a rebuilt glint or a changed map renders anew.  A cached file that
 * does not read back whole at the right size is rendered again.
 */
static int scene_image_raw(const struct sim_cam *s, int sample,
			   struct glint_image **out)
{
	char dir[GLINT_PATH_MAX], path[GLINT_PATH_MAX], data[GLINT_PATH_MAX];
	char key[2048], exe[64], map[64], table[64];
	int ret;

	*out = NULL;
	cache_dir(dir, sizeof(dir));
	if (!dir[0])
		return render_view(s, sample, out);
	file_stamp("/proc/self/exe", exe, sizeof(exe));
	map[0] = table[0] = '\0';
	if (glint_data_path(data, sizeof(data), "env/venice_sunset_1k.hdr") ==
	    0)
		file_stamp(data, map, sizeof(map));
	if (glint_data_path(data, sizeof(data), "paper-table1.json") == 0)
		file_stamp(data, table, sizeof(table));
	glint_error_clear();
	snprintf(key, sizeof(key),
		 "glint sim view 1|%s|%dx%d/%d|lamps %u|%s|gray %g|exe %s|"
		 "map %s|table %s",
		 view_names[sample], s->width, s->height, s->scene_scale,
		 s->lamps, sample == 1 ? s->material : "-",
		 sample == 1   ? 0
		 : sample == 2 ? s->reference
			       : s->gray,
		 exe, map, table);
	uint64_t h = 1469598103934665603ull; /* FNV-1a */
	for (const char *c = key; *c; c++)
		h = (h ^ (unsigned char)*c) * 1099511628211ull;
	if (glint_path_fmt(path, sizeof(path), "%s/%s-%016llx.exr", dir,
			   view_names[sample], (unsigned long long)h) < 0) {
		glint_error_clear();
		return render_view(s, sample, out);
	}
	if (glint_image_read(path, out) == 0 && (*out)->width == s->width &&
	    (*out)->height == s->height &&
	    glint_image_check_finite(*out, path, 1) == 0)
		return 0;
	glint_image_free(*out);
	*out = NULL;
	glint_error_clear();
	ret = render_view(s, sample, out);
	/* A cache that cannot be written costs the next capture a render,
	 * nothing else. */
	if (ret == 0 && glint_image_write(path, *out, NULL) < 0)
		glint_error_clear();
	return ret;
}

/* A view as the sensor receives it: through the lens and the OLPF
 * (sim/sensor.h); the cache keeps the scene's own radiance. */
static int scene_image(const struct sim_cam *s, int sample,
		       struct glint_image **out)
{
	int ret = scene_image_raw(s, sample, out);
	if (ret == 0)
		ret = glint_sensor_optics(&s->sensor, *out);
	if (ret < 0) {
		glint_image_free(*out);
		*out = NULL;
	}
	return ret;
}

static void world_now(const struct sim_cam *s, struct glint_sim_state *w);

static struct glint_image **rig_slot(struct sim_cam *s, int v)
{
	return v == 0	? &s->probe_img
	       : v == 1 ? &s->sample_img
			: &s->reference_img;
}

/* The thread of rig_ahead: its views rendered (or read) in turn; the
 * first failure ends it, its message kept for the capture that needs
 * the view. */
static void *ahead_main(void *arg)
{
	struct sim_cam *s = arg;
	int ret = 0;
	for (int v = 0; ret == 0 && v < 3; v++)
		if (s->ahead_views & 1u << v)
			ret = scene_image(s, v, &s->ahead_img[v]);
	if (ret < 0)
		snprintf(s->ahead_err, sizeof(s->ahead_err), "%s",
			 glint_error_msg());
	s->ahead_ret = ret;
	return NULL;
}

/* The views out of sight, on their own thread: a rig's first capture
 * photographs the probe while the sample's view renders (a reference
 * render takes seconds, the probe's bracket seconds of camera time), and
 * the next capture reads it from the cache.  Without a thread they are
 * made here. */
static int rig_ahead(struct sim_cam *s, unsigned views)
{
	s->ahead_ret = 0;
	s->ahead_err[0] = '\0';
	s->ahead_views = views;
	if (views && pthread_create(&s->ahead, NULL, ahead_main, s) != 0) {
		s->ahead_views = 0;
		for (int v = 0; v < 3; v++) {
			int ret = views & 1u << v
					  ? scene_image(s, v, rig_slot(s, v))
					  : 0;
			if (ret < 0)
				return ret;
		}
	}
	return 0;
}

/* The thread's views, in place once it has ended; its result (0 or a
 * negative errno, its message in ahead_err), the error state untouched. */
static int rig_wait(struct sim_cam *s)
{
	if (!s->ahead_views)
		return 0;
	pthread_join(s->ahead, NULL);
	for (int v = 0; v < 3; v++) {
		if (!(s->ahead_views & 1u << v))
			continue;
		glint_image_free(*rig_slot(s, v));
		*rig_slot(s, v) = s->ahead_img[v];
		s->ahead_img[v] = NULL;
	}
	s->ahead_views = 0;
	return s->ahead_ret;
}

/* rig_wait for a view the sensor needs: 0, or the thread's error. */
static int rig_join(struct sim_cam *s)
{
	int ret = rig_wait(s);
	if (ret < 0) {
		s->views_made = 0; /* made again at the next frame */
		return glint_error_set(-ret, "%s", s->ahead_err);
	}
	return 0;
}

/* The views gone, their thread ended (it is never left running: a
 * close waits for it), the error state untouched. */
static void rig_free(struct sim_cam *s)
{
	rig_wait(s);
	s->views_made = 0;
	for (int v = 0; v < 3; v++) {
		glint_image_free(*rig_slot(s, v));
		*rig_slot(s, v) = NULL;
	}
}

/* scene=rig: its views lit by the lamps on now (lamp 1 while none is):
 * the one in sight (the probe while none is) made now, the others on a
 * thread of their own (rig_ahead); the sensor looks at one of them in
 * place (a 12 MP view is 148 MB), a lights-off or empty one is made on
 * first need (rig_view). */
static int rig_scenes(struct sim_cam *s)
{
	struct glint_sim_state w;
	world_now(s, &w);
	rig_free(s);
	s->lamps = w.lights ? w.lights : 1;
	int now = w.view == GLINT_SIM_VIEW_SAMPLE			   ? 1
		  : w.view == GLINT_SIM_VIEW_REFERENCE && s->reference > 0 ? 2
									   : 0;
	unsigned later =
		(1u << 0 | 1u << 1 | (s->reference > 0) << 2) & ~(1u << now);
	int ret = scene_image(s, now, rig_slot(s, now));
	if (!ret)
		ret = rig_ahead(s, later);
	if (ret < 0)
		rig_free(s);
	s->views_made = ret == 0;
	return ret;
}

/* scene=rig at open: what its views need is there (the map, the
 * material); they are rendered (or read from the cache) when a capture
 * starts (sim_start), so that opening the camera to check a rig costs
 * nothing. */
static int rig_check(const struct sim_cam *s)
{
	char path[GLINT_PATH_MAX];
	const struct glint_model *model;
	double p[GLINT_MAX_PARAMS];
	struct stat st;
	int ret =
		glint_data_path(path, sizeof(path), "env/venice_sunset_1k.hdr");
	if (ret == 0 && stat(path, &st) < 0)
		ret = glint_error_set(errno, "sim rig scene: %s: %s", path,
				      strerror(errno));
	if (ret == 0)
		ret = glint_data_path(path, sizeof(path), "paper-table1.json");
	if (ret == 0)
		ret = glint_material_load(path, s->material, &model, p);
	return ret;
}

static int sim_open(const char *device, const struct glint_clock *clock,
		    void **priv)
{
	struct sim_cam *s = calloc(1, sizeof(*s));
	int ret;

	*priv = NULL;
	if (!s)
		return glint_error_set(ENOMEM, "out of memory");
	s->outer = *clock;
	s->timescale = 1;
	s->decades = 6;
	glint_sensor_default(&s->sensor);
	s->width = 64;
	s->height = 48;
	s->latency = 2;
	s->manual = 1;
	snprintf(s->material, sizeof(s->material), "yellow-plastic");
	ret = parse_device(device, s);
	if (!ret)
		ret = glint_sim_world_open(s->scenario, &s->wobj);
	if (ret < 0) {
		free(s);
		return ret;
	}
	if (s->timescale == 1) {
		s->clock = *clock;
	} else {
		s->clock.now = scaled_now;
		s->clock.sleep_until = scaled_sleep_until;
		s->clock.ctx = s;
	}
	s->lamps = 1;
	if (s->scene == SCENE_PROBE || s->scene == SCENE_SAMPLE)
		ret = scene_image(s, s->scene == SCENE_SAMPLE, &s->radiance);
	else if (s->scene == SCENE_RIG)
		ret = rig_check(s);
	else if (!(s->radiance = glint_sim_test_card(s->width, s->height,
						     s->decades)))
		ret = glint_error_set(ENOMEM, "out of memory");
	else
		ret = glint_sensor_optics(&s->sensor, s->radiance);
	if (ret < 0) {
		glint_sim_world_close(s->wobj);
		free(s);
		return glint_error_prefix(ret, "sim camera");
	}
	s->view = s->radiance;
	s->exposure_s = s->sensor.exposure_s;
	s->gain = 1;
	for (int i = 0; i < 8; i++) {
		s->pending_e[i] = s->exposure_s;
		s->pending_g[i] = s->gain;
	}
	s->next_frame_t = s->clock.now(s->clock.ctx);
	*priv = s;
	return 0;
}

static void sim_close(void *priv)
{
	struct sim_cam *s = priv;
	if (!s)
		return;
	rig_free(s);
	glint_image_free(s->radiance);
	glint_image_free(s->scratch);
	glint_sim_world_close(s->wobj);
	free(s);
}

/* world=PATH: "LIGHTS DEGREES" as a board outside this process left them
 * (LIGHTS: bit k - 1 for lamp k, so 1 is the one lamp on); a view only
 * within a degree of the probe (0), the sample (180) or the reference
 * ball (90, either way). */
static void world_from_file(const char *path, struct glint_sim_state *w)
{
	FILE *f = fopen(path, "r");
	int lights = 0;
	double deg = -1;

	w->lights = 0;
	w->view = GLINT_SIM_VIEW_NONE;
	if (!f)
		return;
	if (fscanf(f, "%d %lf", &lights, &deg) == 2) {
		double a = fabs(remainder(deg, 360.0));
		w->lights = lights > 0 ? (unsigned)lights &
						 ((1u << GLINT_MAX_LIGHTS) - 1)
				       : 0;
		w->turntable_deg = deg;
		w->view = a < 1		     ? GLINT_SIM_VIEW_PROBE
			  : a > 179	     ? GLINT_SIM_VIEW_SAMPLE
			  : fabs(a - 90) < 1 ? GLINT_SIM_VIEW_REFERENCE
					     : GLINT_SIM_VIEW_NONE;
	}
	fclose(f);
}

static void world_now(const struct sim_cam *s, struct glint_sim_state *w)
{
	if (s->world[0])
		world_from_file(s->world, w);
	else
		glint_sim_world_get(s->wobj, w);
}

/* scene=rig, before the stream: the views for the lamps on now (the one
 * in sight made here, so that its frames wait on no render; rig_scenes). */
static int sim_start(void *priv)
{
	struct sim_cam *s = priv;
	struct glint_sim_state w;

	if (s->scene != SCENE_RIG)
		return 0;
	world_now(s, &w);
	if (s->views_made && (!w.lights || w.lights == s->lamps))
		return 0;
	int ret = rig_scenes(s);
	return ret < 0 ? glint_error_prefix(ret, "sim camera") : 0;
}

/* scene=rig: the radiance of what is in view, lit by the lamps on (the
 * views re-rendered when other lamps came on), dimmed with none. */
static int rig_view(struct sim_cam *s)
{
	struct glint_sim_state w;
	world_now(s, &w);
	if (!s->views_made || (w.lights && w.lights != s->lamps)) {
		int ret = rig_scenes(s);
		if (ret < 0)
			return ret;
	}
	int v = w.view == GLINT_SIM_VIEW_PROBE	     ? 0
		: w.view == GLINT_SIM_VIEW_SAMPLE    ? 1
		: w.view == GLINT_SIM_VIEW_REFERENCE ? 2
						     : -1;
	if (v >= 0 && s->ahead_views & 1u << v) {
		int ret = rig_join(s);
		if (ret < 0)
			return ret;
	}
	const struct glint_image *src =
		w.view == GLINT_SIM_VIEW_PROBE	  ? s->probe_img
		: w.view == GLINT_SIM_VIEW_SAMPLE ? s->sample_img
		: w.view == GLINT_SIM_VIEW_REFERENCE && s->reference > 0
			? s->reference_img
			: NULL; /* dark */
	if (src && w.lights) {
		s->view = src;
		return 0;
	}
	if (!s->scratch && !(s->scratch = glint_image_new(s->width, s->height)))
		return glint_error_set(ENOMEM, "sim camera: out of memory");
	float k = (float)GLINT_SIM_LIGHTS_OFF_FACTOR;
	size_t n = (size_t)s->width * s->height * 3;
	for (size_t i = 0; i < n; i++)
		s->scratch->data[i] = src ? k * src->data[i] : 0;
	s->view = s->scratch;
	return 0;
}

static int sim_describe(void *priv, struct glint_camera_info *in)
{
	struct sim_cam *s = priv;

	memset(in, 0, sizeof(*in));
	snprintf(in->backend, sizeof(in->backend), "sim");
	snprintf(in->name, sizeof(in->name), "simulated 12-bit sensor");
	in->width = s->width;
	in->height = s->height;
	in->nformats = 1;
	snprintf(in->formats[0], sizeof(in->formats[0]), "RGGB16");
	in->bit_depth = s->sensor.bits;
	in->manual_exposure = s->manual;
	in->exposure_min_s = 1e-5;
	in->exposure_max_s = 2;
	in->exposure_step_s = 1e-5;
	in->gain_min = 1;
	in->gain_max = 16;
	in->frame_period_min_s = 1.0 / 30;
	in->latency_frames = s->latency;
	snprintf(in->exposure_control, sizeof(in->exposure_control),
		 "simulated, 10 us steps");
	snprintf(in->gain_control, sizeof(in->gain_control),
		 "simulated analogue gain");
	return 0;
}

static int sim_configure(void *priv)
{
	(void)priv; /* one format: raw Bayer at the sensor's depth */
	return 0;
}

static int sim_set_exposure(void *priv, double *exposure_s, double *gain)
{
	struct sim_cam *s = priv;

	if (!s->manual)
		return glint_error_set(ENOTSUP,
				       "sim camera: exposure is automatic");
	/* Quantise to the 10 us step, as a real driver would. */
	double e = 1e-5 * floor(*exposure_s / 1e-5 + 0.5);
	s->pending_e[s->latency] = e;
	s->pending_g[s->latency] = *gain;
	for (int i = s->latency + 1; i < 8; i++) {
		s->pending_e[i] = e;
		s->pending_g[i] = *gain;
	}
	*exposure_s = e;
	return 0;
}

static int sim_grab(void *priv, struct glint_frame *f)
{
	struct sim_cam *s = priv;
	struct glint_image *dn = NULL;
	int ret;

	memset(f, 0, sizeof(*f));
	/* This frame's settings come out of the latency pipeline. */
	s->exposure_s = s->pending_e[0];
	s->gain = s->pending_g[0];
	memmove(s->pending_e, s->pending_e + 1, 7 * sizeof(double));
	memmove(s->pending_g, s->pending_g + 1, 7 * sizeof(double));
	double now = s->clock.now(s->clock.ctx);
	double t0 = fmax(now, s->next_frame_t);
	double period = fmax(s->exposure_s, 1.0 / 30);
	s->next_frame_t = t0 + period;
	s->clock.sleep_until(s->clock.ctx, t0 + s->exposure_s);

	struct glint_sensor sn = s->sensor;
	sn.exposure_s = s->exposure_s;
	sn.gain = s->sensor.gain * s->gain;
	sn.seed = s->sensor.seed * 1000003u + s->sequence;
	dn = glint_image_new(s->width, s->height);
	f->data = malloc((size_t)s->width * s->height * sizeof(uint16_t));
	if (!dn || !f->data) {
		ret = glint_error_set(ENOMEM, "sim camera: out of memory");
		goto err;
	}
	if (s->scene == SCENE_RIG && (ret = rig_view(s)) < 0)
		goto err;
	ret = glint_sensor_capture(&sn, s->view, dn);
	if (ret < 0)
		goto err;
	/* Bayer RGGB: R at (even, even), B at (odd, odd), G elsewhere. */
	for (int y = 0; y < s->height; y++)
		for (int x = 0; x < s->width; x++) {
			int c = (x & 1) + (y & 1);
			f->data[(size_t)y * s->width + x] =
				(uint16_t)glint_image_px(dn, x, y)[c];
		}
	glint_image_free(dn);
	f->width = s->width;
	f->height = s->height;
	snprintf(f->format, sizeof(f->format), "RGGB16");
	snprintf(f->source_format, sizeof(f->source_format), "sim");
	f->channels = 1;
	f->linear = 1;
	f->bit_depth = s->sensor.bits;
	f->exposure_s = s->exposure_s;
	f->gain = s->gain;
	f->black_level = s->sensor.black_level;
	/* On the outer clock, as the interface promises. */
	f->t_start = t0 * s->timescale;
	f->t_end = (t0 + s->exposure_s) * s->timescale;
	f->sequence = s->sequence++;
	return 0;
err:
	glint_image_free(dn);
	glint_frame_release(f);
	return ret;
}

const struct glint_camera_ops glint_camera_sim_ops = {
	.name = "sim",
	.open = sim_open,
	.close = sim_close,
	.describe = sim_describe,
	.configure = sim_configure,
	.set_exposure = sim_set_exposure,
	.grab = sim_grab,
	.start = sim_start,
};
