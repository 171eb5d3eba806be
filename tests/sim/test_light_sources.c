/* SPDX-License-Identifier: MIT */
/*
 * A lamp whose flux the probe knows to 15 % (fit/light_sources.c).  The
 * photo: yellow plastic (Table 1) by the reference renderer under the
 * lamp-fill lighting class (sim/light_class.h) with its lamp 15 % brighter
 * than the map the fit is given.  Fitted with the map alone, the
 * diffuse albedos come out about 14 % high and their intervals miss the
 * truth; fitted with the lamp stated as a source whose flux is known to
 * 15 %, every truth is inside its interval, the lamp's stated part of
 * diffuse.r's error is the shift the 15 % made (within 25 %), and a
 * finding names the lamp as what limits it.  In a joint fit of the photo
 * twice with the lamp stated on the second photo's map, its part is half
 * as large (it moves half the rows).  A clipped source is said to be out
 * of the intervals.  The scene's environment.sources is read by the job (a
 * probe's env-sources.json), the bad entry named.
 */
#include "test.h"

#include "core/error.h"
#include "core/image.h"
#include "fit/fit.h"
#include "fit/job.h"
#include "sim/light_class.h"
#include "sim_scene.h"

#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[] = "/tmp/glint-sources-XXXXXX";

/* The lamp of lamp-fill: azimuth -150, elevation 25 degrees (sim/
 * light_class.c), 1.5 degrees in radius. */
static struct vec3 lamp_dir(void)
{
	return glint_latlong_uv_to_dir(0.5 - 150.0 / 360, (90 - 25.0) / 180);
}

/* Texel (x, y)'s solid angle when it lies within deg degrees of the
 * lamp, else 0. */
static double lamp_texel(const struct glint_image *map, int x, int y,
			 double deg)
{
	double th = M_PI / map->height;
	struct vec3 t = glint_latlong_uv_to_dir((x + 0.5) / map->width,
						(y + 0.5) / map->height);
	if (v3_dot(t, lamp_dir()) < cos(deg * M_PI / 180))
		return 0;
	return 2 * M_PI / map->width * th * sin((y + 0.5) * th);
}

static int write_maps(char *plain, char *bright, size_t n)
{
	struct glint_image *map = NULL;
	CHECK(glint_sim_light_class("lamp-fill", 1024, &map) == 0, "%s",
	      glint_error_msg());
	if (!map)
		return -1;
	snprintf(plain, n, "%s/map.exr", tmpdir);
	snprintf(bright, n, "%s/bright.exr", tmpdir);
	CHECK(glint_image_write(plain, map, NULL) == 0, "%s",
	      glint_error_msg());
	for (int y = 0; y < map->height; y++)
		for (int x = 0; x < map->width; x++) {
			if (!lamp_texel(map, x, y, 4))
				continue;
			float *v = map->data + 3 * ((size_t)y * map->width + x);
			for (int c = 0; c < 3; c++)
				v[c] *= 1.15f;
		}
	CHECK(glint_image_write(bright, map, NULL) == 0, "%s",
	      glint_error_msg());
	glint_image_free(map);
	return test_failures ? -1 : 0;
}

/* The lamp's flux per channel in the map at path: its texels within 3
 * degrees, times their solid angle. */
static void lamp_flux(const char *path, double flux[3])
{
	struct glint_image *map = NULL;
	flux[0] = flux[1] = flux[2] = 0;
	CHECK(glint_image_read(path, &map) == 0, "%s", glint_error_msg());
	for (int y = 0; map && y < map->height; y++)
		for (int x = 0; x < map->width; x++) {
			double dw = lamp_texel(map, x, y, 3);
			for (int c = 0; c < 3; c++)
				flux[c] += glint_image_px(map, x, y)[c] * dw;
		}
	printf("the lamp's flux %.4f %.4f %.4f\n", flux[0], flux[1], flux[2]);
	glint_image_free(map);
}

/* How many true values lie outside their intervals. */
static int misses(const struct glint_fit_result *res,
		  const struct glint_model *m, const double *truth,
		  const char *what)
{
	int out = 0;
	for (int k = 0; k < m->nparams; k++) {
		int in = truth[k] >= res->unc.lo[k] &&
			 truth[k] <= res->unc.hi[k];
		printf("  %-6s %-11s %.4f [%.4f, %.4f] truth %.4f%s\n", what,
		       m->params[k].name, res->p[k], res->unc.lo[k],
		       res->unc.hi[k], truth[k], in ? "" : "  MISSED");
		out += !in;
	}
	return out;
}

static int said(const struct glint_fit_result *res, const char *what)
{
	json_t *u = glint_fit_uncertainty_json(res), *f;
	size_t i;
	int found = 0;
	json_array_foreach(json_object_get(u, "findings"), i, f)
	{
		if (strstr(json_string_value(f), what)) {
			printf("  finding: %s\n", json_string_value(f));
			found = 1;
		}
	}
	json_decref(u);
	return found;
}

/* Writes text as the sources file src, then loads the scene's job into
 * *job (the caller unloads it); returns the load's result, -1 where src
 * could not be written. */
static int load_with_sources(const char *scene, const char *photo,
			     const char *src, const char *text,
			     struct glint_fit_job *job)
{
	FILE *f = fopen(src, "w");
	CHECK(f != NULL, "%s", src);
	memset(job, 0, sizeof(*job));
	if (!f)
		return -1;
	fputs(text, f);
	fclose(f);
	job->scene_path = scene;
	job->photo_path = photo;
	return glint_fit_job_load(job, NULL);
}

/* The scene file's environment.sources through the job: the lamp read
 * with its sigma; a source without a flux named; the probe's resolution
 * read, absent taken as unknown (-1), a negative one named. */
static void job_reads_sources(const char *map)
{
	char scene[600], src[600], photo[600];
	struct vec3 d = lamp_dir();
	snprintf(scene, sizeof(scene), "%s/scene.json", tmpdir);
	snprintf(src, sizeof(src), "%s/env-sources.json", tmpdir);
	snprintf(photo, sizeof(photo), "%s/photo.exr", tmpdir);
	FILE *f = fopen(scene, "w");
	CHECK(f != NULL, "%s", scene);
	if (!f)
		return;
	fprintf(f,
		"{\"camera\": {\"width\": 192, \"height\": 192, "
		"\"focal_length_mm\": 100, \"sensor_width_mm\": 36},\n"
		" \"sphere\": {\"diameter_m\": 0.1, \"centre\": [0, 0, "
		"-0.5]},\n"
		" \"environment\": {\"path\": \"%s\", \"sources\": "
		"\"env-sources.json\"}}\n",
		map);
	fclose(f);
	for (int bad = 0; bad < 2; bad++) {
		char text[400];
		snprintf(text, sizeof(text),
			 "{\"sources\": [{\"direction\": [%.9f, %.9f, %.9f], "
			 "\"flux\": [0.1, 0.08, 0.05], %s\"size_deg\": 0.8, "
			 "\"pixel_deg\": 1.2, \"saturated\": false}]}\n",
			 d.x, d.y, d.z,
			 bad ? "" : "\"flux_sigma\": [0.015, 0.012, 0.0075], ");
		struct glint_fit_job job;
		int ret = load_with_sources(scene, photo, src, text, &job);
		if (bad) {
			CHECK(ret < 0 &&
				      strstr(glint_error_msg(), "sources[0]") &&
				      strstr(glint_error_msg(), "flux_sigma"),
			      "a source without flux_sigma: %s",
			      ret < 0 ? glint_error_msg() : "accepted");
		} else {
			CHECK(ret == 0, "%s", glint_error_msg());
			CHECK(job.nsources == 1 &&
				      job.sources[0].flux[0] == 0.1 &&
				      job.sources[0].flux_sigma[0] == 0.015 &&
				      fabs(job.sources[0].radius_deg - 2.4) <
					      1e-9 &&
				      fabs(job.sources[0].dir[1] - d.y) <
					      1e-6 &&
				      job.map_pixel_deg == -1,
			      "read %d sources: sigma %g, radius %g",
			      job.nsources, job.sources[0].flux_sigma[0],
			      job.sources[0].radius_deg);
		}
		glint_fit_job_unload(&job);
	}
	/* the probe's resolution, and a bad one named */
	for (int bad = 0; bad < 2; bad++) {
		struct glint_fit_job job;
		int ret = load_with_sources(
			scene, photo, src,
			bad ? "{\"map_pixel_deg\": -3, \"sources\": []}\n"
			    : "{\"map_pixel_deg\": 1.93, \"sources\": []}\n",
			&job);
		if (bad)
			CHECK(ret < 0 && strstr(glint_error_msg(),
						"map_pixel_deg"),
			      "a negative map_pixel_deg: %s",
			      ret < 0 ? glint_error_msg() : "accepted");
		else
			CHECK(ret == 0 && job.map_pixel_deg == 1.93 &&
				      job.nsources == 0,
			      "map_pixel_deg %g: %s", job.map_pixel_deg,
			      ret < 0 ? glint_error_msg() : "");
		glint_error_clear();
		glint_fit_job_unload(&job);
	}
}

int main(void)
{
	char plain[600], bright[600];
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];
	struct glint_scene sc;
	struct glint_renderer r;

	CHECK(mkdtemp(tmpdir) != NULL, "mkdtemp");
	CHECK(glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
				  "yellow-plastic", &m, truth) == 0,
	      "%s", glint_error_msg());
	if (test_failures || write_maps(plain, bright, sizeof(plain)) < 0)
		return test_result();

	/* the photo under the brighter lamp */
	sim_scene_192(&sc, bright, 0);
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	struct glint_image *photo =
		test_failures ? NULL : sim_photo(&r, m, truth);
	glint_renderer_release(&r);
	CHECK(photo != NULL, "%s", glint_error_msg());
	if (!photo)
		return test_result();
	char path[600];
	snprintf(path, sizeof(path), "%s/photo.exr", tmpdir);
	CHECK(glint_image_write(path, photo, NULL) == 0, "%s",
	      glint_error_msg());

	/* fitted under the map as the probe gave it */
	sim_scene_192(&sc, plain, 0);
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	struct glint_fit_opts o;
	struct glint_fit_result alone, with;
	glint_fit_default_opts(&o);
	CHECK(glint_fit(&r, m, photo, NULL, &o, &alone) == 0, "%s",
	      glint_error_msg());
	struct vec3 d = lamp_dir();
	struct glint_fit_light_source lamp = {
		.dir = { d.x, d.y, d.z },
		.radius_deg = 3,
	};
	lamp_flux(plain, lamp.flux);
	for (int c = 0; c < 3; c++)
		lamp.flux_sigma[c] = 0.15 * lamp.flux[c];
	o.sources = &lamp;
	o.nsources = 1;
	CHECK(glint_fit(&r, m, photo, NULL, &o, &with) == 0, "%s",
	      glint_error_msg());
	if (test_failures)
		return test_result();
	int ma = misses(&alone, m, truth, "alone");
	int mw = misses(&with, m, truth, "lamp");
	CHECK(ma >= 1, "the map alone: every truth inside its interval, so "
		       "the lamp's 15 %% tests nothing");
	CHECK(mw == 0, "with the lamp's flux uncertainty: %d truths outside",
	      mw);
	/* The lamp lights most of the diffuse term: a 15 % brighter lamp
	 * moved diffuse.r by about its stated part (the first-order
	 * propagation checked against what the error does). */
	double shift = alone.p[0] - truth[0], part = with.source_stderr[0][0];
	printf("diffuse.r: moved %.4f by the lamp's 15 %%, its stated part "
	       "%.4f\n",
	       shift, part);
	CHECK(with.nsources == 1 && part > 0 &&
		      fabs(part - fabs(shift)) < 0.25 * part,
	      "the lamp's part of diffuse.r %g, the shift it made %g", part,
	      shift);
	CHECK(said(&with, "diffuse.r is limited by the light: light source 1"),
	      "no finding names the lamp as what limits diffuse.r");

	/* A joint fit of the photo twice, the lamp stated on the second
	 * photo's map only: its error moves half the rows, and so the
	 * answer by half as much; the finding names the photo. */
	struct glint_fit_view two[2] = { { &r, photo, NULL },
					 { &r, photo, NULL } };
	struct glint_fit_result joint;
	lamp.view = 1;
	CHECK(glint_fit_views(two, 2, m, &o, &joint) == 0, "%s",
	      glint_error_msg());
	double half = test_failures ? 0 : joint.source_stderr[0][0];
	printf("joint fit, the lamp on photo 2 only: its part of diffuse.r "
	       "%.4f (one photo's %.4f)\n",
	       half, part);
	CHECK(joint.nsources == 1 && fabs(half - 0.5 * part) < 0.125 * part,
	      "joint fit: the lamp's part %g, half the one photo's %g", half,
	      0.5 * part);
	CHECK(said(&joint, "photo 2's light source 1"),
	      "no finding names the photo whose lamp it is");
	lamp.view = 0;

	/* clipped: no sigma to carry, and said */
	lamp.saturated = 1;
	struct glint_fit_result clip;
	o.max_pixels = 1024;
	CHECK(glint_fit(&r, m, photo, NULL, &o, &clip) == 0, "%s",
	      glint_error_msg());
	CHECK(!test_failures && clip.source_stderr[0][0] == 0 &&
		      said(&clip, "is clipped in the probe"),
	      "a clipped source is not said to be outside the intervals");
	glint_renderer_release(&r);
	glint_image_free(photo);

	job_reads_sources(plain);
	test_remove_dir(tmpdir);
	return test_result();
}
