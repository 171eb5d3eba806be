/* SPDX-License-Identifier: MIT */
/*
 * The main job on the simulated rig, with no arguments: for now a render of
 * a Table-1 material under the embedded real environment map.
 */
#include "cmd.h"
#include "render_job.h"

#include "core/error.h"
#include "core/log.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

void cmd_demo_help(void)
{
	printf("usage: glint demo [--material NAME] [--out DIR] [--json]\n"
	       "\n"
	       "Render a sphere of a material from the paper's Table 1 "
	       "(default\nyellow-plastic) under the embedded Venice-sunset "
	       "environment map (Poly Haven,\nCC0), 512x512, and write "
	       "DIR/render.exr and DIR/render.png (DIR defaults\nto "
	       "./demo-out).\n"
	       "\n"
	       "  --material NAME  a Table-1 material: satin-paint, "
	       "semi-gloss-paint,\n"
	       "                   matte-paint, yellow-plastic, teflon, "
	       "nylon, silver,\n"
	       "                   green-acrylic, aluminium-bronze, copper, "
	       "nickel\n"
	       "  --out DIR        output folder (created if missing)\n"
	       "  --threads N      worker threads (default: all CPUs)\n"
	       "  --json           print a JSON result on stdout\n"
	       "  -q, --quiet      no progress or info messages\n");
}

int cmd_demo(int argc, char **argv)
{
	enum { O_JSON = 256, O_THREADS };
	static const struct option opts[] = {
		{ "material", required_argument, NULL, 'm' },
		{ "out", required_argument, NULL, 'o' },
		{ "threads", required_argument, NULL, O_THREADS },
		{ "json", no_argument, NULL, O_JSON },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *material = "yellow-plastic", *dir = "demo-out";
	char scene_path[4096], table[4096], exr[4096], png[4096];
	struct render_job job = { .background = 1, .exposure = NAN };
	int json = 0, c;

	optind = 1;
	while ((c = getopt_long(argc, argv, "m:o:qh", opts, NULL)) != -1) {
		switch (c) {
		case 'm':
			material = optarg;
			break;
		case 'o':
			dir = optarg;
			break;
		case O_JSON:
			json = 1;
			break;
		case 'q':
			glint_log_set_mode(GLINT_LOG_QUIET);
			break;
		case 'h':
			cmd_demo_help();
			return GLINT_EXIT_OK;
		case O_THREADS:
			if (cmd_parse_int("demo", "--threads", optarg, 0, 256,
					  &job.nthreads) < 0)
				return GLINT_EXIT_USAGE;
			break;
		default:
			return cmd_usage_error("demo", "unknown option");
		}
	}
	if (optind != argc)
		return cmd_usage_error("demo", "unexpected argument '%s'",
				       argv[optind]);
	if (json)
		glint_log_set_mode(GLINT_LOG_JSON);
	snprintf(scene_path, sizeof(scene_path), "%s/demo-scene.json",
		 glint_data_dir());
	snprintf(table, sizeof(table), "%s/paper-table1.json",
		 glint_data_dir());
	if (glint_scene_load(scene_path, &job.scene) < 0 ||
	    glint_material_load(table, material, &job.model, job.params) < 0)
		return cmd_fail("demo");
	if (mkdir(dir, 0777) < 0 && errno != EEXIST) {
		glint_error_set(errno, "%s: cannot create folder: %s", dir,
				strerror(errno));
		return cmd_fail("demo");
	}
	snprintf(exr, sizeof(exr), "%s/render.exr", dir);
	snprintf(png, sizeof(png), "%s/render.png", dir);
	job.out_exr = exr;
	job.out_png = png;
	glint_log_info("rendering %s (Table 1) under %s", material,
		       job.scene.env_path);
	json_t *result;
	if (render_job_run(&job, &result) < 0)
		return cmd_fail("demo");
	if (json) {
		json_object_set_new(result, "material_name",
				    json_string(material));
		cmd_print_json(result);
		return GLINT_EXIT_OK;
	}
	printf("demo: %s sphere, %dx%d, rendered in %.2f s\n", material,
	       job.scene.cam.width, job.scene.cam.height,
	       json_real_value(json_object_get(result, "trace_seconds")) +
		       json_real_value(
			       json_object_get(result, "shade_seconds")));
	printf("  HDR image: %s\n  preview:   %s\n", exr, png);
	json_decref(result);
	return GLINT_EXIT_OK;
}
