/* SPDX-License-Identifier: MIT */
/*
 * The main job on the simulated rig, with no arguments: a sphere of a
 * Table-1 material is "photographed" under a real environment map by the
 * simulator (the independent reference renderer, optionally through the
 * sensor model), then fitted; true and recovered values are printed.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"
#include "fit/job.h"

#include "core/output.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"
#include "sim/light_class.h"
#include "sim/photo.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

void cmd_demo_help(void)
{
	printf("usage: glint demo [--material NAME] [--light CLASS] [--out "
	       "DIR] "
	       "[--noise]\n                  [--force] [--json]\n"
	       "\n"
	       "The whole job on the simulated rig: the simulator photographs "
	       "a 10 cm sphere of\na material from the paper's Table 1 "
	       "(default yellow-plastic) under the\nembedded Venice-sunset "
	       "environment map (Poly Haven, CC0) with its reference\n"
	       "renderer, then glint fits the Torrance-Sparrow model to that "
	       "photo with the\npaper's three-pass method and prints true "
	       "against recovered values.\nWrites DIR/photo.exr and "
	       "DIR/fit/{report.html, params.json, render.exr, "
	       "compare.png}\n(DIR "
	       "defaults to ./demo-out).\n"
	       "\n"
	       "  --material NAME  satin-paint, semi-gloss-paint, "
	       "matte-paint, yellow-plastic,\n"
	       "                   teflon, nylon, silver, green-acrylic, "
	       "aluminium-bronze,\n"
	       "                   copper, nickel, blue-quartz, "
	       "purple-quartz (transparent)\n"
	       "  --light CLASS    photograph it under a procedural lighting "
	       "class instead:\n"
	       "                   window-room, softbox-studio, overcast, "
	       "sun-sky, lamp-fill,\n"
	       "                   night-lamps (docs/scene.md); the map is "
	       "written as DIR/light.exr\n"
	       "  --method M       three-pass (default), naive, varpro\n"
	       "  --noise          a single 12-bit exposure with shot and "
	       "read noise instead\n"
	       "                   of a noise-free HDR photo (saturated "
	       "pixels get weight 0)\n"
	       "  --out DIR        output folder (created if missing)\n"
	       "  --force          replace a previous demo's photo and fit "
	       "there (refused\n"
	       "                   without it)\n"
	       "  --threads N      worker threads (default: all CPUs)\n"
	       "  --json           print the fit's params.json plus the "
	       "truth on stdout\n"
	       "  -q, --quiet      no progress or info messages\n");
}

int cmd_demo(int argc, char **argv)
{
	const char *material = "yellow-plastic", *dir = "demo-out",
		   *light = NULL;
	char scene_path[GLINT_PATH_MAX], table[GLINT_PATH_MAX];
	char photo_path[GLINT_PATH_MAX], fit_dir[GLINT_PATH_MAX];
	char light_path[GLINT_PATH_MAX];
	struct glint_fit_job job = { 0 };
	const struct glint_model *model;
	double truth[GLINT_MAX_PARAMS];
	int noise = 0, method = -1, force = 0, ret;

	glint_fit_default_opts(&job.opts);
	const struct cmd_opt opts[] = {
		CMD_STRING("material", 'm', &material),
		CMD_STRING("light", 0, &light),
		CMD_STRING("output", 'o', &dir),
		CMD_CHOICE("method", &method, glint_fit_method_names),
		CMD_FLAG("noise", 0, &noise),
		CMD_FLAG("force", 0, &force),
		CMD_INT("threads", &job.nthreads, 0, 256),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("demo", cmd_demo_help, opts, argc, argv, &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json;
	if (method >= 0)
		job.opts.method = (enum glint_fit_method)method;
	if (a.argc != 0)
		return cmd_usage_error("demo", "unexpected argument '%s'",
				       a.argv[0]);
	if (glint_path_join(scene_path, sizeof(scene_path), glint_data_dir(),
			    "demo-scene.json") < 0 ||
	    glint_path_join(table, sizeof(table), glint_data_dir(),
			    "paper-table1.json") < 0 ||
	    glint_path_join(photo_path, sizeof(photo_path), dir, "photo.exr") <
		    0 ||
	    glint_path_join(fit_dir, sizeof(fit_dir), dir, "fit") < 0 ||
	    glint_path_join(light_path, sizeof(light_path), dir, "light.exr") <
		    0 ||
	    glint_scene_load(scene_path, &job.scene) < 0 ||
	    glint_material_load(table, material, &model, truth) < 0)
		return cmd_fail("demo");
	job.model = model; /* the demo fits the material's own model */
	/* The one overwrite rule: the photo here, the fit's folder by its
	 * own check. */
	job.force = job.replace = force;
	if (glint_output_check(photo_path, force, NULL) < 0 ||
	    (light && glint_output_check(light_path, force, NULL) < 0))
		return cmd_fail("demo");
	struct glint_image *map = NULL;
	if (light && glint_sim_light_class(light, 1024, &map) < 0)
		return cmd_usage_error("demo", "--light: %s",
				       glint_error_msg());
	if (mkdir(dir, 0777) < 0 && errno != EEXIST) {
		glint_error_set(errno, "%s: cannot create folder: %s", dir,
				strerror(errno));
		glint_image_free(map);
		return cmd_fail("demo");
	}
	if (map) {
		/* The classes face a camera on +Z unrotated, as the demo's
		 * scene has it. */
		ret = glint_image_write(light_path, map, NULL);
		glint_image_free(map);
		if (ret < 0)
			return cmd_fail("demo");
		snprintf(job.scene.env_path, sizeof(job.scene.env_path), "%s",
			 light_path);
		memset(job.scene.env_rotation, 0,
		       sizeof(job.scene.env_rotation));
	}

	/* The simulated capture. */
	struct glint_image *photo = NULL;
	struct glint_sim_photo_opts so = { .noise = noise,
					   .nthreads = job.nthreads };
	glint_log_info("simulating a photo of %s (Table 1) under %s", material,
		       job.scene.env_path);
	double t0 = glint_clock_monotonic();
	ret = glint_sim_photo(&job.scene, model, truth, &so, &photo,
			      &job.weight);
	if (ret < 0)
		return cmd_fail("demo");
	double sim_s = glint_clock_monotonic() - t0;
	ret = glint_image_write(photo_path, photo, NULL);
	if (ret < 0)
		goto fail;
	job.scene_path = scene_path;
	job.photo_path = photo_path;
	job.photo = photo;
	photo = NULL; /* the job's from here: glint_fit_job_crop() */
	job.model = model;
	job.out_dir = fit_dir;
	json_t *doc;
	job.opts.progress = cmd_fit_progress;
	ret = glint_fit_job_crop(&job);
	if (ret == 0)
		ret = glint_fit_job_run(&job, &doc);
	if (ret < 0)
		goto fail;
	if (json) {
		json_object_set_new(doc, "truth",
				    glint_material_to_json(model, truth));
		json_object_set_new(doc, "material_name",
				    json_string(material));
		json_object_set_new(doc, "photo", json_string(photo_path));
		cmd_print_json(doc);
	} else {
		printf("demo: %s sphere under %s, %dx%d%s\n", material,
		       light ? light : strrchr(job.scene.env_path, '/') + 1,
		       job.window.frame_width ? job.window.frame_width
					      : job.scene.cam.width,
		       job.window.frame_width ? job.window.frame_height
					      : job.scene.cam.height,
		       noise ? ", one noisy 12-bit exposure"
			     : ", noise-free HDR");
		printf("  photo simulated in %.1f s; fit (%s) in %.2f s, "
		       "relative RMSE %.4f\n",
		       sim_s,
		       glint_model_is_transparent(model)
			       ? "annealing + LM polish"
			       : glint_fit_method_name(job.opts.method),
		       json_real_value(json_object_get(doc, "seconds")),
		       json_real_value(json_object_get(doc, "relative_rmse")));
		cmd_print_params(doc, truth);
		cmd_print_verdicts(doc);
		printf("  photo:   %s\n  results: %s/report.html, params.json, "
		       "render.exr, compare.png\n",
		       photo_path, fit_dir);
		json_decref(doc);
	}
	glint_image_free(photo);
	glint_image_free(job.photo);
	glint_image_free(job.weight);
	return GLINT_EXIT_OK;
fail:
	glint_image_free(photo);
	glint_image_free(job.photo);
	glint_image_free(job.weight);
	return cmd_fail("demo");
}
