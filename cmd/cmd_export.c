/* SPDX-License-Identifier: MIT */
/* glint export: the fitted material in a renderer's model (fit/export.h). */
#define _POSIX_C_SOURCE 200809L /* lstat */
#include "cmd.h"
#include "options.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "fit/export.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void cmd_export_help(void)
{
	printf("usage: glint export MATERIAL.json --to gltf -o OUT.gltf "
	       "[--name N] [--force]\n"
	       "\n"
	       "Write a fitted material (a fit's params.json, or a material "
	       "file) in a\nrenderer's own model. The target's parameters "
	       "are fitted to glint's BRDF by\nleast squares over 8 view "
	       "angles x 512 incident directions, not copied\nacross; the "
	       "fit's relative RMS difference of reflected radiance is "
	       "printed\nand stored with the export (docs/export.md).\n"
	       "\n"
	       "  --to FORMAT       gltf: a glTF 2.0 file holding the "
	       "material\n"
	       "                    (pbrMetallicRoughness, metallic 0, "
	       "KHR_materials_ior,\n"
	       "                    KHR_materials_specular)\n"
	       "  -o, --output OUT  the file to write (refused if it exists, "
	       "unless --force)\n"
	       "  --entry NAME      pick NAME from a Table-1 style file\n"
	       "  --name N          the material's name (default: the "
	       "input's file name)\n"
	       "  --force           replace OUT\n"
	       "  --json            print the result as JSON\n");
}

static const char *const formats[] = { "gltf", NULL };

int cmd_export(int argc, char **argv)
{
	const char *out = NULL, *name = NULL, *entry = NULL;
	int to = -1, force = 0;
	const struct cmd_opt opts[] = {
		CMD_CHOICE("to", &to, formats), CMD_STRING("output", 'o', &out),
		CMD_STRING("entry", 0, &entry), CMD_STRING("name", 0, &name),
		CMD_FLAG("force", 0, &force),	{ 0 },
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
						 "(gltf)");
	if (!out)
		return cmd_usage_error("export", "-o OUT is required");
	struct stat st;
	if (!force && lstat(out, &st) == 0) {
		glint_error_set(EEXIST,
				"%s exists: refusing to replace it (--force "
				"to)",
				out);
		return cmd_fail("export");
	}

	const struct glint_model_ops *model;
	double p[GLINT_MAX_PARAMS];
	struct glint_gltf_material g;
	double residual;
	if (glint_material_load(a.argv[0], entry, &model, p) < 0 ||
	    glint_gltf_refit(model, p, &g, &residual) < 0)
		return cmd_fail("export");
	if (!name) {
		const char *s = strrchr(a.argv[0], '/');
		name = entry ? entry : s ? s + 1 : a.argv[0];
	}
	json_t *doc = glint_gltf_document(&g, name, a.argv[0], model, residual);
	char *text = doc ? json_dumps(doc, JSON_INDENT(2)) : NULL;
	json_decref(doc);
	if (!text) {
		glint_error_set(ENOMEM, "out of memory");
		return cmd_fail("export");
	}
	int ret = glint_atomic_write_file(out, text, strlen(text));
	free(text);
	if (ret < 0)
		return cmd_fail("export");
	if (a.json) {
		cmd_print_json(json_pack(
			"{s:s, s:s, s:s, s:s, s:f, s:{s:[f,f,f], s:f, s:f, "
			"s:f, s:[f,f,f]}}",
			"input", a.argv[0], "output", out, "format", "gltf",
			"model", model->name, "refit_relative_rms", residual,
			"gltf", "base_color", g.base[0], g.base[1], g.base[2],
			"roughness", g.roughness, "ior", g.ior, "specular",
			g.specular, "specular_color", g.specular_color[0],
			g.specular_color[1], g.specular_color[2]));
	} else {
		glint_log_info("%s (%s) -> %s: glTF refitted to glint's BRDF, "
			       "relative RMS difference %.3f",
			       a.argv[0], model->name, out, residual);
		printf("gltf: base colour %.4f %.4f %.4f, roughness %.4f, "
		       "ior %.3f, specular %.4f, specular colour %.4f %.4f "
		       "%.4f; refit relative RMS %.4f\n",
		       g.base[0], g.base[1], g.base[2], g.roughness, g.ior,
		       g.specular, g.specular_color[0], g.specular_color[1],
		       g.specular_color[2], residual);
	}
	return GLINT_EXIT_OK;
}
