/* SPDX-License-Identifier: Apache-2.0 */
/* Command lines the same way in every host tool: "--opt value" and
 * "--opt=value", "-" as a file name (stdin), "--" ends the options, and one
 * exit-code convention. Host tool code (stdio). */
#ifndef IMEST_TOOL_ARGS_H
#define IMEST_TOOL_ARGS_H

#include <stdio.h>

/* Exit codes of every imest tool. */
enum {
  TOOL_EXIT_OK = 0,       /* success */
  TOOL_EXIT_DATA = 1,     /* the input or data is unusable (bad content, nothing decoded, I/O) */
  TOOL_EXIT_USAGE = 2,    /* bad option or argument */
  TOOL_EXIT_NOT_VALID = 3 /* --require-valid: windows estimated or decoded, none valid */
};

/* What --require-valid asks of at least one window (imest-replay,
 * imest-monitor): the column of that name is 1. */
typedef enum {
  TOOL_REQUIRE_NONE = 0, /* option not given: any window is success */
  TOOL_REQUIRE_VALID,    /* "valid" (the default): T_R and R_S both valid */
  TOOL_REQUIRE_TR,       /* "tr": tr_valid */
  TOOL_REQUIRE_RS        /* "rs": rs_valid */
} tool_require_t;

typedef enum { TOOL_ARG_END = 0, TOOL_ARG_OPTION, TOOL_ARG_OPERAND } tool_arg_kind_t;

typedef struct {
  const char *prog; /* for messages: "prog: ..." */
  int argc;
  char **argv;
  int next;                 /* index of the next argv element */
  int options_done;         /* after "--" everything is an operand */
  char opt[64];             /* current option's name without "=value" */
  const char *inline_value; /* the text after '=' of "--opt=value", else NULL */
  const char *operand;      /* current operand (TOOL_ARG_OPERAND) */
} tool_args_t;

void tool_args_init(tool_args_t *a, const char *prog, int argc, char **argv);

/* The next argument: an option (a->opt), an operand (a->operand; "-" is an
 * operand) or the end. */
tool_arg_kind_t tool_args_next(tool_args_t *a);

/* Whether the current option is `name` (e.g. "--window"). */
int tool_args_is(const tool_args_t *a, const char *name);

/* The current option's value: "--opt=value" or the next argument. NULL after
 * printing "prog: --opt needs a value". */
const char *tool_args_value(tool_args_t *a);

/* The value as a finite number. 0, or -1 after printing the reason. */
int tool_args_number(tool_args_t *a, double *out);

/* A flag takes no value: 0, or -1 after printing "--flag takes no value". */
int tool_args_flag(tool_args_t *a);

/* --require-valid[=valid|tr|rs]: the value only after '=' (the next argument
 * stays an operand). 0 with *out set, or -1 after printing the reason. */
int tool_args_require_valid(const tool_args_t *a, tool_require_t *out);

/* The column --require-valid checks ("valid", "tr_valid", "rs_valid"). */
const char *tool_require_column(tool_require_t r);

/* Prints "prog: unknown option '--x'" and "Try 'prog --help'." on stderr;
 * returns TOOL_EXIT_USAGE. */
int tool_args_unknown(const tool_args_t *a);

/* The options every tool has, handled the same way: -h and --help print
 * usage(stdout), --version prints tool_version(); either returns TOOL_EXIT_OK
 * (TOOL_EXIT_USAGE after a message for "--help=x"). -1 when the current
 * option is none of them. */
int tool_args_standard(tool_args_t *a, void (*usage)(FILE *));

/* "prog VERSION" (imest_version.h) and the licence line, on stdout (GNU
 * style: the first line is the program's name and version). */
void tool_version(const char *prog);

#endif
