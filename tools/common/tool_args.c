/* SPDX-License-Identifier: Apache-2.0 */
#include "tool_args.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "imest/imest_version.h"

void tool_args_init(tool_args_t *a, const char *prog, int argc, char **argv)
{
  memset(a, 0, sizeof *a);
  a->prog = prog;
  a->argc = argc;
  a->argv = argv;
  a->next = 1;
}

tool_arg_kind_t tool_args_next(tool_args_t *a)
{
  a->opt[0] = '\0';
  a->inline_value = NULL;
  a->operand = NULL;
  if (a->next >= a->argc) return TOOL_ARG_END;
  const char *s = a->argv[a->next++];
  if (!a->options_done && strcmp(s, "--") == 0) {
    a->options_done = 1;
    return tool_args_next(a);
  }
  if (a->options_done || s[0] != '-' || s[1] == '\0') {
    a->operand = s;
    return TOOL_ARG_OPERAND;
  }
  /* "--opt=value": the name is what precedes the first '=' (long options only) */
  const char *eq = (s[1] == '-') ? strchr(s, '=') : NULL;
  size_t len = eq ? (size_t)(eq - s) : strlen(s);
  if (len >= sizeof a->opt) len = sizeof a->opt - 1; /* too long for any known name */
  memcpy(a->opt, s, len);
  a->opt[len] = '\0';
  a->inline_value = eq ? eq + 1 : NULL;
  return TOOL_ARG_OPTION;
}

int tool_args_is(const tool_args_t *a, const char *name)
{
  return strcmp(a->opt, name) == 0;
}

const char *tool_args_value(tool_args_t *a)
{
  if (a->inline_value != NULL) return a->inline_value;
  if (a->next >= a->argc) {
    fprintf(stderr, "%s: %s needs a value (see --help)\n", a->prog, a->opt);
    return NULL;
  }
  return a->argv[a->next++];
}

int tool_args_number(tool_args_t *a, double *out)
{
  const char *v = tool_args_value(a);
  if (v == NULL) return -1;
  char *end = NULL;
  const double x = strtod(v, &end);
  if (end == v || *end != '\0' || !isfinite(x)) {
    fprintf(stderr, "%s: %s: '%s' is not a number\n", a->prog, a->opt, v);
    return -1;
  }
  *out = x;
  return 0;
}

int tool_args_flag(tool_args_t *a)
{
  if (a->inline_value == NULL) return 0;
  fprintf(stderr, "%s: %s takes no value\n", a->prog, a->opt);
  return -1;
}

int tool_args_require_valid(const tool_args_t *a, tool_require_t *out)
{
  const char *v = a->inline_value;
  if (v == NULL || strcmp(v, "valid") == 0)
    *out = TOOL_REQUIRE_VALID;
  else if (strcmp(v, "tr") == 0)
    *out = TOOL_REQUIRE_TR;
  else if (strcmp(v, "rs") == 0)
    *out = TOOL_REQUIRE_RS;
  else {
    fprintf(stderr, "%s: %s takes valid, tr or rs (as %s=WHICH), not '%s'\n", a->prog, a->opt, a->opt, v);
    return -1;
  }
  return 0;
}

const char *tool_require_column(tool_require_t r)
{
  return r == TOOL_REQUIRE_TR ? "tr_valid" : r == TOOL_REQUIRE_RS ? "rs_valid" : "valid";
}

int tool_args_unknown(const tool_args_t *a)
{
  fprintf(stderr, "%s: unknown option '%s'\nTry '%s --help'.\n", a->prog, a->opt, a->prog);
  return TOOL_EXIT_USAGE;
}

void tool_version(const char *prog)
{
  printf("%s %s\n"
         "Licence: Apache License 2.0 <https://www.apache.org/licenses/LICENSE-2.0>\n",
         prog, IMEST_VERSION_STRING);
}

int tool_args_standard(tool_args_t *a, void (*usage)(FILE *))
{
  const int help = tool_args_is(a, "-h") || tool_args_is(a, "--help");
  if (!help && !tool_args_is(a, "--version")) return -1;
  if (tool_args_flag(a)) return TOOL_EXIT_USAGE;
  if (help)
    usage(stdout);
  else
    tool_version(a->prog);
  return TOOL_EXIT_OK;
}
