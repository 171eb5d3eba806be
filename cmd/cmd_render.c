/* SPDX-License-Identifier: MIT */
#include "cmd.h"
#include "fit/render/render_job.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"
#include "fit/render/render.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cmd_render_help(void)
{
	printf("usage: glint render SCENE.json (--material FILE.json | "
	       "--paper NAME) [options]\n"
	       "\n"
	       "Render the scene's sphere of a material under the scene's "
	       "environment map\n(direct light only; multiple importance "
	       "sampling of map and BRDF).\n"
	       "\n"
	       "  --material FILE     material JSON: {\"model\": "
	       "\"torrance-sparrow\", \"diffuse\": [r,g,b], ...},\n"
	       "                      or a fit's params.json (its "
	       "material)\n"
	       "  --entry NAME        with --material: pick NAME from a "
	       "Table-1 style file\n"
	       "  --paper NAME        a material of the paper's Table 1 (e.g. "
	       "satin-paint, copper)\n"
	       "  -o, --output FILE   HDR output (.exr, .hdr, .pfm); default "
	       "render.exr\n"
	       "      --png FILE      8-bit sRGB preview (tone map: see "
	       "docs/conventions.md)\n"
	       "      --exposure EV   preview exposure in stops (default: "
	       "auto)\n"
	       "      --coverage FILE per-pixel fraction of samples on the "
	       "sphere\n"
	       "      --half          EXR with half floats (default 32-bit "
	       "float)\n"
	       "      --spp N         primary samples per pixel (scene "
	       "default 4)\n"
	       "      --light-samples N  env-map samples per hit (default "
	       "32)\n"
	       "      --brdf-samples N   BRDF samples per hit (default 32)\n"
	       "      --no-background black where the sphere is not\n"
	       "      --threads N     worker threads (default: all CPUs)\n"
	       "      --json          print a JSON result on stdout, logs as "
	       "JSON lines\n"
	       "  -q, --quiet         no progress or info messages\n"
	       "\nExit status: 0 done, 1 bad input or failure, 2 bad command "
	       "line.\n");
}

int cmd_render(int argc, char **argv)
{
	enum {
		O_PNG = 256,
		O_EXPOSURE,
		O_COVERAGE,
		O_HALF,
		O_SPP,
		O_LS,
		O_BS,
		O_NOBG,
		O_THREADS,
		O_JSON,
		O_ENTRY,
		O_PAPER
	};
	static const struct option opts[] = {
		{ "material", required_argument, NULL, 'm' },
		{ "entry", required_argument, NULL, O_ENTRY },
		{ "paper", required_argument, NULL, O_PAPER },
		{ "output", required_argument, NULL, 'o' },
		{ "png", required_argument, NULL, O_PNG },
		{ "exposure", required_argument, NULL, O_EXPOSURE },
		{ "coverage", required_argument, NULL, O_COVERAGE },
		{ "half", no_argument, NULL, O_HALF },
		{ "spp", required_argument, NULL, O_SPP },
		{ "light-samples", required_argument, NULL, O_LS },
		{ "brdf-samples", required_argument, NULL, O_BS },
		{ "no-background", no_argument, NULL, O_NOBG },
		{ "threads", required_argument, NULL, O_THREADS },
		{ "json", no_argument, NULL, O_JSON },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	struct glint_render_job job = { .out_exr = "render.exr",
					.background = 1,
					.exposure = NAN };
	const char *material = NULL, *entry = NULL, *paper = NULL;
	int spp = 0, ls = -1, bs = -1, json = 0, c;
	char paper_path[4096];

	optind = 1;
	while ((c = getopt_long(argc, argv, "m:o:qh", opts, NULL)) != -1) {
		switch (c) {
		case 'm':
			material = optarg;
			break;
		case O_ENTRY:
			entry = optarg;
			break;
		case O_PAPER:
			paper = optarg;
			break;
		case 'o':
			job.out_exr = optarg;
			break;
		case O_PNG:
			job.out_png = optarg;
			break;
		case O_COVERAGE:
			job.out_coverage = optarg;
			break;
		case O_HALF:
			job.half = 1;
			break;
		case O_NOBG:
			job.background = 0;
			break;
		case O_JSON:
			json = 1;
			break;
		case 'q':
			glint_log_set_mode(GLINT_LOG_QUIET);
			break;
		case 'h':
			cmd_render_help();
			return GLINT_EXIT_OK;
		case O_EXPOSURE: {
			char *end;
			job.exposure = strtod(optarg, &end);
			if (*end || !isfinite(job.exposure))
				return cmd_usage_error(
					"render",
					"--exposure '%s': expected "
					"a number of stops",
					optarg);
			break;
		}
		case O_SPP:
			if (cmd_parse_int("render", "--spp", optarg, 1, 4096,
					  &spp) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_LS:
			if (cmd_parse_int("render", "--light-samples", optarg,
					  0, 1 << 16, &ls) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_BS:
			if (cmd_parse_int("render", "--brdf-samples", optarg, 0,
					  1 << 16, &bs) < 0)
				return GLINT_EXIT_USAGE;
			break;
		case O_THREADS:
			if (cmd_parse_int("render", "--threads", optarg, 0, 256,
					  &job.nthreads) < 0)
				return GLINT_EXIT_USAGE;
			break;
		default:
			return cmd_usage_error("render", "unknown option");
		}
	}
	if (json)
		glint_log_set_mode(GLINT_LOG_JSON);
	if (optind != argc - 1)
		return cmd_usage_error("render",
				       "expected one SCENE.json argument");
	if (!material == !paper)
		return cmd_usage_error("render", "give exactly one of "
						 "--material and --paper");
	if (entry && !material)
		return cmd_usage_error("render", "--entry needs --material");
	if (glint_scene_load(argv[optind], &job.scene) < 0)
		return cmd_fail("render");
	if (paper) {
		snprintf(paper_path, sizeof(paper_path), "%s/paper-table1.json",
			 glint_data_dir());
		material = paper_path;
		entry = paper;
	}
	if (glint_material_load(material, entry, &job.model, job.params) < 0)
		return cmd_fail("render");
	if (spp)
		job.scene.spp = spp;
	if (ls >= 0)
		job.scene.light_samples = ls;
	if (bs >= 0)
		job.scene.brdf_samples = bs;
	if (job.scene.light_samples + job.scene.brdf_samples == 0)
		return cmd_usage_error("render", "light and BRDF samples are "
						 "both 0");
	json_t *result;
	if (glint_render_job_run(&job, &result) < 0)
		return cmd_fail("render");
	if (json) {
		cmd_print_json(result);
	} else {
		glint_log_info("wrote %s%s%s (%dx%d) in %.2f s", job.out_exr,
			       job.out_png ? " and " : "",
			       job.out_png ? job.out_png : "",
			       job.scene.cam.width, job.scene.cam.height,
			       json_real_value(json_object_get(
				       result, "trace_seconds")) +
				       json_real_value(json_object_get(
					       result, "shade_seconds")));
		json_decref(result);
	}
	return GLINT_EXIT_OK;
}
