/* SPDX-License-Identifier: MIT */
/* One render of a material under a scene, written to files (glint render,
 * glint demo). */
#include "render_job.h"

#include "render.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"

#include <math.h>

static json_t *vec_json(struct vec3 v)
{
	return json_pack("[f,f,f]", v.x, v.y, v.z);
}

int glint_render_job_run(const struct glint_render_job *job, json_t **result)
{
	struct glint_renderer r;
	struct glint_progress prog;
	struct glint_image *img = NULL, *cov = NULL;
	const struct glint_scene *sc = &job->scene;
	int ret;

	*result = NULL;
	glint_progress_start(&prog, "trace", sc->cam.height);
	ret = glint_renderer_init(&r, sc, job->nthreads, &prog);
	glint_progress_finish(&prog);
	if (ret < 0)
		return ret;
	img = glint_image_new(sc->cam.width, sc->cam.height);
	if (job->out_coverage)
		cov = glint_image_new(sc->cam.width, sc->cam.height);
	if (!img || (job->out_coverage && !cov)) {
		ret = -ENOMEM;
		goto out;
	}
	struct glint_shade_opts so = {
		.light_samples = sc->light_samples,
		.brdf_samples = sc->brdf_samples,
		.background = job->background,
		.nthreads = job->nthreads,
		.progress = &prog,
	};
	double t0 = glint_clock_monotonic();
	glint_progress_start(&prog, "shade", sc->cam.height);
	ret = glint_renderer_shade(&r, job->model, job->params, &so, img, cov);
	glint_progress_finish(&prog);
	double shade_s = glint_clock_monotonic() - t0;
	if (ret < 0)
		goto out;
	ret = glint_image_check_finite(img, "rendered image", 1);
	if (ret < 0)
		goto out;
	struct glint_write_opts wo = { .exr_half = job->half,
				       .exposure = job->exposure,
				       .auto_expose = isnan(job->exposure) };
	ret = glint_image_write(job->out_exr, img, &wo);
	if (!ret && job->out_png)
		ret = glint_image_write(job->out_png, img, &wo);
	if (!ret && cov)
		ret = glint_image_write(job->out_coverage, cov, &wo);
	if (ret < 0)
		goto out;
	struct glint_ellipse el;
	glint_pinhole_sphere_ellipse(&sc->cam, sc->sphere_centre,
				     sc->sphere_radius, &el);
	*result = json_pack(
		"{s:s,s:s?,s:s?,s:i,s:i,s:i,s:i,s:i,s:o,s:o,s:{s:f,s:f,s:f,"
		"s:f},s:s,s:f,s:f,s:f}",
		"output", job->out_exr, "png", job->out_png, "coverage",
		job->out_coverage, "width", sc->cam.width, "height",
		sc->cam.height, "samples_per_pixel", sc->spp, "light_samples",
		sc->light_samples, "brdf_samples", sc->brdf_samples, "material",
		glint_material_to_json(job->model, job->params),
		"sphere_centre_m", vec_json(sc->sphere_centre),
		"sphere_image_px", "cx", el.cx, "cy", el.cy, "a", el.a, "b",
		el.b, "environment", sc->env_path, "trace_seconds",
		r.trace_seconds, "shade_seconds", shade_s, "png_exposure_ev",
		job->out_png
			? (isnan(job->exposure) ? glint_png_auto_exposure(img)
						: job->exposure)
			: 0.0);
out:
	glint_image_free(img);
	glint_image_free(cov);
	glint_renderer_release(&r);
	return ret;
}
