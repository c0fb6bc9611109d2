/* SPDX-License-Identifier: Apache-2.0 */
/* imest-sim command line (internal to sim/ and test/sim/). */
#ifndef IMSIM_CLI_H
#define IMSIM_CLI_H

#include <stddef.h>
#include <stdio.h>

#include "imsim/imsim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const char *out; /* "-" = stdout */
  long decimate;   /* write every n-th sample (1 = all) */
  int progress;    /* -1 auto (isatty(stderr)), 0 off, 1 on */
  int help;        /* -h, --help */
  int version;     /* --version */
} imsim_cli_opts_t;

/* The CSV header line (no newline). */
const char *imsim_cli_header(void);
/* The columns appended to it (and to every row) when a real-motor effect is on. */
const char *imsim_cli_header_real(void);

/* The --help text. */
const char *imsim_cli_usage(void);

/* Every flag the parser accepts: writes up to max names, returns how many there are. */
size_t imsim_cli_flags(const char **names, size_t max);

/* Parses argv into c (preset applied first, then the other flags in order) and o.
   Returns 0, or -1 with a message in err (a flag the parser does not know: "unknown option
   '--x'"). */
int imsim_cli_parse(int argc, char **argv, imsim_config_t *c, imsim_cli_opts_t *o, char *err, size_t errlen);

/* Writes one CSV row (with newline). */
void imsim_cli_write_row(FILE *f, const imsim_sample_t *s);

/* The whole program; returns the process exit status. */
int imsim_cli_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif

#endif
