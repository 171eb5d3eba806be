/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"
#include "fit/render/render_job.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"
#include "core/output.h"
#include "fit/render/render.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
	       "      --env MAP       relight: this environment map instead "
	       "of the scene's\n"
	       "                      (lat-long .exr/.hdr/.pfm; a path from "
	       "the current folder)\n"
	       "      --srgb          the map is an 8-bit image to take as "
	       "sRGB-encoded (without\n"
	       "                      it an 8-bit map is refused: "
	       "camera-encoded, not radiance)\n"
	       "      --env-rotation X,Y,Z  the map's rotation, degrees about "
	       "X, Y, Z\n"
	       "                      (default: the scene's; 0,0,0 with "
	       "--env)\n"
	       "      --env-scale S   radiance multiplier (default: the "
	       "scene's; 1 with --env)\n"
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
	       "      --force         replace outputs glint wrote (existing "
	       "ones are refused\n"
	       "                      without it; files glint did not write "
	       "or the inputs,\n"
	       "                      always)\n"
	       "      --threads N     worker threads (default: all CPUs)\n"
	       "      --json          print a JSON result on stdout, logs as "
	       "JSON lines\n"
	       "  -q, --quiet         no progress or info messages\n"
	       "\nExit status: 0 done, 1 bad input or failure, 2 bad command "
	       "line.\n");
}

struct rotation {
	int given;
	double deg[3];
};

/* "X,Y,Z" in degrees. */
static int parse_rotation(const char *arg, void *dest)
{
	struct rotation *r = dest;
	char *end;
	const char *p = arg;

	for (int k = 0; k < 3; k++) {
		r->deg[k] = strtod(p, &end);
		if (end == p || !isfinite(r->deg[k]) || fabs(r->deg[k]) > 360 ||
		    *end != (k < 2 ? ',' : '\0'))
			return glint_error_set(EINVAL,
					       "expected X,Y,Z in degrees "
					       "(each within +-360), e.g. "
					       "0,90,0");
		p = end + 1;
	}
	r->given = 1;
	return 0;
}

/* --env and its rotation and scale replace the scene's environment. */
static int relight(struct glint_scene *sc, const char *env,
		   const struct rotation *rot, double scale)
{
	if (env) {
		if (access(env, R_OK) < 0)
			return glint_error_set(errno, "--env: %s: %s", env,
					       strerror(errno));
		if (strlen(env) >= sizeof(sc->env_path))
			return glint_error_set(ENAMETOOLONG,
					       "--env: path too long");
		memcpy(sc->env_path, env, strlen(env) + 1);
		memset(sc->env_rotation, 0, sizeof(sc->env_rotation));
		sc->env_scale = 1;
	}
	if (rot->given)
		memcpy(sc->env_rotation, rot->deg, sizeof(rot->deg));
	if (!isnan(scale))
		sc->env_scale = scale;
	return 0;
}

int cmd_render(int argc, char **argv)
{
	struct glint_render_job job = { .out_exr = "render.exr",
					.background = 1,
					.exposure = NAN };
	const char *material = NULL, *entry = NULL, *paper = NULL;
	int spp = 0, ls = -1, bs = -1, nobg = 0, srgb = 0, force = 0;
	const char *env = NULL;
	struct rotation rot = { 0 };
	double env_scale = NAN;
	char paper_path[4096];
	const struct cmd_opt opts[] = {
		CMD_STRING("material", 'm', &material),
		CMD_STRING("entry", 0, &entry),
		CMD_STRING("paper", 0, &paper),
		CMD_STRING("env", 0, &env),
		CMD_FLAG("srgb", 0, &srgb),
		CMD_CALL("env-rotation", &rot, parse_rotation),
		CMD_REAL("env-scale", &env_scale, 1e-12, 1e12),
		CMD_STRING("output", 'o', &job.out_exr),
		CMD_STRING("png", 0, &job.out_png),
		CMD_REAL("exposure", &job.exposure, -64, 64),
		CMD_STRING("coverage", 0, &job.out_coverage),
		CMD_FLAG("half", 0, &job.half),
		CMD_INT("spp", &spp, 1, 4096),
		CMD_INT("light-samples", &ls, 0, 1 << 16),
		CMD_INT("brdf-samples", &bs, 0, 1 << 16),
		CMD_FLAG("no-background", 0, &nobg),
		CMD_FLAG("force", 0, &force),
		CMD_INT("threads", &job.nthreads, 0, 256),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("render", cmd_render_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json;
	if (nobg)
		job.background = 0;
	if (a.argc != 1)
		return cmd_usage_error("render",
				       "expected one SCENE.json argument");
	if (!material == !paper)
		return cmd_usage_error("render", "give exactly one of "
						 "--material and --paper");
	if (entry && !material)
		return cmd_usage_error("render", "--entry needs --material");
	if (glint_scene_load(a.argv[0], &job.scene) < 0 ||
	    relight(&job.scene, env, &rot, env_scale) < 0)
		return cmd_fail("render");
	job.scene.env_srgb = srgb;
	if (paper) {
		snprintf(paper_path, sizeof(paper_path), "%s/paper-table1.json",
			 glint_data_dir());
		material = paper_path;
		entry = paper;
	}
	if (glint_material_load(material, entry, &job.model, job.params) < 0)
		return cmd_fail("render");
	/* Every output checked before any work. */
	const char *inputs[] = { a.argv[0], material, job.scene.env_path,
				 NULL };
	const char *outs[] = { job.out_exr, job.out_png, job.out_coverage };
	for (int k = 0; k < 3; k++)
		if (outs[k] && glint_output_check(outs[k], force, inputs) < 0)
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
