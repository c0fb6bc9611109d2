/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay's command line: the options, --help, and which of them the
 * user gave (a bad setting the user chose is a usage error, one the data
 * forces is a data error). */
#ifndef IMEST_REPLAY_OPTIONS_H
#define IMEST_REPLAY_OPTIONS_H

#include "imest/imest.h"
#include "imest/imest_temperature.h"

/* Where the phase voltage comes from (--voltage). */
typedef enum {
  REPLAY_VOLTAGE_PHASE = 0, /* measured phase-to-neutral voltages u_a,u_b,u_c: imest_isr_abc() */
  REPLAY_VOLTAGE_DUTY = 1   /* duty cycles d_a,d_b,d_c and the bus v_dc: imest_isr_duty() */
} replay_voltage_t;

typedef struct {
  imest_config_t cfg;       /* motor constants and the plain numeric options */
  unsigned long given;      /* bit k: option k of the numeric table was given */
  replay_voltage_t voltage; /* --voltage */
  const char *path;         /* the recording, "-" = stdin */
  const char *output_path;  /* -o/--output: the windows' CSV; NULL or "-" = stdout */
  const char *candump_path; /* NULL = no CAN log; "-" = stdout */
  const char *can_iface;    /* --candump-iface: the interface name written into that log */
  uint32_t can_id;          /* with IMEST_CAN_ID_EXT for a 29-bit identifier */
  double fs_hz;             /* --fs: 0 = from t */
  double speed_limit;       /* --speed-limit: 0 = from the sample rate */
  double i_limit, u_limit;  /* -1 = auto */
  int from_rest;            /* -1 = auto, 0 no, 1 yes */
  int gaps_restart;         /* --gaps restart: missing samples restart the estimator (0: refused) */
  int quiet;
  int align_check;  /* 0 after --no-align-check */
  int require;      /* --require-valid: a tool_require_t */
  int temperatures; /* --temperatures given: temp_cfg holds its references */
  imest_temperature_config_t temp_cfg;
} replay_opts_t;

/* Parses argv into *o. Returns -1 to go on, or the exit code to end with
 * (0 after --help; TOOL_EXIT_USAGE after a message). */
int replay_parse(int argc, char **argv, replay_opts_t *o);

/* The option that sets a config field ("filter_hz" -> "--filter-hz"), or NULL;
 * *given: whether the user gave it. */
const char *replay_option_of(const replay_opts_t *o, const char *field, int *given);

#endif
