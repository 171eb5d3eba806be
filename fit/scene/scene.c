/* SPDX-License-Identifier: MIT */
#include "scene.h"

#include "core/error.h"
#include "core/json.h"

#include <libgen.h>
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

void glint_scene_defaults(struct glint_scene *s)
{
	memset(s, 0, sizeof(*s));
	s->env_scale = 1;
	s->spp = 4;
	s->light_samples = 32;
	s->brdf_samples = 32;
}

/*
 * Primary hits a pixel when the scene does not say: 4 for the pixel's own
 * square; 16 under the camera's blur, whose filter spreads a pixel's hits
 * over 2 to 3 pixels a side.  At 4 there a highlight a few pixels wide
 * falls between them: on the simulated rig (lens, OLPF, mosaic) the
 * eleven opaque Table-1 materials give 5 of 11 within tolerance at 4 and
 * 10 of 11 at 16 (bench/rig_materials.py, docs/fitting.md).
 */
int glint_scene_spp_default(const struct glint_pinhole *cam)
{
	return glint_pixel_filter_on(cam) ? 16 : 4;
}

/*
 * Env-map and BRDF samples a hit when the scene does not say: 32 each at
 * up to 4 hits a pixel, and 128 a pixel shared by more hits (8 each at a
 * blurred camera's 16).  A pixel's value averages its hits' samples, so
 * its noise follows their total; 32 each at 16 hits made the rig's final
 * render 4 times the time for a quarter of the noise, and overran its
 * budget threefold.
 */
int glint_scene_samples_default(int spp)
{
	int n = spp > 4 ? (int)lround(128.0 / spp) : 32;
	return n > 1 ? n : 1;
}

static const struct glint_range positive = { 0, INFINITY, 1, 0 };
static const struct glint_range any = { -INFINITY, INFINITY, 0, 0 };

static int load_camera(const char *file, json_t *o, struct glint_scene *s)
{
	static const char *const known[] = { "width",
					     "height",
					     "focal_length_mm",
					     "sensor_width_mm",
					     "pixel_pitch_um",
					     "f_number",
					     "focus_distance_m",
					     "position",
					     "look_at",
					     "up",
					     "psf_sigma_px",
					     "olpf",
					     "cfa",
					     NULL };
	double focal = 0, sensor = 0, pitch_um = 0, fnum = 0, focus = 0;
	double psf = 0;
	double pos[3] = { 0, 0, 0 }, at[3] = { 0, 0, -1 }, up[3] = { 0, 1, 0 };
	int w = 0, h = 0, ret;

	ret = glint_json_known_keys(file, "camera", o, known);
	if (!ret)
		ret = glint_json_int(file, "camera", o, "width", 1, 1, 65536,
				     &w);
	if (!ret)
		ret = glint_json_int(file, "camera", o, "height", 1, 1, 65536,
				     &h);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "focal_length_mm", 1,
					(struct glint_range){ 0, 1e5, 1, 0 },
					&focal);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "sensor_width_mm", 0,
					positive, &sensor);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "pixel_pitch_um", 0,
					positive, &pitch_um);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "f_number", 0,
					(struct glint_range){ 0, 1e3, 0, 0 },
					&fnum);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "focus_distance_m",
					0, positive, &focus);
	if (!ret)
		ret = glint_json_number(file, "camera", o, "psf_sigma_px", 0,
					(struct glint_range){ 0, 8, 0, 0 },
					&psf);
	int olpf = 0;
	if (!ret)
		ret = glint_json_bool(file, "camera", o, "olpf", &olpf);
	if (!ret)
		ret = glint_json_numbers(file, "camera", o, "position", 0, 3,
					 any, pos);
	if (!ret)
		ret = glint_json_numbers(file, "camera", o, "look_at", 0, 3,
					 any, at);
	if (!ret)
		ret = glint_json_numbers(file, "camera", o, "up", 0, 3, any,
					 up);
	if (ret < 0)
		return ret;
	if ((sensor > 0) == (pitch_um > 0))
		return glint_error_set(EINVAL,
				       "%s: camera: give exactly one of "
				       "sensor_width_mm and pixel_pitch_um",
				       file);
	double pitch_m = sensor > 0 ? sensor * 1e-3 / w : pitch_um * 1e-6;
	if (fnum > 0 && !(focus > 0))
		return glint_error_set(EINVAL,
				       "%s: camera.f_number = %g needs "
				       "camera.focus_distance_m (a number > 0)",
				       file, fnum);
	ret = glint_pinhole_init(&s->cam, w, h, focal * 1e-3, pitch_m, fnum,
				 focus, v3(pos[0], pos[1], pos[2]),
				 v3(at[0], at[1], at[2]),
				 v3(up[0], up[1], up[2]));
	if (ret < 0)
		return glint_error_prefix(ret, "%s", file);
	s->cam.psf_sigma_px = psf;
	s->cam.olpf = olpf;
	json_t *cfa = json_object_get(o, "cfa");
	if (cfa && !json_is_string(cfa))
		return glint_error_set(EINVAL,
				       "%s: camera.cfa: expected a string "
				       "(RGGB, GRBG, GBRG or BGGR)",
				       file);
	ret = glint_pinhole_set_cfa(&s->cam,
				    cfa ? json_string_value(cfa) : NULL);
	if (ret < 0)
		return glint_error_prefix(ret, "%s: camera", file);
	return 0;
}

static int load_sphere(const char *file, json_t *o, struct glint_scene *s)
{
	static const char *const known[] = { "diameter_m", "centre", "center",
					     "circle_px", NULL };
	static const char *const circle_keys[] = { "cx", "cy", "r", NULL };
	double diam = 0, c[3];
	json_t *circle = NULL;
	int ret, has_c;

	ret = glint_json_known_keys(file, "sphere", o, known);
	if (!ret)
		ret = glint_json_number(file, "sphere", o, "diameter_m", 1,
					positive, &diam);
	if (ret < 0)
		return ret;
	s->sphere_radius = diam / 2;
	const char *ckey = json_object_get(o, "center") ? "center" : "centre";
	has_c = json_object_get(o, ckey) != NULL;
	ret = glint_json_object(file, "sphere", o, "circle_px", 0, &circle);
	if (ret < 0)
		return ret;
	if (has_c == (circle != NULL))
		return glint_error_set(EINVAL,
				       "%s: sphere: give exactly one of "
				       "\"centre\" (metres) and \"circle_px\" "
				       "({cx, cy, r} in pixels)",
				       file);
	if (has_c) {
		ret = glint_json_numbers(file, "sphere", o, ckey, 1, 3, any, c);
		if (ret < 0)
			return ret;
		s->sphere_centre = v3(c[0], c[1], c[2]);
	} else {
		double cx = 0, cy = 0, r = 0;
		ret = glint_json_known_keys(file, "sphere.circle_px", circle,
					    circle_keys);
		if (!ret)
			ret = glint_json_number(file, "sphere.circle_px",
						circle, "cx", 1, any, &cx);
		if (!ret)
			ret = glint_json_number(file, "sphere.circle_px",
						circle, "cy", 1, any, &cy);
		if (!ret)
			ret = glint_json_number(file, "sphere.circle_px",
						circle, "r", 1, positive, &r);
		if (!ret)
			ret = glint_pinhole_sphere_from_circle(
				&s->cam, cx, cy, r, s->sphere_radius,
				&s->sphere_centre);
		if (ret < 0)
			return ret;
	}
	struct vec3 q = v3_sub(s->sphere_centre, s->cam.pos);
	if (v3_len(q) <= s->sphere_radius || v3_dot(q, s->cam.fwd) <= 0)
		return glint_error_set(EINVAL,
				       "%s: sphere at (%g, %g, %g) m is not in "
				       "front of the camera",
				       file, s->sphere_centre.x,
				       s->sphere_centre.y, s->sphere_centre.z);
	return 0;
}

static int load_env(const char *file, const char *dir, json_t *o,
		    struct glint_scene *s)
{
	static const char *const known[] = { "path",	"rotation_deg",
					     "scale",	"scale_sigma",
					     "sources", NULL };
	const char *p = NULL, *src = NULL;
	int ret;

	ret = glint_json_known_keys(file, "environment", o, known);
	if (!ret)
		ret = glint_json_string(file, "environment", o, "sources", 0,
					&src);
	if (!ret)
		ret = glint_json_string(file, "environment", o, "path", 1, &p);
	if (!ret)
		ret = glint_json_numbers(
			file, "environment", o, "rotation_deg", 0, 3,
			(struct glint_range){ -360, 360, 0, 0 },
			s->env_rotation);
	if (!ret)
		ret = glint_json_number(file, "environment", o, "scale", 0,
					positive, &s->env_scale);
	/* one number for every channel, or one per channel */
	json_t *sg = json_object_get(o, "scale_sigma");
	struct glint_range rel = { 0, 1, 0, 0 };
	if (!ret && json_is_array(sg))
		ret = glint_json_numbers(file, "environment", o, "scale_sigma",
					 0, 3, rel, s->env_scale_sigma);
	else if (!ret && sg) {
		ret = glint_json_number(file, "environment", o, "scale_sigma",
					0, rel, &s->env_scale_sigma[0]);
		s->env_scale_sigma[1] = s->env_scale_sigma[2] =
			s->env_scale_sigma[0];
	}
	if (ret < 0)
		return ret;
	if (p[0] == '/' || !dir[0])
		snprintf(s->env_path, sizeof(s->env_path), "%s", p);
	else
		snprintf(s->env_path, sizeof(s->env_path), "%s/%s", dir, p);
	s->env_sources_path[0] = 0;
	if (src && (src[0] == '/' || !dir[0]))
		snprintf(s->env_sources_path, sizeof(s->env_sources_path), "%s",
			 src);
	else if (src)
		snprintf(s->env_sources_path, sizeof(s->env_sources_path),
			 "%s/%s", dir, src);
	return 0;
}

static int load_render(const char *file, json_t *o, struct glint_scene *s)
{
	static const char *const known[] = { "samples_per_pixel",
					     "light_samples", "brdf_samples",
					     NULL };
	int ret = glint_json_known_keys(file, "render", o, known);

	if (!ret)
		ret = glint_json_int(file, "render", o, "samples_per_pixel", 0,
				     1, 4096, &s->spp);
	if (!ret)
		ret = glint_json_int(file, "render", o, "light_samples", 0, 0,
				     1 << 16, &s->light_samples);
	if (!ret)
		ret = glint_json_int(file, "render", o, "brdf_samples", 0, 0,
				     1 << 16, &s->brdf_samples);
	return ret;
}

int glint_scene_from_json(const char *file, const char *dir, json_t *root,
			  struct glint_scene *s)
{
	static const char *const known[] = { "units",	    "camera", "sphere",
					     "environment", "render", NULL };
	json_t *cam, *sph, *env, *rnd;
	const char *units = NULL;
	int ret;

	glint_scene_defaults(s);
	ret = glint_json_known_keys(file, "", root, known);
	if (!ret)
		ret = glint_json_string(file, "", root, "units", 0, &units);
	if (!ret && units && strcmp(units, "metres") && strcmp(units, "meters"))
		ret = glint_error_set(EINVAL,
				      "%s: units = \"%s\": expected \"metres\"",
				      file, units);
	if (!ret)
		ret = glint_json_object(file, "", root, "camera", 1, &cam);
	if (!ret)
		ret = glint_json_object(file, "", root, "sphere", 1, &sph);
	if (!ret)
		ret = glint_json_object(file, "", root, "environment", 1, &env);
	if (!ret)
		ret = glint_json_object(file, "", root, "render", 0, &rnd);
	if (!ret)
		ret = load_camera(file, cam, s);
	if (!ret)
		ret = load_sphere(file, sph, s);
	if (!ret)
		ret = load_env(file, dir, env, s);
	/* unless the file says: glint_scene_spp_default(), and the samples
	 * a hit for those hits (glint_scene_samples_default()) */
	s->spp = 0;
	s->light_samples = s->brdf_samples = -1;
	if (!ret && rnd)
		ret = load_render(file, rnd, s);
	if (!ret && !s->spp)
		s->spp = glint_scene_spp_default(&s->cam);
	if (s->light_samples < 0)
		s->light_samples = glint_scene_samples_default(s->spp);
	if (s->brdf_samples < 0)
		s->brdf_samples = glint_scene_samples_default(s->spp);
	if (!ret && s->light_samples + s->brdf_samples == 0)
		ret = glint_error_set(EINVAL,
				      "%s: render: light_samples + "
				      "brdf_samples is 0: expected at least 1",
				      file);
	return ret;
}

int glint_scene_load(const char *path, struct glint_scene *s)
{
	char dir[GLINT_PATH_MAX];
	json_t *root;
	int ret = glint_json_load(path, &root);

	if (ret < 0)
		return ret;
	snprintf(dir, sizeof(dir), "%s", path);
	ret = glint_scene_from_json(path, dirname(dir), root, s);
	json_decref(root);
	return ret;
}
