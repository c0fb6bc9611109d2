#include "replay_options.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "imest/imest_can.h"
#include "imest_can_id.h"
#include "tool_args.h"

static const char *const k_prog = "imest-replay";

static void usage(FILE *o)
{
  fprintf(o, "usage: imest-replay --pole-pairs N --ls HENRY --sigma VALUE [options] FILE.csv\n"
             "\n"
             "Runs a recording through the estimator exactly as firmware does and prints one\n"
             "CSV row per window: t_end_s,T_R_s,R_S_ohm,E_I,valid,status,...\n"
             "FILE (\"-\" = stdin) needs a header with t,u_a,u_b,u_c,i_a,i_b,i_c,theta (any\n"
             "order; other columns ignored): t in s, phase-to-neutral V, phase currents in A\n"
             "(positive into the motor), mechanical angle in rad (wrapped or unwrapped,\n"
             "increasing with the a-b-c field). Guide: docs/feeding-logs.md.\n"
             "Options take a value as '--opt VALUE' or '--opt=VALUE'.\n"
             "\n"
             "motor (required):\n"
             "  --pole-pairs N      pole pairs n_p\n"
             "  --ls H              stator inductance L_S [H]\n"
             "  --sigma X           total leakage factor (0 < sigma < 1)\n"
             "time base:\n"
             "  --fs HZ             sample rate; t then only orders the rows and may be in any\n"
             "                      unit (ms, a sample index) or too coarse (default: from t,\n"
             "                      which must then be in seconds; rounding of t to its printed\n"
             "                      decimals is tolerated)\n"
             "estimator:\n"
             "  --window S          window length [s] (default 1; at least 64 samples)\n"
             "  --filter-hz HZ      front-end Butterworth-3 cut-off (default 100; needs\n"
             "                      fs > 2.5 x cut-off)\n"
             "  --aa-hz HZ          cut-off of a 2nd-order analog anti-alias filter on the\n"
             "                      electrical channels, modelled on the angle (default none)\n"
             "  --u-delay S         the voltage samples lag the currents by S seconds, 0..1/fs\n"
             "                      (e.g. 50e-6 for volt-seconds of the PWM period that just\n"
             "                      ended at 10 kHz)\n"
             "  --dc-block-hz HZ    cut-off of the offset high-pass on voltages and currents\n"
             "                      (default 1; 0 = off)\n"
             "  --angle-observer-hz HZ  natural frequency of the angle observer between the\n"
             "                      encoder and the rotation (default 0: filter-hz / 2;\n"
             "                      negative: off)\n"
             "  --tr-nominal S      nominal T_R for scaling (default 0.1)\n"
             "  --tr-min S --tr-max S   admissible T_R band (default 0.001 .. 10)\n"
             "  --max-pe-k2 X       validity threshold on the relative PE index of K2 (0.1)\n"
             "  --speed-limit RAD_S an angle step faster than this is an encoder fault\n"
             "                      (default min(3000, 2 x fs); below 3 x fs, i.e. less than\n"
             "                      pi per sample)\n"
             "  --i-limit A|auto    |phase current| at which the ADC saturates (default auto:\n"
             "                      detected from plateaus at the record's extreme; 0 = off)\n"
             "  --u-limit V|auto    the same for the phase voltages (default auto)\n"
             "  --from-rest auto|yes|no  the record starts at rest (no warm-up needed);\n"
             "                      auto = current ~0 and rotor still at the first samples\n"
             "CAN telemetry:\n"
             "  --candump FILE      also write the published CAN frames (candump -L format;\n"
             "                      \"-\" = stdout)\n"
             "  --can-iface NAME    interface name in that log (default vcan0)\n"
             "  --can-id ID         base CAN identifier (default 0x6A0; above 0x7FF a 29-bit\n"
             "                      extended identifier)\n"
             "  --can-ext           the base CAN identifier is 29-bit even if it is small\n"
             "other:\n"
             "  --quiet             no notes or summary on stderr\n"
             "  -h, --help          this text\n"
             "\n"
             "exit status: 0 windows estimated; 1 the file or its data are unusable (the\n"
             "message says why and what to do); 2 bad option or argument.\n");
}

/* The config fields set by a plain numeric option. */
static const struct {
  const char *name, *field;
  size_t offset;
} k_numeric[] = {
    {"--window", "window_s", offsetof(imest_config_t, window_s)},
    {"--filter-hz", "filter_hz", offsetof(imest_config_t, filter_hz)},
    {"--aa-hz", "aa_hz", offsetof(imest_config_t, aa_hz)},
    {"--u-delay", "u_delay_s", offsetof(imest_config_t, u_delay_s)},
    {"--dc-block-hz", "dc_block_hz", offsetof(imest_config_t, dc_block_hz)},
    {"--tr-nominal", "tr_nominal_s", offsetof(imest_config_t, tr_nominal_s)},
    {"--tr-min", "tr_min_s", offsetof(imest_config_t, tr_min_s)},
    {"--tr-max", "tr_max_s", offsetof(imest_config_t, tr_max_s)},
    {"--max-pe-k2", "max_pe_k2_rel", offsetof(imest_config_t, max_pe_k2_rel)},
    {"--ls", "ls_h", offsetof(imest_config_t, ls_h)},
    {"--sigma", "sigma", offsetof(imest_config_t, sigma)},
    {"--angle-observer-hz", "angle_observer_hz", offsetof(imest_config_t, angle_observer_hz)},
};
#define N_NUMERIC   (sizeof k_numeric / sizeof k_numeric[0])
#define GIVEN_LS    (1u << 9)
#define GIVEN_SIGMA (1u << 10)

const char *replay_option_of(const replay_opts_t *o, const char *field, int *given)
{
  for (size_t k = 0; k < N_NUMERIC; ++k) {
    if (strcmp(field, k_numeric[k].field) == 0) {
      *given = (o->given >> k) & 1u;
      return k_numeric[k].name;
    }
  }
  if (strcmp(field, "speed_limit_rad_s") == 0) {
    *given = o->speed_limit > 0;
    return "--speed-limit";
  }
  if (strcmp(field, "pole_pairs") == 0) {
    *given = 1;
    return "--pole-pairs";
  }
  *given = 0;
  return NULL;
}

/* "auto" or a number >= 0 (-1 stands for auto). */
static int limit_value(tool_args_t *a, double *out)
{
  const char *v = tool_args_value(a);
  if (v == NULL) return -1;
  if (strcmp(v, "auto") == 0) {
    *out = -1.0;
    return 0;
  }
  char *end = NULL;
  const double x = strtod(v, &end);
  if (end == v || *end != '\0' || !(x >= 0.0) || !isfinite(x)) {
    fprintf(stderr, "%s: %s takes 'auto' or a limit >= 0 (0 = off), not '%s'\n", k_prog, a->opt, v);
    return -1;
  }
  *out = x;
  return 0;
}

int replay_parse(int argc, char **argv, replay_opts_t *o)
{
  memset(o, 0, sizeof *o);
  imest_config_default(&o->cfg);
  o->can_iface = "vcan0";
  o->can_id = IMEST_CAN_DEFAULT_BASE_ID;
  o->i_limit = o->u_limit = -1.0;
  o->from_rest = -1;
  int have_np = 0, can_ext = 0;
  const char *can_id = NULL;
  double d;
  tool_args_t a;
  tool_args_init(&a, k_prog, argc, argv);
  tool_arg_kind_t kind;
  while ((kind = tool_args_next(&a)) != TOOL_ARG_END) {
    if (kind == TOOL_ARG_OPERAND) {
      if (o->path != NULL) {
        fprintf(stderr, "%s: more than one input file ('%s', '%s')\n", k_prog, o->path, a.operand);
        return TOOL_EXIT_USAGE;
      }
      o->path = a.operand;
      continue;
    }
    size_t k = 0;
    while (k < N_NUMERIC && !tool_args_is(&a, k_numeric[k].name)) k++;
    if (k < N_NUMERIC) {
      if (tool_args_number(&a, &d)) return TOOL_EXIT_USAGE;
      *(float *)(void *)((char *)&o->cfg + k_numeric[k].offset) = (float)d;
      o->given |= 1u << k;
    } else if (tool_args_is(&a, "-h") || tool_args_is(&a, "--help")) {
      usage(stdout);
      return TOOL_EXIT_OK;
    } else if (tool_args_is(&a, "--pole-pairs")) {
      if (tool_args_number(&a, &d)) return TOOL_EXIT_USAGE;
      if (d < 1 || d > 64 || d != floor(d)) {
        fprintf(stderr, "%s: --pole-pairs must be an integer 1..64\n", k_prog);
        return TOOL_EXIT_USAGE;
      }
      o->cfg.pole_pairs = (unsigned int)d;
      have_np = 1;
    } else if (tool_args_is(&a, "--fs")) {
      if (tool_args_number(&a, &o->fs_hz)) return TOOL_EXIT_USAGE;
      if (!(o->fs_hz > 0.0) || o->fs_hz > 1e6) {
        fprintf(stderr, "%s: --fs must be a sample rate above 0 and at most 1e6 Hz\n", k_prog);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "--speed-limit")) {
      if (tool_args_number(&a, &o->speed_limit)) return TOOL_EXIT_USAGE;
      if (!(o->speed_limit > 0.0)) {
        fprintf(stderr, "%s: --speed-limit must be a speed above 0 [rad/s]\n", k_prog);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "--i-limit")) {
      if (limit_value(&a, &o->i_limit)) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--u-limit")) {
      if (limit_value(&a, &o->u_limit)) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--from-rest")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (!strcmp(v, "auto"))
        o->from_rest = -1;
      else if (!strcmp(v, "yes"))
        o->from_rest = 1;
      else if (!strcmp(v, "no"))
        o->from_rest = 0;
      else {
        fprintf(stderr, "%s: --from-rest takes auto, yes or no, not '%s'\n", k_prog, v);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "--candump")) {
      if ((o->candump_path = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-iface")) {
      if ((o->can_iface = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-id")) {
      if ((can_id = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-ext")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      can_ext = 1;
    } else if (tool_args_is(&a, "--quiet")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      o->quiet = 1;
    } else {
      return tool_args_unknown(&a);
    }
  }
  if (!have_np || !(o->given & GIVEN_LS) || !(o->given & GIVEN_SIGMA)) {
    fprintf(stderr, "%s: --pole-pairs, --ls and --sigma are required (see --help)\n", k_prog);
    return TOOL_EXIT_USAGE;
  }
  if (o->path == NULL) {
    fprintf(stderr, "%s: no input file (\"-\" reads stdin; see --help)\n", k_prog);
    return TOOL_EXIT_USAGE;
  }
  /* the same parser as imest-monitor's --base-id (port/canid) */
  o->can_id = IMEST_CAN_DEFAULT_BASE_ID | (can_ext ? IMEST_CAN_ID_EXT : 0u);
  char err[256];
  if (can_id != NULL && imest_can_id_parse(can_id, can_ext, "--can-ext", &o->can_id, err, sizeof err)) {
    fprintf(stderr, "%s: --can-id %s\n", k_prog, err);
    return TOOL_EXIT_USAGE;
  }
  return -1;
}
