/* SPDX-License-Identifier: MIT */
/*
 * The job's inputs: the scene, the photo and its weights read, and the
 * sphere's window cut from a frame-sized photo (job.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "fit/job.h"
#include "fit/job_internal.h"

#include "fit/ladder.h"
#include "fit/misfit.h"
#include "fit/select.h"
#include "export/export.h"
#include "fit/render/compare.h"
#include "core/clock.h"
#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/path.h"
#include "core/formats.h"
#include "core/json.h"
#include "core/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CROP_MIN_SAVING 0.25

/*
 * The window around the scene sphere's silhouette in the camera's frame:
 * the ellipse's extent plus a margin (lens blur at the sphere's nearest
 * depth, a tenth of the radius for the compare image's context, 8
 * pixels).  Returns 1 when it saves at least CROP_MIN_SAVING of the
 * frame, else 0.
 */
static int sphere_window(const struct glint_fit_job *job,
			 struct glint_image_window *win)
{
	const struct glint_pinhole *cam = &job->scene.cam;
	int fw = cam->width, fh = cam->height;
	struct glint_ellipse e;

	if (job->window.frame_width)
		return 0;
	if (glint_pinhole_sphere_ellipse(cam, job->scene.sphere_centre,
					 job->scene.sphere_radius, &e) < 0) {
		glint_error_clear(); /* the fit reports what is wrong */
		return 0;
	}
	double ca = cos(e.angle), sa = sin(e.angle);
	double hx = sqrt(e.a * e.a * ca * ca + e.b * e.b * sa * sa);
	double hy = sqrt(e.a * e.a * sa * sa + e.b * e.b * ca * ca);
	double z =
		v3_dot(v3_sub(job->scene.sphere_centre, cam->pos), cam->fwd) -
		job->scene.sphere_radius;
	double blur = 0;
	if (cam->aperture_radius > 0 && z > 0 && cam->focus_distance > 0)
		blur = cam->aperture_radius * cam->fpx *
		       fabs(1 / z - 1 / cam->focus_distance);
	double margin = 8 + 0.1 * fmax(e.a, e.b) + blur;
	int x0 = (int)floor(fmax(0, e.cx - hx - margin));
	int y0 = (int)floor(fmax(0, e.cy - hy - margin));
	int x1 = (int)ceil(fmin(fw, e.cx + hx + margin));
	int y1 = (int)ceil(fmin(fh, e.cy + hy + margin));
	if (x1 - x0 < 1 || y1 - y0 < 1 ||
	    (double)(x1 - x0) * (y1 - y0) >
		    (1 - CROP_MIN_SAVING) * (double)fw * fh)
		return 0;
	*win = (struct glint_image_window){ x0, y0, x1 - x0, y1 - y0 };
	return 1;
}

/* The camera shifted to the window, and job->window set. */
static void apply_window(struct glint_fit_job *job,
			 const struct glint_image_window *win)
{
	struct glint_pinhole *cam = &job->scene.cam;
	int fw = cam->width, fh = cam->height;

	cam->width = win->width;
	cam->height = win->height;
	cam->cx -= win->x;
	cam->cy -= win->y;
	cam->frame_x = win->x;
	cam->frame_y = win->y;
	cam->frame_width = fw;
	job->window.x = win->x;
	job->window.y = win->y;
	job->window.frame_width = fw;
	job->window.frame_height = fh;
	glint_log_info("fitting the %dx%d window at (%d, %d) around the "
		       "sphere: %.0f%% of the %dx%d frame",
		       win->width, win->height, win->x, win->y,
		       100.0 * win->width * win->height / ((double)fw * fh), fw,
		       fh);
}

/* The photo and weights read whole. */
static int read_whole(struct glint_fit_job *job, const char *weights_path)
{
	int ret = glint_image_read(job->photo_path, &job->photo);

	if (ret == 0 && weights_path)
		ret = glint_image_read(weights_path, &job->weight);
	return ret;
}

static int read_photo(struct glint_fit_job *job, const char *weights_path);

/*
 * A probe's sources file (capture/probe/probe_sources.c writes it): each
 * source's direction in the map's frame, flux and its sigma per channel,
 * its size and the probe pixel's angle there, whether it clipped.  Its
 * texels in the map are those within 3 times its RMS radius or 2 probe
 * pixels, whichever is larger.  At most GLINT_FIT_MAX_SOURCES, the
 * brightest (the file lists them brightest first); a source whose flux
 * is not positive is skipped.
 */
static int read_sources(const char *path, struct glint_fit_light_source *out,
			int *n, double *map_pixel_deg)
{
	json_t *doc = NULL, *arr, *e;
	size_t i;
	int ret = glint_json_load(path, &doc);

	*n = 0;
	if (ret < 0)
		return ret;
	*map_pixel_deg = -1; /* absent: a probe of unknown resolution */
	ret = glint_json_number(path, "", doc, "map_pixel_deg", 0,
				(struct glint_range){ 0, 180, 0, 0 },
				map_pixel_deg);
	if (ret < 0) {
		json_decref(doc);
		return ret;
	}
	arr = json_object_get(doc, "sources");
	if (!json_is_array(arr)) {
		json_decref(doc);
		return glint_error_set(EINVAL, "%s: no \"sources\" array",
				       path);
	}
	json_array_foreach(arr, i, e)
	{
		if (*n >= GLINT_FIT_MAX_SOURCES)
			break;
		struct glint_fit_light_source s = { 0 };
		double flux[3], sigma[3], size = 0, pix = 0;
		char where[48];
		int sat = 0;
		snprintf(where, sizeof(where), "sources[%zu]", i);
		struct glint_range any = { -1, 1, 0, 0 },
				   pos = { 0, INFINITY, 0, 0 };
		ret = glint_json_numbers(path, where, e, "direction", 1, 3, any,
					 s.dir);
		if (!ret)
			ret = glint_json_numbers(path, where, e, "flux", 1, 3,
						 pos, flux);
		if (!ret)
			ret = glint_json_numbers(path, where, e, "flux_sigma",
						 1, 3, pos, sigma);
		if (!ret)
			ret = glint_json_number(path, where, e, "size_deg", 0,
						pos, &size);
		if (!ret)
			ret = glint_json_number(path, where, e, "pixel_deg", 0,
						pos, &pix);
		if (!ret)
			ret = glint_json_bool(path, where, e, "saturated",
					      &sat);
		if (ret < 0)
			break;
		double len = sqrt(s.dir[0] * s.dir[0] + s.dir[1] * s.dir[1] +
				  s.dir[2] * s.dir[2]);
		if (!(len > 0.5) || !(flux[0] + flux[1] + flux[2] > 0))
			continue;
		for (int c = 0; c < 3; c++) {
			s.dir[c] /= len;
			s.flux[c] = flux[c];
			s.flux_sigma[c] = sigma[c];
		}
		s.radius_deg = fmax(3 * size, 2 * pix);
		s.saturated = sat;
		out[(*n)++] = s;
	}
	json_decref(doc);
	return ret < 0 ? ret : 0;
}

int glint_fit_job_load(struct glint_fit_job *job, const char *weights_path)
{
	int ret = glint_scene_load(job->scene_path, &job->scene);

	job->weights_path = weights_path;
	job->photo = job->weight = NULL;
	job->nsources = 0;
	job->map_pixel_deg = 0;
	if (ret == 0)
		ret = glint_radiance_check(job->photo_path, job->srgb);
	if (ret < 0)
		return ret;
	ret = read_photo(job, weights_path);
	/* NaN or infinity in the photo, or a weight that is not a finite
	 * non-negative number, is a broken file, not pixels to skip */
	if (ret == 0)
		ret = glint_image_check_finite_at(job->photo, job->photo_path,
						  0, job->window.x,
						  job->window.y);
	if (ret == 0 && job->weight)
		ret = glint_image_check_finite_at(job->weight, weights_path, 1,
						  job->window.x, job->window.y);
	if (ret == 0 && glint_image_encoded(job->photo_path))
		glint_image_from_srgb(job->photo_path, job->photo);
	if (ret == 0 && job->scene.env_sources_path[0])
		ret = read_sources(job->scene.env_sources_path, job->sources,
				   &job->nsources, &job->map_pixel_deg);
	return ret;
}

/* The photo (and weights): the sphere's window of a frame-sized one, or
 * whole. */
static int read_photo(struct glint_fit_job *job, const char *weights_path)
{
	struct glint_image_window win;
	int cp = 0, cw = 0, ret;

	if (!sphere_window(job, &win))
		return read_whole(job, weights_path);
	/* Only the window of a frame-sized photo and weights: a 12 MP
	 * frame's EXR is never held whole. */
	int fw = job->scene.cam.width, fh = job->scene.cam.height;
	ret = glint_image_read_window(job->photo_path, fw, fh, &win,
				      &job->photo, &cp);
	if (ret == 0 && weights_path)
		ret = glint_image_read_window(weights_path, fw, fh, &win,
					      &job->weight, &cw);
	if (ret < 0)
		return ret;
	if (cp && (!weights_path || cw)) {
		apply_window(job, &win);
		return 0;
	}
	/* An image of another size: both whole, as the fit expects to say
	 * what is wrong with them. */
	glint_fit_job_unload(job);
	return read_whole(job, weights_path);
}

int glint_fit_job_crop(struct glint_fit_job *job)
{
	const struct glint_pinhole *cam = &job->scene.cam;
	struct glint_image_window win;

	if (!job->photo || job->photo->width != cam->width ||
	    job->photo->height != cam->height ||
	    (job->weight && (job->weight->width != cam->width ||
			     job->weight->height != cam->height)) ||
	    !sphere_window(job, &win))
		return 0;
	struct glint_image *p = glint_image_crop(job->photo, win.x, win.y,
						 win.width, win.height);
	struct glint_image *w =
		job->weight ? glint_image_crop(job->weight, win.x, win.y,
					       win.width, win.height)
			    : NULL;
	if (!p || (job->weight && !w)) {
		glint_image_free(p);
		glint_image_free(w);
		return glint_error_set(ENOMEM, "out of memory");
	}
	glint_image_free(job->photo);
	glint_image_free(job->weight);
	job->photo = p;
	job->weight = w;
	apply_window(job, &win);
	return 0;
}

void glint_fit_job_unload(struct glint_fit_job *job)
{
	glint_image_free(job->photo);
	glint_image_free(job->weight);
	job->photo = job->weight = NULL;
}
