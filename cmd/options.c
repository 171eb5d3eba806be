/* SPDX-License-Identifier: MIT */
#define _GNU_SOURCE /* getopt_long */
#include "options.h"

#include "cmd.h"
#include "core/error.h"
#include "core/log.h"
#include "core/suggest.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { OPT_JSON = 1000, OPT_FIRST = 1100 };

int cmd_choice_error(const char *arg, const char *const *choices)
{
	char list[512] = "";
	size_t used = 0;

	for (int i = 0; choices[i]; i++) {
		int n = snprintf(list + used, sizeof(list) - used, "%s%s",
				 i ? ", " : "", choices[i]);
		if (n < 0 || (size_t)n >= sizeof(list) - used)
			break;
		used += (size_t)n;
	}
	const char *hint = glint_suggest_hint(arg, choices);
	return glint_error_set(EINVAL, "expected one of %s%s", list, hint);
}

static int apply(const struct cmd_opt *o, const char *arg)
{
	char *end;

	switch (o->kind) {
	case CMD_OPT_FLAG:
		*(int *)o->dest = o->value ? o->value : 1;
		return 0;
	case CMD_OPT_STRING:
		if (!arg[0])
			return glint_error_set(EINVAL, "expected a value");
		*(const char **)o->dest = arg;
		return 0;
	case CMD_OPT_INT: {
		errno = 0;
		long v = strtol(arg, &end, 10);
		if (!arg[0] || *end || errno || v < o->lo || v > o->hi)
			return glint_error_set(EINVAL,
					       "expected an integer in "
					       "[%.0f, %.0f]",
					       o->lo, o->hi);
		*(int *)o->dest = (int)v;
		return 0;
	}
	case CMD_OPT_REAL: {
		double v = strtod(arg, &end);
		if (!arg[0] || *end || !isfinite(v) || v < o->lo || v > o->hi)
			return glint_error_set(EINVAL,
					       "expected a number in [%g, %g]",
					       o->lo, o->hi);
		*(double *)o->dest = v;
		return 0;
	}
	case CMD_OPT_CHOICE:
		for (int i = 0; o->choices[i]; i++)
			if (!strcmp(arg, o->choices[i])) {
				*(int *)o->dest = i;
				return 0;
			}
		return cmd_choice_error(arg, o->choices);
	case CMD_OPT_CALL:
		return o->parse(arg, o->dest);
	}
	return glint_error_set(EINVAL, "bad option table");
}

static const char *const common_names[] = { "json", "quiet", "verbose",
					    "help" };

/* Say why an unknown option was refused, with the likeliest meant. */
static int unknown(const char *cmd, const struct cmd_opt *opts, size_t n,
		   const char *word, int short_opt)
{
	char given[128], candidates_text[1200];
	const char *names[160];
	size_t k = 0;

	if (short_opt)
		return cmd_usage_error(cmd, "unknown option '-%c'", short_opt);
	snprintf(given, sizeof(given), "%s", word + strspn(word, "-"));
	given[strcspn(given, "=")] = '\0';
	for (size_t i = 0; i < n && k < 150; i++)
		names[k++] = opts[i].name;
	for (size_t i = 0; i < 4; i++)
		names[k++] = common_names[i];
	names[k] = NULL;
	/* An abbreviation of several (getopt takes unique ones). */
	size_t used = 0, hits = 0, gl = strlen(given);
	for (size_t i = 0; i < k && gl; i++)
		if (!strncmp(names[i], given, gl)) {
			int m = snprintf(candidates_text + used,
					 sizeof(candidates_text) - used,
					 "%s--%s", hits++ ? ", " : "",
					 names[i]);
			if (m < 0 ||
			    (size_t)m >= sizeof(candidates_text) - used)
				break;
			used += (size_t)m;
		}
	if (hits > 1)
		return cmd_usage_error(cmd, "option '--%s' is ambiguous: %s",
				       given, candidates_text);
	const char *near = glint_suggest(given, names);
	if (near)
		return cmd_usage_error(cmd,
				       "unknown option '--%s' (did you mean "
				       "'--%s'?)",
				       given, near);
	return cmd_usage_error(cmd, "unknown option '--%s'", given);
}

static const struct cmd_opt *by_short(const struct cmd_opt *opts, size_t n,
				      int c)
{
	for (size_t i = 0; i < n; i++)
		if (opts[i].short_name == c)
			return &opts[i];
	return NULL;
}

int cmd_options_parse(const char *cmd, void (*help)(void),
		      const struct cmd_opt *opts, int argc, char **argv,
		      struct cmd_args *out)
{
	size_t n = 0;
	char shorts[128] = ":qvh";
	size_t ns = strlen(shorts);

	memset(out, 0, sizeof(*out));
	while (opts && opts[n].name)
		n++;
	struct option *lo = calloc(n + 5, sizeof(*lo));
	if (!lo) {
		glint_log_error("out of memory");
		return -GLINT_EXIT_FAIL;
	}
	for (size_t i = 0; i < n; i++) {
		int arg = opts[i].kind != CMD_OPT_FLAG;
		lo[i] = (struct option){ opts[i].name,
					 arg ? required_argument : no_argument,
					 NULL, OPT_FIRST + (int)i };
		if (opts[i].short_name && ns + 3 < sizeof(shorts)) {
			shorts[ns++] = opts[i].short_name;
			if (arg)
				shorts[ns++] = ':';
			shorts[ns] = '\0';
		}
	}
	lo[n] = (struct option){ "json", no_argument, NULL, OPT_JSON };
	lo[n + 1] = (struct option){ "quiet", no_argument, NULL, 'q' };
	lo[n + 2] = (struct option){ "verbose", no_argument, NULL, 'v' };
	lo[n + 3] = (struct option){ "help", no_argument, NULL, 'h' };

	int ret = 0, c;
	opterr = 0;
	optind = 0; /* glibc: start over */
	while (!ret && (c = getopt_long(argc, argv, shorts, lo, NULL)) != -1) {
		const char *word = argv[optind - 1];
		const struct cmd_opt *o = NULL;
		if (c >= OPT_FIRST && c < OPT_FIRST + (int)n)
			o = &opts[c - OPT_FIRST];
		else if (c != 'q' && c != 'v' && c != 'h' && c != '?' &&
			 c != ':' && c != OPT_JSON)
			o = by_short(opts, n, c);
		if (c == '?')
			ret = unknown(cmd, opts, n, word, optopt);
		else if (c == ':')
			ret = cmd_usage_error(cmd, "option '%s' needs a value",
					      word);
		else if (c == 'h') {
			help();
			printf("\nEvery command also takes --json (results and "
			       "logs as JSON), -q/--quiet\n(errors and "
			       "warnings only), -v/--verbose (debug messages) "
			       "and -h/--help.\n");
			ret = 1;
		} else if (c == OPT_JSON)
			out->json = 1;
		else if (c == 'q')
			out->quiet = 1;
		else if (c == 'v')
			out->verbose = 1;
		else if (o && apply(o, optarg) < 0) {
			char shown[64];
			if (o->short_name && word[1] != '-')
				snprintf(shown, sizeof(shown), "-%c",
					 o->short_name);
			else
				snprintf(shown, sizeof(shown), "--%s", o->name);
			ret = cmd_usage_error(
				cmd, "%s%s%s%s: %s", shown, optarg ? " '" : "",
				optarg ? optarg : "", optarg ? "'" : "",
				glint_error_msg());
		}
	}
	free(lo);
	if (ret == GLINT_EXIT_USAGE)
		return -GLINT_EXIT_USAGE;
	if (ret)
		return ret;
	out->argc = argc - optind;
	out->argv = argv + optind;
	glint_log_set_mode(out->json ? GLINT_LOG_JSON : GLINT_LOG_HUMAN);
	glint_log_set_verbosity(out->quiet ? -1 : out->verbose ? 1 : 0);
	return 0;
}

int cmd_options_exit(int ret)
{
	return ret == 1 ? GLINT_EXIT_OK : -ret;
}
