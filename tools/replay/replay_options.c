/* SPDX-License-Identifier: Apache-2.0 */
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
             "CSV row per window: t_end_s,T_R_s,R_S_ohm,E_I,valid,status,...,tr_valid,rs_valid,...\n"
             "FILE (\"-\" = stdin) needs a header with t,u_a,u_b,u_c,i_a,i_b,i_c,theta (any\n"
             "order; other columns ignored): t in s, phase-to-neutral V, phase currents in A\n"
             "(positive into the motor), mechanical angle in rad (wrapped or unwrapped,\n"
             "increasing with the a-b-c field). With --voltage duty it needs\n"
             "t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta instead. Logs are read as drives write\n"
             "them: names case-insensitive, a few aliases (time, v_a, angle, u_dc, ...), a\n"
             "unit after the name in [] or () converted (ms, us, mA, mV, deg, rev, %%);\n"
             "separator ',', ';' or tab (then a decimal comma is read); '#' comment lines;\n"
             "two of the three currents suffice (the third is minus their sum), and so do\n"
             "two line-to-line voltages u_ab,u_bc,u_ca instead of u_a,u_b,u_c (converted\n"
             "without a zero sequence). Guide: docs/feeding-logs.md.\n"
             "Options take a value as '--opt VALUE' or '--opt=VALUE'.\n"
             "\n"
             "motor (required):\n"
             "  --pole-pairs N      pole pairs n_p\n"
             "  --ls H              stator inductance L_S [H]\n"
             "  --sigma X           total leakage factor (0 < sigma < 1)\n"
             "  --ls-uncertainty X  largest relative error of --ls (default 0.1: a data\n"
             "                      sheet's; 0 = exact, e.g. a simulator's own constants);\n"
             "                      what it can move T_R and R_S by is in their error bounds\n"
             "  --sigma-uncertainty X  the same for --sigma (default 0.2). Commissioned\n"
             "                      constants: what imest-commission states (imest_comm_apply)\n"
             "time base:\n"
             "  --fs HZ             sample rate; t then only orders the rows and may be in any\n"
             "                      unit (ms, a sample index) or too coarse (default: from t,\n"
             "                      which must then be in seconds; rounding of t to its printed\n"
             "                      decimals is tolerated). With --fs, a t in seconds (or with\n"
             "                      a unit in its header) that disagrees is named\n"
             "  --gaps refuse|restart  missing samples (a step of t of 1.5 sample periods or\n"
             "                      more): refuse the file (default), or restart the estimator\n"
             "                      at each gap (the window before it is estimated if it has\n"
             "                      half a window's samples, else dropped; the filters warm up\n"
             "                      again)\n"
             "voltage:\n"
             "  --voltage phase|duty  phase: measured phase-to-neutral voltages u_a,u_b,u_c\n"
             "                      (default); duty: the upper switches' duty cycles d_a,d_b,d_c\n"
             "                      in [0,1], row k's applied from t_k to t_k+1, and the DC bus\n"
             "                      v_dc [V] sampled at t_k (the library forms the voltage)\n"
             "  --u-delay S         the voltage lags the currents by S seconds beyond what\n"
             "                      --pwm-timing accounts for; negative: it leads; |S| <= 1/fs\n"
             "                      (e.g. 50e-6 for phase voltages taken as the volt-seconds of\n"
             "                      the PWM period that just ended at 10 kHz)\n"
             "  --pwm-hz HZ         carrier frequency when it is faster than the sample rate\n"
             "                      (default: the sample rate, one sample per period)\n"
             "  --voltage-kind staircase|smooth  what the measured phase voltages look like:\n"
             "                      staircase = a PWM inverter's, sampled unfiltered (default);\n"
             "                      smooth = a sine source (line-fed motor) or a voltage channel\n"
             "                      filtered well below the carrier: no PWM staircase share in\n"
             "                      the R_S and T_R error bounds (smooth on a staircase: R_S\n"
             "                      reads valid but up to 10 %% low). Not with --voltage duty\n"
             "duty cycles and the inverter (--voltage duty only):\n"
             "  --pwm-timing next|centred|last  when row k's duties apply: next = during\n"
             "                      [t_k, t_k+1) (default: computed one ISR earlier, loaded at\n"
             "                      the carrier valley where sample k is taken); centred =\n"
             "                      [t_k - T/2, t_k + T/2); last = [t_k-1, t_k)\n"
             "  --dead-time S       effective dead time, switching delays included [s]\n"
             "  --v-switch V        switch (IGBT, MOSFET) threshold voltage [V]\n"
             "  --r-switch OHM      switch slope resistance [ohm]\n"
             "  --v-diode V         freewheeling diode threshold voltage [V]\n"
             "  --r-diode OHM       diode slope resistance [ohm]\n"
             "  --i-band A          half-width of the current band around a zero crossing in\n"
             "                      which the error fades (default 0: per leg and sample,\n"
             "                      its ripple at the switching instants; docs/METHOD.md 17.1)\n"
             "  --edge-band A       > 0: the switching-instant model with the devices' own\n"
             "                      band A at an edge (docs/METHOD.md 17.1; default 0: the\n"
             "                      smooth sign)\n"
             "  --inverter-uncertainty X  relative uncertainty of that model's voltage error\n"
             "                      (default 0.2 when any of --dead-time .. --edge-band is\n"
             "                      given; without them the error is unknown and R_S is not\n"
             "                      valid; negative: unknown)\n"
             "estimator:\n"
             "  --window S          window length [s] (default 1; at least 64 samples)\n"
             "  --filter-hz HZ      front-end Butterworth-3 cut-off (default 100; needs\n"
             "                      fs > 2.5 x cut-off)\n"
             "  --aa-hz HZ          cut-off of a 2nd-order analog anti-alias filter on the\n"
             "                      electrical channels, modelled on the angle (default none)\n"
             "  --dc-block-hz HZ    cut-off of the offset high-pass on voltages and currents\n"
             "                      (default 1; 0 = off)\n"
             "  --angle-observer-hz HZ  natural frequency of the angle observer between the\n"
             "                      encoder and the rotation (default 0: filter-hz / 4;\n"
             "                      negative: off)\n"
             "  --encoder-counts N  the encoder's counts per revolution after decoding (4096\n"
             "                      for 1024 lines): where the observer's correction exceeds\n"
             "                      one count (it lags a real motion) the encoder is used\n"
             "                      (default 0: unknown)\n"
             "  --ls-curve I1:L1,I2:L2,...  the magnetising curve: L_S [H] measured at no load\n"
             "                      at 2 to 4 magnetising currents I [A], given as the alpha/beta\n"
             "                      amplitude (sqrt 3 x the phase rms current, the unit of\n"
             "                      i_rms_a), increasing; T_R and R_S are then moved to L_S at\n"
             "                      each window's flux, and a column ls_window_h [H] is appended\n"
             "                      (docs/feeding-logs.md; default none: L_S = --ls at any flux)\n"
             "  --tr-nominal S      nominal T_R for scaling (default 0.1)\n"
             "  --tr-min S --tr-max S   admissible T_R band (default 0.001 .. 10)\n"
             "  --max-pe-k2 X       validity threshold on the relative PE index of K2\n"
             "                      (default 0.1)\n"
             "  --rs OHM            R_S at ambient temperature (data sheet, commissioning);\n"
             "                      an R_S far from it marks the window constants_mismatch\n"
             "                      (default 0: unknown)\n"
             "  --rs-tolerance X    R_S is valid only if its error bound is within this,\n"
             "                      relative (default 0.05)\n"
             "  --tr-tolerance X    T_R is valid only if its error bound is within this,\n"
             "                      relative (default 0.02)\n"
             "  --timing-uncertainty S  uncertainty of the voltage/current alignment after\n"
             "                      --pwm-timing and --u-delay [s] (default 1e-6)\n"
             "  --rotor-hf-rr X     a deep-bar (double-cage) rotor: its resistance at high rotor\n"
             "                      frequency over R_R' (commissioning's square wave at fs/8;\n"
             "                      default 0: a single cage); the inverter's harmonics' move\n"
             "                      of the fit then enters the T_R and R_S bounds\n"
             "  --rotor-hf-sigma X  its sigma L_S at high rotor frequency over sigma L_S, in\n"
             "                      (0, 1] (default 0; needed with --rotor-hf-rr)\n"
             "  --inverter-vdc V    measured phase voltages with --rotor-hf-rr: the DC bus of\n"
             "                      their inverter [V], with --dead-time .. --inverter-\n"
             "                      uncertainty (allowed then) the harmonics' size (default 0:\n"
             "                      unknown, T_R not valid unless --voltage-kind smooth)\n"
             "  --speed-limit RAD_S an angle step faster than this is an encoder fault\n"
             "                      (default min(3000, 2 x fs); below 3 x fs, i.e. less than\n"
             "                      pi per sample)\n"
             "  --i-limit A|auto    |phase current| at which the ADC saturates (default auto:\n"
             "                      detected from plateaus at the record's extreme; 0 = off)\n"
             "  --u-limit V|auto    the same for measured phase voltages (default auto; not\n"
             "                      with --voltage duty: a duty-cycle voltage has no ADC)\n"
             "  --from-rest auto|yes|no  the record starts at rest (no warm-up needed);\n"
             "                      auto = current ~0 and rotor still at the first samples\n"
             "output:\n"
             "  -o, --output FILE   the windows' CSV into FILE (default: stdout; \"-\" = stdout)\n"
             "  --temperatures T_REF_C,RS_REF_OHM,TR_REF_S\n"
             "                      append the stator's and the rotor's temperatures\n"
             "                      (imest_temperature.h, the resistance method: copper stator,\n"
             "                      aluminium cage) from R_S and T_R measured at T_REF_C [degC]\n"
             "                      (ambient at commissioning): columns stator_c,\n"
             "                      stator_uncert_k, stator_valid, rr_ohm, rotor_c,\n"
             "                      rotor_uncert_k, rotor_valid after the others (L_R = --ls)\n"
             "CAN telemetry:\n"
             "  --candump FILE      also write the published CAN frames (candump -L format;\n"
             "                      \"-\" = stdout, with the windows' CSV in -o FILE): six\n"
             "                      frames per window, and with --temperatures its IMEST_TEMP\n"
             "  --candump-iface NAME  the interface name written into that log, a label only\n"
             "                      (default vcan0; a live interface is --can-iface in\n"
             "                      imest-monitor and imest-demo)\n"
             "  --can-base-id ID    base CAN identifier (default 0x6A0; above 0x7FF a 29-bit\n"
             "                      extended identifier; --can-id ID is the same, the older\n"
             "                      spelling)\n"
             "  --can-ext           the base CAN identifier is 29-bit even if it is small\n"
             "other:\n"
             "  --require-valid[=WHICH]  exit 3 when windows were estimated but none has\n"
             "                      WHICH = 1: valid (the default: T_R and R_S), tr (the\n"
             "                      tr_valid column) or rs (rs_valid); the value only as\n"
             "                      --require-valid=WHICH\n"
             "  --no-align-check    skip the alignment check: after the run the record is\n"
             "                      fitted again with the voltage (or duty and v_dc) columns\n"
             "                      one row earlier and later; a note names the shift and the\n"
             "                      option that would fix it when one fits clearly better\n"
             "                      (R_S then no longer changes with the frequency; needs a\n"
             "                      record over more than one operating point). Never changes\n"
             "                      the output or the exit status; costs two more runs\n"
             "  --quiet             no notes or summary on stderr (and no alignment check)\n"
             "  -h, --help          this text\n"
             "  --version           the version and licence\n"
             "\n"
             "Exit status: 0 windows estimated (valid or not, unless --require-valid); 1 the\n"
             "file or its data are unusable, or an output cannot be written (the message says\n"
             "why and what to do); 2 bad option or argument; 3 --require-valid given and no\n"
             "window valid (the message names the column).\n");
}

/* Which input an option belongs to. */
enum {
  FOR_ANY = 0,     /* either voltage input */
  FOR_DUTY = 1,    /* the duty-cycle input only */
  FOR_INVERTER = 2 /* the duty-cycle input, and part of the inverter's error model */
};

/* The config fields set by a plain numeric option. */
static const struct {
  const char *name, *field;
  size_t offset;
  int use; /* FOR_* */
} k_numeric[] = {
    {"--window", "window_s", offsetof(imest_config_t, window_s), FOR_ANY},
    {"--filter-hz", "filter_hz", offsetof(imest_config_t, filter_hz), FOR_ANY},
    {"--aa-hz", "aa_hz", offsetof(imest_config_t, aa_hz), FOR_ANY},
    {"--u-delay", "u_delay_s", offsetof(imest_config_t, u_delay_s), FOR_ANY},
    {"--dc-block-hz", "dc_block_hz", offsetof(imest_config_t, dc_block_hz), FOR_ANY},
    {"--tr-nominal", "tr_nominal_s", offsetof(imest_config_t, tr_nominal_s), FOR_ANY},
    {"--tr-min", "tr_min_s", offsetof(imest_config_t, tr_min_s), FOR_ANY},
    {"--tr-max", "tr_max_s", offsetof(imest_config_t, tr_max_s), FOR_ANY},
    {"--max-pe-k2", "max_pe_k2_rel", offsetof(imest_config_t, max_pe_k2_rel), FOR_ANY},
    {"--ls", "ls_h", offsetof(imest_config_t, ls_h), FOR_ANY},
    {"--sigma", "sigma", offsetof(imest_config_t, sigma), FOR_ANY},
    {"--ls-uncertainty", "ls_uncertainty", offsetof(imest_config_t, ls_uncertainty), FOR_ANY},
    {"--sigma-uncertainty", "sigma_uncertainty", offsetof(imest_config_t, sigma_uncertainty), FOR_ANY},
    {"--angle-observer-hz", "angle_observer_hz", offsetof(imest_config_t, angle_observer_hz), FOR_ANY},
    {"--encoder-counts", "encoder_counts_per_rev", offsetof(imest_config_t, encoder_counts_per_rev), FOR_ANY},
    {"--rs", "rs_nominal_ohm", offsetof(imest_config_t, rs_nominal_ohm), FOR_ANY},
    {"--rs-tolerance", "rs_tolerance", offsetof(imest_config_t, rs_tolerance), FOR_ANY},
    {"--tr-tolerance", "tr_tolerance", offsetof(imest_config_t, tr_tolerance), FOR_ANY},
    {"--timing-uncertainty", "timing_uncertainty_s", offsetof(imest_config_t, timing_uncertainty_s), FOR_ANY},
    {"--pwm-hz", "pwm_hz", offsetof(imest_config_t, pwm_hz), FOR_ANY},
    {"--rotor-hf-rr", "rotor_hf_rr_ratio", offsetof(imest_config_t, rotor_hf_rr_ratio), FOR_ANY},
    {"--rotor-hf-sigma", "rotor_hf_sigma_ratio", offsetof(imest_config_t, rotor_hf_sigma_ratio), FOR_ANY},
    {"--inverter-vdc", "inverter_vdc_v", offsetof(imest_config_t, inverter_vdc_v), FOR_ANY},
    {"--inverter-uncertainty", "inverter.uncertainty", offsetof(imest_config_t, inverter.uncertainty),
     FOR_DUTY},
    {"--dead-time", "inverter.dead_time_s", offsetof(imest_config_t, inverter.dead_time_s), FOR_INVERTER},
    {"--v-switch", "inverter.v_switch_v", offsetof(imest_config_t, inverter.v_switch_v), FOR_INVERTER},
    {"--r-switch", "inverter.r_switch_ohm", offsetof(imest_config_t, inverter.r_switch_ohm), FOR_INVERTER},
    {"--v-diode", "inverter.v_diode_v", offsetof(imest_config_t, inverter.v_diode_v), FOR_INVERTER},
    {"--r-diode", "inverter.r_diode_ohm", offsetof(imest_config_t, inverter.r_diode_ohm), FOR_INVERTER},
    {"--i-band", "inverter.i_band_a", offsetof(imest_config_t, inverter.i_band_a), FOR_INVERTER},
    {"--edge-band", "inverter.edge_band_a", offsetof(imest_config_t, inverter.edge_band_a), FOR_INVERTER},
};
#define N_NUMERIC (sizeof k_numeric / sizeof k_numeric[0])
_Static_assert(N_NUMERIC <= 32, "replay_opts_t.given holds one bit per numeric option");

/* The relative uncertainty of an inverter model the user gave without saying
 * how good it is: data-sheet dead times and drops are typically this close. */
#define INVERTER_UNCERTAINTY_GIVEN 0.2f

/* Whether the numeric option `name` was given. */
static int given(const replay_opts_t *o, const char *name)
{
  for (size_t k = 0; k < N_NUMERIC; ++k)
    if (strcmp(name, k_numeric[k].name) == 0) return (int)((o->given >> k) & 1u);
  return 0;
}

const char *replay_option_of(const replay_opts_t *o, const char *field, int *is_given)
{
  for (size_t k = 0; k < N_NUMERIC; ++k) {
    if (strcmp(field, k_numeric[k].field) == 0) {
      *is_given = (int)((o->given >> k) & 1u);
      return k_numeric[k].name;
    }
  }
  if (strcmp(field, "speed_limit_rad_s") == 0) {
    *is_given = o->speed_limit > 0;
    return "--speed-limit";
  }
  if (strncmp(field, "ls_curve_", 9) == 0) {
    *is_given = o->cfg.ls_curve_points > 0u;
    return "--ls-curve";
  }
  if (strcmp(field, "pole_pairs") == 0) {
    *is_given = 1;
    return "--pole-pairs";
  }
  if (strcmp(field, "pwm_timing") == 0) {
    *is_given = 1;
    return "--pwm-timing";
  }
  if (strcmp(field, "voltage_kind") == 0) {
    *is_given = 1;
    return "--voltage-kind";
  }
  *is_given = 0;
  return NULL;
}

/* The duty-cycle input's options make no sense for measured phase voltages
 * (they already contain the inverter's error): name the first one given. */
static int check_input_options(const replay_opts_t *o, int pwm_timing_given)
{
  if (o->voltage == REPLAY_VOLTAGE_DUTY) {
    if (o->u_limit >= 0) {
      fprintf(stderr,
              "%s: --u-limit applies to measured phase voltages; with --voltage duty the voltage "
              "comes from the duty cycles and has no ADC to clip\n",
              k_prog);
      return TOOL_EXIT_USAGE;
    }
    if (o->cfg.voltage_kind == IMEST_VOLTAGE_SMOOTH) {
      fprintf(stderr,
              "%s: --voltage-kind smooth applies to measured phase voltages; the voltage formed "
              "from the duty cycles is a PWM staircase by construction\n",
              k_prog);
      return TOOL_EXIT_USAGE;
    }
    return -1;
  }
  const char *opt = pwm_timing_given ? "--pwm-timing" : NULL;
  /* a deep-bar rotor: the inverter the measured voltages come from sizes its harmonics */
  const int hf = o->cfg.rotor_hf_rr_ratio > 0.0f;
  for (size_t k = 0; opt == NULL && k < N_NUMERIC; ++k)
    if (k_numeric[k].use != FOR_ANY && !hf && ((o->given >> k) & 1u)) opt = k_numeric[k].name;
  if (opt == NULL) return -1;
  fprintf(stderr,
          "%s: %s describes the duty-cycle input: give --voltage duty with the columns "
          "d_a,d_b,d_c,v_dc (measured phase voltages already contain the inverter's error)\n",
          k_prog, opt);
  return TOOL_EXIT_USAGE;
}

/* With a model of the inverter but no word on its quality: a data sheet's
 * numbers (INVERTER_UNCERTAINTY_GIVEN); without any model the library's
 * default stands (the error is unknown). */
static void default_uncertainty(replay_opts_t *o)
{
  if (given(o, "--inverter-uncertainty")) return;
  for (size_t k = 0; k < N_NUMERIC; ++k)
    if (k_numeric[k].use == FOR_INVERTER && ((o->given >> k) & 1u)) {
      o->cfg.inverter.uncertainty = INVERTER_UNCERTAINTY_GIVEN;
      return;
    }
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

/* --ls-curve I1:L1,I2:L2,...: the magnetising curve's points (2 .. IMEST_LS_CURVE_POINTS), in
   the config as given (imest_config_check() judges their order and signs). 0, or -1 after a
   message. */
static int parse_ls_curve(const char *v, replay_opts_t *o)
{
  const char *p = v;
  unsigned int n = 0;
  for (;;) {
    char *end = NULL;
    const double i = strtod(p, &end);
    if (end == p || *end != ':' || n >= IMEST_LS_CURVE_POINTS) break;
    p = end + 1;
    const double l = strtod(p, &end);
    if (end == p || !isfinite(i) || !isfinite(l)) break;
    o->cfg.ls_curve_i_a[n] = (float)i;
    o->cfg.ls_curve_h[n] = (float)l;
    n++;
    if (*end == '\0') {
      o->cfg.ls_curve_points = n;
      return 0;
    }
    if (*end != ',') break;
    p = end + 1;
  }
  fprintf(stderr,
          "%s: --ls-curve takes I1:L1,I2:L2,... (2 to %d points: current [A] alpha/beta amplitude, "
          "L_S [H]), not '%s'\n",
          k_prog, IMEST_LS_CURVE_POINTS, v);
  return -1;
}

/* --temperatures T_REF_C,RS_REF_OHM,TR_REF_S: three numbers into the temperature module's config
   (its other fields default; the ranges are checked once --ls is known). 0, or -1 after a message. */
static int parse_temperatures(const char *v, replay_opts_t *o)
{
  double x[3];
  const char *p = v;
  for (int k = 0; k < 3; k++) {
    char *end = NULL;
    x[k] = strtod(p, &end);
    if (end == p || !isfinite(x[k]) || *end != (k < 2 ? ',' : '\0')) {
      fprintf(stderr, "%s: --temperatures takes T_REF_C,RS_REF_OHM,TR_REF_S (three numbers), not '%s'\n",
              k_prog, v);
      return -1;
    }
    p = end + 1;
  }
  imest_temperature_config_default(&o->temp_cfg, (float)x[0], (float)x[1], (float)x[2], 1.0f);
  o->temperatures = 1;
  return 0;
}

int replay_parse(int argc, char **argv, replay_opts_t *o)
{
  memset(o, 0, sizeof *o);
  o->align_check = 1;
  imest_config_default(&o->cfg);
  o->can_iface = "vcan0";
  o->can_id = IMEST_CAN_DEFAULT_BASE_ID;
  o->i_limit = o->u_limit = -1.0;
  o->from_rest = -1;
  int have_np = 0, can_ext = 0, pwm_timing_given = 0;
  const char *can_id = NULL;
  double d;
  tool_args_t a;
  tool_args_init(&a, k_prog, argc, argv);
  tool_arg_kind_t kind;
  int std_rc;
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
      o->given |= 1ul << k;
    } else if ((std_rc = tool_args_standard(&a, usage)) >= 0) {
      return std_rc;
    } else if (tool_args_is(&a, "--pole-pairs")) {
      if (tool_args_number(&a, &d)) return TOOL_EXIT_USAGE;
      if (d < 1 || d > 64 || d != floor(d)) {
        fprintf(stderr, "%s: --pole-pairs must be an integer 1..64\n", k_prog);
        return TOOL_EXIT_USAGE;
      }
      o->cfg.pole_pairs = (unsigned int)d;
      have_np = 1;
    } else if (tool_args_is(&a, "--voltage")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (!strcmp(v, "phase"))
        o->voltage = REPLAY_VOLTAGE_PHASE;
      else if (!strcmp(v, "duty"))
        o->voltage = REPLAY_VOLTAGE_DUTY;
      else {
        fprintf(stderr, "%s: --voltage takes phase or duty, not '%s'\n", k_prog, v);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "--pwm-timing")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (!strcmp(v, "next"))
        o->cfg.pwm_timing = IMEST_PWM_NEXT_PERIOD;
      else if (!strcmp(v, "centred") || !strcmp(v, "centered"))
        o->cfg.pwm_timing = IMEST_PWM_CENTRED;
      else if (!strcmp(v, "last"))
        o->cfg.pwm_timing = IMEST_PWM_LAST_PERIOD;
      else {
        fprintf(stderr, "%s: --pwm-timing takes next, centred or last, not '%s'\n", k_prog, v);
        return TOOL_EXIT_USAGE;
      }
      pwm_timing_given = 1;
    } else if (tool_args_is(&a, "--voltage-kind")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (!strcmp(v, "staircase"))
        o->cfg.voltage_kind = IMEST_VOLTAGE_STAIRCASE;
      else if (!strcmp(v, "smooth"))
        o->cfg.voltage_kind = IMEST_VOLTAGE_SMOOTH;
      else {
        fprintf(stderr, "%s: --voltage-kind takes staircase or smooth, not '%s'\n", k_prog, v);
        return TOOL_EXIT_USAGE;
      }
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
    } else if (tool_args_is(&a, "--gaps")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (!strcmp(v, "refuse") || !strcmp(v, "restart")) {
        o->gaps_restart = !strcmp(v, "restart");
      } else {
        fprintf(stderr, "%s: --gaps takes refuse or restart, not '%s'\n", k_prog, v);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "-o") || tool_args_is(&a, "--output")) {
      if ((o->output_path = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--ls-curve")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (parse_ls_curve(v, o) != 0) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--temperatures")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (parse_temperatures(v, o) != 0) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--candump")) {
      if ((o->candump_path = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--candump-iface")) {
      if ((o->can_iface = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-iface")) {
      /* in every other tool --can-iface is a live SocketCAN interface */
      fprintf(stderr,
              "%s: --can-iface is now --candump-iface NAME: the interface name written into the "
              "--candump log (a label; imest-replay sends nothing on a bus)\n",
              k_prog);
      return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--require-valid")) {
      tool_require_t req;
      if (tool_args_require_valid(&a, &req)) return TOOL_EXIT_USAGE;
      o->require = (int)req;
    } else if (tool_args_is(&a, "--can-base-id") || tool_args_is(&a, "--can-id")) {
      if ((can_id = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-ext")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      can_ext = 1;
    } else if (tool_args_is(&a, "--quiet")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      o->quiet = 1;
    } else if (tool_args_is(&a, "--no-align-check")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      o->align_check = 0;
    } else {
      return tool_args_unknown(&a);
    }
  }
  if (!have_np || !given(o, "--ls") || !given(o, "--sigma")) {
    fprintf(stderr, "%s: --pole-pairs, --ls and --sigma are required (see --help)\n", k_prog);
    return TOOL_EXIT_USAGE;
  }
  if (o->temperatures) {
    o->temp_cfg.lr_h = o->cfg.ls_h; /* equal leakages */
    const char *field = NULL;
    if (imest_temperature_config_check(&o->temp_cfg, &field) != IMEST_OK) {
      fprintf(stderr, "%s: --temperatures: %s is out of range (imest_temperature.h)\n", k_prog,
              field ? field : "a reference");
      return TOOL_EXIT_USAGE;
    }
  }
  if (o->path == NULL) {
    fprintf(stderr, "%s: no input file (\"-\" reads stdin; see --help)\n", k_prog);
    return TOOL_EXIT_USAGE;
  }
  const int to_stdout = o->output_path == NULL || strcmp(o->output_path, "-") == 0;
  if (o->candump_path != NULL && strcmp(o->candump_path, "-") == 0 && to_stdout) {
    fprintf(stderr,
            "%s: --candump - writes the CAN frames to stdout, where the windows' CSV goes: "
            "give the CSV a file with -o FILE (or the frames one with --candump FILE)\n",
            k_prog);
    return TOOL_EXIT_USAGE;
  }
  const int rc = check_input_options(o, pwm_timing_given);
  if (rc >= 0) return rc;
  default_uncertainty(o);
  /* the same parser as imest-monitor's --can-base-id (port/canid) */
  o->can_id = IMEST_CAN_DEFAULT_BASE_ID | (can_ext ? IMEST_CAN_ID_EXT : 0u);
  char err[256];
  if (can_id != NULL && imest_can_id_parse(can_id, can_ext, "--can-ext", &o->can_id, err, sizeof err)) {
    fprintf(stderr, "%s: --can-base-id %s\n", k_prog, err);
    return TOOL_EXIT_USAGE;
  }
  return -1;
}
