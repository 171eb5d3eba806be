/* SPDX-License-Identifier: MIT */
/* glint export: the fitted material in a renderer's model (export/export.h). */
#include "cmd.h"
#include "options.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"
#include "core/output.h"
#include "export/export.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cmd_export_help(void)
{
	printf("usage: glint export MATERIAL.json --to FORMAT -o OUT "
	       "[--name N] [--force]\n"
	       "\n"
	       "Write a fitted material (a fit's params.json, or a material "
	       "file) in a\nrenderer's own model. The target's parameters "
	       "are fitted to glint's BRDF by\nleast squares over 8 view "
	       "angles x 512 incident directions, not copied\nacross; the "
	       "fit's relative RMS difference of reflected radiance is "
	       "printed\nand stored with the export (docs/export.md). A "
	       "transparent (dielectric) sphere\ncarries across exactly: "
	       "glass of its ior around an interior absorbing\n-ln(T) / "
	       "diameter per metre (--diameter-m).\n"
	       "\n"
	       "  --to FORMAT       gltf: a glTF 2.0 file (.gltf) holding the "
	       "material\n"
	       "                    (pbrMetallicRoughness, metallic 0, "
	       "KHR_materials_ior,\n"
	       "                    KHR_materials_specular; a dielectric: "
	       "KHR_materials_\n"
	       "                    transmission and KHR_materials_volume)\n"
	       "                    mitsuba: a Mitsuba 3 scene file (.xml) "
	       "holding one\n"
	       "                    BSDF (blendbsdf of diffuse and "
	       "roughconductor)\n"
	       "                    pbrt: a pbrt-v4 file (.pbrt) of named "
	       "materials (mix of\n"
	       "                    diffuse and conductor) to Include\n"
	       "                    blender: a Python script (.py) that "
	       "builds a node\n"
	       "                    material (Diffuse + Fresnel-weighted "
	       "Beckmann Glossy);\n"
	       "                    blender -b -P OUT.py -- --render "
	       "PNG [--env MAP]\n"
	       "                    renders a preview sphere of it\n"
	       "                    materialx: a MaterialX 1.38 document "
	       "(.mtlx), one\n"
	       "                    standard_surface and its "
	       "surfacematerial\n"
	       "  -o, --output OUT  the file to write (refused if it exists, "
	       "unless --force)\n"
	       "  --entry NAME      pick NAME from a Table-1 style file\n"
	       "  --name N          the material's name (default: the one "
	       "the input holds, else\n"
	       "                    its session's for a fit, else the "
	       "file's stem)\n"
	       "  --diameter-m D    a transparent sphere's diameter in "
	       "metres (its absorption\n"
	       "                    is per diameter; a fit's params.json "
	       "records it)\n"
	       "  --force           replace OUT if glint wrote it (never "
	       "another's file\n"
	       "                    or the input)\n"
	       "  --json            print the result as JSON\n");
}

json_t *cmd_export_write(enum glint_export_format format,
			 const struct glint_model *model, const double *p,
			 double diameter_m, const char *source,
			 const char *name, const char *out, int force)
{
	const char *inputs[] = { source, NULL };
	if (glint_output_check(out, force, inputs) < 0)
		return NULL;
	struct glint_export e;
	if (glint_export_refit(format, model, p, diameter_m, &e) < 0)
		return NULL;
	char *text = glint_export_text(&e, name, source, model);
	if (!text) {
		glint_error_set(ENOMEM, "out of memory");
		return NULL;
	}
	int ret = glint_atomic_write_file(out, text, strlen(text));
	free(text);
	if (ret < 0)
		return NULL;
	glint_log_info(e.dielectric ? "%s (%s) -> %s: %s, carried across; "
				      "the interface's Fresnel term differs "
				      "by a relative RMS %.3f"
				    : "%s (%s) -> %s: %s refitted to glint's "
				      "BRDF, relative RMS difference %.3f",
		       source, model->name, out,
		       glint_export_format_names[format], e.residual);
	return json_pack("{s:s, s:s, s:s, s:f, s:o}", "output", out, "format",
			 glint_export_format_names[format], "model",
			 model->name, "refit_relative_rms", e.residual,
			 glint_export_format_names[format],
			 glint_export_params_json(&e));
}

/* The sphere's diameter a fit's params.json records, or NAN. */
static double recorded_diameter(const char *path)
{
	json_t *doc = glint_json_read_quiet(path);
	double d = json_number_value(json_object_get(
		json_object_get(doc, "inputs"), "sphere_diameter_m"));
	json_decref(doc);
	return d > 0 ? d : NAN;
}

/* The name a material file or a fit's params.json gives its material,
 * else one from where it lives (glint_export_name_from_path). */
static const char *material_name(const char *path, char buf[256])
{
	json_t *doc = glint_json_read_quiet(path);
	json_t *fitted = json_object_get(doc, "material");
	const char *n = json_string_value(
		json_object_get(json_is_object(fitted) ? fitted : doc, "name"));
	if (n && *n)
		snprintf(buf, 256, "%s", n);
	else
		glint_export_name_from_path(path, buf, 256);
	json_decref(doc);
	return buf;
}

int cmd_export(int argc, char **argv)
{
	const char *out = NULL, *name = NULL, *entry = NULL;
	int to = -1, force = 0;
	double diameter_m = NAN;
	const struct cmd_opt opts[] = {
		CMD_CHOICE("to", &to, glint_export_format_names),
		CMD_STRING("output", 'o', &out),
		CMD_STRING("entry", 0, &entry),
		CMD_STRING("name", 0, &name),
		CMD_FLAG("force", 0, &force),
		CMD_REAL("diameter-m", &diameter_m, 1e-6, 1e3),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("export", cmd_export_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	if (a.argc != 1)
		return cmd_usage_error("export", "expected one MATERIAL.json");
	if (to < 0)
		return cmd_usage_error("export", "--to FORMAT is required "
						 "(gltf, mitsuba, pbrt, "
						 "blender, materialx)");
	if (!out)
		return cmd_usage_error("export", "-o OUT is required");

	const struct glint_model *model;
	double p[GLINT_MAX_PARAMS];
	if (glint_material_load(a.argv[0], entry, &model, p) < 0)
		return cmd_fail("export");
	if (isnan(diameter_m))
		diameter_m = recorded_diameter(a.argv[0]);
	char name_buf[256];
	if (!name)
		name = entry ? entry : material_name(a.argv[0], name_buf);
	json_t *res = cmd_export_write((enum glint_export_format)to, model, p,
				       diameter_m, a.argv[0], name, out, force);
	if (!res)
		return cmd_fail("export");
	if (a.json) {
		json_object_set_new(res, "input", json_string(a.argv[0]));
		cmd_print_json(res);
		return GLINT_EXIT_OK;
	}
	char *params =
		json_dumps(json_object_get(res, glint_export_format_names[to]),
			   JSON_COMPACT);
	printf("%s: %s; refit relative RMS %.4f\n",
	       glint_export_format_names[to], params ? params : "",
	       json_real_value(json_object_get(res, "refit_relative_rms")));
	free(params);
	json_decref(res);
	return GLINT_EXIT_OK;
}
