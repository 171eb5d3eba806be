/* SPDX-License-Identifier: MIT */
#include "backends.h"
#include "cmd.h"
#include "core/suggest.h"

#include "core/error.h"
#include "core/log.h"
#include "core/path.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef GLINT_VERSION
#define GLINT_VERSION "dev"
#endif

static const struct glint_cmd commands[] = {
	{ "rig",
	  "the appliance: button -> captures -> fit (--once: the main job)",
	  cmd_rig, cmd_rig_help },
	{ "demo",
	  "the fitter alone: simulate a photo of a Table-1 material, fit it",
	  cmd_demo, cmd_demo_help },
	{ "fit", "recover a material from an HDR photo of the sphere", cmd_fit,
	  cmd_fit_help },
	{ "render", "render a sphere of a material under an environment map",
	  cmd_render, cmd_render_help },
	{ "export",
	  "a fitted material for a renderer (glTF, Mitsuba, pbrt, Blender, "
	  "MaterialX)",
	  cmd_export, cmd_export_help },
	{ "convert",
	  "convert an image between EXR, HDR, PFM, TIFF (and PNG out)",
	  cmd_convert, cmd_convert_help },
	{ "capture", "capture an exposure bracket of the probe or the sample",
	  cmd_capture, cmd_capture_help },
	{ "cameras", "list cameras and their capabilities", cmd_cameras,
	  cmd_cameras_help },
	{ "hdr", "merge a bracket of raw frames into radiance and variance",
	  cmd_hdr, cmd_hdr_help },
	{ "probe", "unwrap a mirror-ball photo; convert probe formats",
	  cmd_probe, cmd_probe_help },
	{ "check-rig", "check a rig file, its camera and GPIO lines",
	  cmd_check_rig, cmd_check_rig_help },
	{ "sessions", "list capture sessions and their status", cmd_sessions,
	  cmd_sessions_help },
	{ "jobs", "list the job queue", cmd_jobs, cmd_jobs_help },
	{ "queue", "add, cancel or run queued fits", cmd_queue,
	  cmd_queue_help },
};

#define NCOMMANDS (sizeof(commands) / sizeof(commands[0]))

const char *cmd_rig_config(char *buf, size_t n, const char *config)
{
	if (config)
		snprintf(buf, n, "%s", config);
	else
		snprintf(buf, n, "%s", glint_rig_config_default());
	if (!config && access(buf, F_OK) < 0)
		glint_log_warn("no rig file at %s (the installed appliance's): "
			       "copy rig.example.json beside it to rig.json "
			       "and edit it, or give --config FILE (the "
			       "simulated rig: %s/rig-sim.json)",
			       buf, glint_data_dir());
	return buf;
}

int cmd_fail(const char *cmd)
{
	glint_log_error("%s: %s", cmd, glint_error_msg());
	return GLINT_EXIT_FAIL;
}

int cmd_usage_error(const char *cmd, const char *fmt, ...)
{
	char msg[512];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	fprintf(stderr, "glint %s: %s\nTry 'glint %s --help'.\n", cmd, msg,
		cmd);
	return GLINT_EXIT_USAGE;
}

void cmd_print_json(json_t *obj)
{
	char *s = json_dumps(obj, JSON_INDENT(2) | JSON_REAL_PRECISION(9));
	printf("%s\n", s);
	free(s);
	json_decref(obj);
}

static void usage(FILE *fp)
{
	fprintf(fp,
		"usage: glint <command> [options]\n"
		"\n"
		"glint measures a material's appearance from one HDR photo of "
		"a sphere of it\nand one HDR photo of a mirror-ball light "
		"probe.\n\ncommands:\n");
	for (size_t i = 0; i < NCOMMANDS; i++)
		fprintf(fp, "  %-10s %s\n", commands[i].name,
			commands[i].summary);
	fprintf(fp, "\n'glint <command> --help' describes each command.\n"
		    "Every command takes --json (results and logs as JSON), "
		    "-q/--quiet,\n-v/--verbose and -h/--help; outputs are "
		    "-o/--output.\n");
}

int main(int argc, char **argv)
{
	glint_backends_register();
	if (argc < 2) {
		usage(stderr);
		return GLINT_EXIT_USAGE;
	}
	if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") ||
	    !strcmp(argv[1], "help")) {
		if (argc > 2 && strcmp(argv[1], "help") == 0) {
			for (size_t i = 0; i < NCOMMANDS; i++)
				if (!strcmp(commands[i].name, argv[2])) {
					commands[i].help();
					return GLINT_EXIT_OK;
				}
		}
		usage(stdout);
		return GLINT_EXIT_OK;
	}
	if (!strcmp(argv[1], "--version")) {
		printf("glint %s\n", GLINT_VERSION);
		return GLINT_EXIT_OK;
	}
	for (size_t i = 0; i < NCOMMANDS; i++)
		if (!strcmp(commands[i].name, argv[1]))
			return commands[i].run(argc - 1, argv + 1);
	const char *names[NCOMMANDS + 1];
	for (size_t i = 0; i < NCOMMANDS; i++)
		names[i] = commands[i].name;
	names[NCOMMANDS] = NULL;
	const char *hint = glint_suggest_hint(argv[1], names);
	fprintf(stderr, "glint: unknown command '%s'%s\nTry 'glint --help'.\n",
		argv[1], hint);
	return GLINT_EXIT_USAGE;
}
