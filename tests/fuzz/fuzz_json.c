/* SPDX-License-Identifier: MIT */
/* glint's JSON files: the same bytes as a scene, a material (or a fit's
 * params.json), and a rig file. */
#include "fuzz.h"

#include "board/rig.h"
#include "fit/brdf/model.h"
#include "fit/scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_path(data, size);
	struct glint_scene scene;
	glint_scene_load(path, &scene);
	const struct glint_model_ops *model;
	double params[GLINT_MAX_PARAMS];
	glint_material_load(path, NULL, &model, params);
	glint_material_load(path, "fuzz", &model, params);
	struct glint_rig rig;
	glint_rig_load(path, &rig);
	glint_rig_free(&rig);
	return 0;
}
