/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CMD_OPTIONS_H
#define GLINT_CMD_OPTIONS_H

/*
 * One option grammar for every glint command.  A command describes its
 * options in a table; cmd_options_parse() adds the common ones
 *
 *   --json         results (and logs) as JSON, for scripts
 *   -q, --quiet    errors and warnings only
 *   -v, --verbose  debug messages too
 *   -h, --help     the command's help
 *
 * checks every value (range, choice), and reports a bad command line the
 * same way everywhere: one line naming the option and what was expected,
 * a suggestion for a misspelt name ("did you mean '--samples'?"), then
 * "Try 'glint CMD --help'." and exit status 2.
 *
 * Errors: a usage error prints one line and returns -EINVAL (exit 2).
 * Threads: one thread (the option tables are the caller's).  Who frees:
 * nothing (values point into argv).
 */

#include <stddef.h>

enum cmd_opt_kind {
	CMD_OPT_FLAG,	/* int *: set to `value` (1 when 0) */
	CMD_OPT_STRING, /* const char **: the argument */
	CMD_OPT_INT,	/* int *: an integer in [lo, hi] */
	CMD_OPT_REAL,	/* double *: a finite number in [lo, hi] */
	CMD_OPT_CHOICE, /* int *: the index of the argument in `choices` */
	CMD_OPT_CALL,	/* parse(arg, dest): < 0 with glint_error_msg() */
};

struct cmd_opt {
	const char *name; /* long name, without "--" */
	char short_name;  /* or 0 */
	enum cmd_opt_kind kind;
	void *dest;
	double lo, hi;		    /* INT, REAL */
	const char *const *choices; /* CHOICE: NULL-terminated */
	int (*parse)(const char *arg, void *dest);
	int value; /* FLAG */
};

/* Table entries. */
#define CMD_FLAG(n, s, d)                                                      \
	{                                                                      \
		.name = (n), .short_name = (s), .kind = CMD_OPT_FLAG,          \
		.dest = (d)                                                    \
	}
#define CMD_STRING(n, s, d)                                                    \
	{                                                                      \
		.name = (n), .short_name = (s), .kind = CMD_OPT_STRING,        \
		.dest = (d)                                                    \
	}
#define CMD_INT(n, d, l, h)                                                    \
	{                                                                      \
		.name = (n), .kind = CMD_OPT_INT, .dest = (d), .lo = (l),      \
		.hi = (h)                                                      \
	}
#define CMD_REAL(n, d, l, h)                                                   \
	{                                                                      \
		.name = (n), .kind = CMD_OPT_REAL, .dest = (d), .lo = (l),     \
		.hi = (h)                                                      \
	}
#define CMD_CHOICE(n, d, c)                                                    \
	{                                                                      \
		.name = (n), .kind = CMD_OPT_CHOICE, .dest = (d),              \
		.choices = (c)                                                 \
	}
#define CMD_CALL(n, d, f)                                                      \
	{                                                                      \
		.name = (n), .kind = CMD_OPT_CALL, .dest = (d), .parse = (f)   \
	}

/* The common options' values, and the positional arguments. */
struct cmd_args {
	int json, quiet, verbose;
	int argc;    /* positional arguments left ... */
	char **argv; /* ... in order (options may come anywhere; "--" ends
		      * them) */
};

/*
 * Parse argv[1..] (argv[0] is the command's name) against opts (ended by
 * a zero entry).  Sets the log mode from --json/-q/-v.  Returns 0 to run,
 * 1 when help was printed (exit 0), or GLINT_EXIT_USAGE's negative when
 * the line was refused (the message printed): exit with cmd_exit(ret).
 */
int cmd_options_parse(const char *cmd, void (*help)(void),
		      const struct cmd_opt *opts, int argc, char **argv,
		      struct cmd_args *out);

/* The exit status for a cmd_options_parse() result that is not 0. */
int cmd_options_exit(int ret);

/* "--NAME 'ARG': expected one of a, b, c (did you mean 'b'?)": a choice
 * error in the common form, into the error state; returns -EINVAL. */
int cmd_choice_error(const char *arg, const char *const *choices);

#endif
