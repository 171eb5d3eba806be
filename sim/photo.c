/* SPDX-License-Identifier: MIT */
#include "photo.h"

#include "reference.h"
#include "sensor.h"

#include "core/error.h"
#include "fit/scene/envmap.h"

#include <errno.h>
#include <stddef.h>

/* One exposure for the diffuse body through the sensor model: photo
 * becomes the radiance the camera would report, weight its 1/variance. */
static int expose(struct glint_image *photo, struct glint_image **weight)
{
	struct glint_sensor s;
	size_t n = (size_t)photo->width * photo->height * 3;
	struct glint_image *dn = glint_image_new(photo->width, photo->height);
	struct glint_image *w = glint_image_new(photo->width, photo->height);
	int ret = dn && w ? 0 : glint_error_set(ENOMEM, "out of memory");

	glint_sensor_default(&s);
	double mean = 0;
	for (size_t i = 0; i < n; i++)
		mean += photo->data[i];
	mean /= (double)n;
	s.exposure_s = glint_sensor_exposure_for(&s, mean, 0.1);
	if (!ret)
		ret = glint_sensor_capture(&s, photo, dn);
	if (!ret)
		ret = glint_sensor_to_radiance(&s, dn, photo, w);
	glint_image_free(dn);
	if (ret < 0) {
		glint_image_free(w);
		return ret;
	}
	*weight = w;
	return 0;
}

int glint_sim_photo(const struct glint_scene *scene,
		    const struct glint_model *model, const double *params,
		    const struct glint_sim_photo_opts *o,
		    struct glint_image **photo, struct glint_image **weight)
{
	struct glint_envmap *env = NULL;
	struct glint_reference_opts ro;
	struct glint_image *img = NULL, *w = NULL;
	int ret;

	*photo = NULL;
	if (weight)
		*weight = NULL;
	ret = glint_envmap_load(scene->env_path, scene->env_rotation,
				scene->env_scale, scene->env_srgb, &env);
	if (ret < 0)
		return ret;
	img = glint_image_new(scene->cam.width, scene->cam.height);
	if (!img) {
		ret = glint_error_set(ENOMEM, "out of memory");
		goto out;
	}
	glint_reference_default_opts(&ro);
	ro.spp = glint_model_is_transparent(model)
			 ? 64
			 : 4; /* its paths branch at random */
	ro.nthreads = o->nthreads;
	ret = glint_reference_render(scene, env, model, params, &ro, img);
	if (ret == 0 && o->noise)
		ret = expose(img, &w);
out:
	glint_envmap_free(env);
	if (ret < 0) {
		glint_image_free(img);
		return ret;
	}
	*photo = img;
	if (weight)
		*weight = w;
	else
		glint_image_free(w);
	return 0;
}
