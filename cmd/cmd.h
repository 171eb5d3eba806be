/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_CMD_H
#define GLINT_CMD_CMD_H

/*
 * The glint command: a thin layer over the libraries.
 *
 * Errors: each command prints its one error and returns its exit status
 * (0, 1, 2 for usage).  Threads: called from main.  Who frees: nothing.
 */

#include "core/error.h"
#include "core/path.h"
#include "export/export.h"

#include <jansson.h>

#include <stddef.h>

/* Exit codes shared by every command. */
enum {
	GLINT_EXIT_OK = 0,
	GLINT_EXIT_FAIL = 1,  /* bad input or a failure while working */
	GLINT_EXIT_USAGE = 2, /* bad command line */
};

struct glint_cmd {
	const char *name;
	const char *summary;
	int (*run)(int argc, char **argv);
	void (*help)(void);
};

int cmd_render(int argc, char **argv);
void cmd_render_help(void);
int cmd_demo(int argc, char **argv);
void cmd_demo_help(void);
int cmd_fit(int argc, char **argv);
void cmd_fit_help(void);
int cmd_export(int argc, char **argv);
void cmd_export_help(void);
int cmd_convert(int argc, char **argv);
void cmd_convert_help(void);
int cmd_capture(int argc, char **argv);
void cmd_capture_help(void);
int cmd_cameras(int argc, char **argv);
int cmd_hdr(int argc, char **argv);
int cmd_probe(int argc, char **argv);

void cmd_probe_help(void);
int cmd_rig(int argc, char **argv);
void cmd_rig_help(void);
int cmd_check_rig(int argc, char **argv);
void cmd_check_rig_help(void);
int cmd_queue(int argc, char **argv);
int cmd_jobs(int argc, char **argv);
int cmd_sessions(int argc, char **argv);
void cmd_queue_help(void);
void cmd_jobs_help(void);
void cmd_sessions_help(void);
void cmd_hdr_help(void);
void cmd_cameras_help(void);

/* The rig file to use: `config`, or the simulated rig (data/rig-sim.json)
 * when it is NULL; written into buf (n bytes), which is returned. */
const char *cmd_rig_config(char *buf, size_t n, const char *config);

/* Report the current error (human or JSON) and return GLINT_EXIT_FAIL. */
int cmd_fail(const char *cmd);
/* Print a usage error and return GLINT_EXIT_USAGE. */
int cmd_usage_error(const char *cmd, const char *fmt, ...) GLINT_PRINTF(2, 3);
/* Print a JSON result on stdout (consumes obj). */
void cmd_print_json(json_t *obj);

/* Print a fit's parameters (value, standard error; truth and error when
 * truth is not NULL) as a table on stdout. */
void cmd_print_params(const json_t *doc, const double *truth);
/* The fit's acceptance verdict and its misfit verdict, one line each. */
void cmd_print_verdicts(const json_t *doc);

/* Refit (model, p) in `format` and write it to out (refused when it
 * exists, unless force); a transparent model needs the sphere's
 * diameter_m.  The result as JSON, or NULL with the error set. */
json_t *cmd_export_write(enum glint_export_format format,
			 const struct glint_model *model, const double *p,
			 double diameter_m, const char *source,
			 const char *name, const char *out, int force);

/* A fit's progress on a terminal (struct glint_fit_opts.progress). */
void cmd_fit_progress(void *ctx, const char *pass, int iter, double cost);

#endif
