/* SPDX-License-Identifier: MIT */
#include "scenario.h"

#include "core/error.h"
#include "core/json.h"

int glint_sim_scenario_load(const char *path, json_t **doc)
{
	static const char *const top[] = { "camera", "presses", NULL };
	json_t *d, *cam, *presses;
	int ret;

	*doc = NULL;
	ret = glint_json_load(path, &d);
	if (ret < 0)
		return ret;
	ret = glint_json_known_keys(path, "", d, top);
	cam = json_object_get(d, "camera");
	presses = json_object_get(d, "presses");
	if (!ret && cam && !json_is_object(cam))
		ret = glint_error_set(EINVAL,
				      "%s: camera: expected an object of the "
				      "sim camera's options",
				      path);
	if (!ret && presses && !json_is_array(presses))
		ret = glint_error_set(EINVAL,
				      "%s: presses: expected an array of "
				      "{at_s, hold_s, bounces}",
				      path);
	if (ret < 0) {
		json_decref(d);
		return ret;
	}
	*doc = d;
	return 0;
}
