/* SPDX-License-Identifier: Apache-2.0 */
/* imest-sim: writes a simulated induction-motor record as CSV. A thin layer on the imsim API:
 * parse (flags -> imsim_config_t) and run (simulate, write rows, progress). */
#define _POSIX_C_SOURCE 200809L
#include "imsim_cli.h"

#include "tool_args.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const char HEADER[] =
    "t,u_a,u_b,u_c,i_a,i_b,i_c,theta,"
    "T_R_true_s,R_S_true_ohm,speed_rad_s,torque_nm,load_nm,psi_r_wb,temp_stator_c,temp_rotor_c,"
    "i_a_true,i_b_true,i_c_true,theta_true,u_a_true,u_b_true,u_c_true,"
    "ifoc_torque_ref_nm,ifoc_flux_ref_wb,ifoc_tr_s,ifoc_speed_ref_rad_s,"
    "d_a,d_b,d_c,v_dc";
/* Appended when a real-motor effect is on (sim/README.md, Real-motor effects). */
static const char HEADER_REAL[] = ",psi_m_wb,lm_h,lr_eff_h,rr_eff_ohm,p_fe_w,T_R_ifoc_s";

const char *imsim_cli_header(void)
{
  return HEADER;
}

const char *imsim_cli_header_real(void)
{
  return HEADER_REAL;
}

static const char USAGE[] =
    "usage: imest-sim [options]\n"
    "Simulates an induction motor (by default the one of Wang et al., IEEE TCST 2007) fed by an\n"
    "ideal source, a PWM inverter or an IFOC drive, and writes CSV: t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n"
    "(measured), truth columns, then the drive's d_a,d_b,d_c (duties applied from this row to the\n"
    "next, firmware timing) and v_dc (bus sample). Every flag is optional: the defaults are the\n"
    "preset's (exp1 when none is given); a flag given overrides the preset. --opt value and\n"
    "--opt=value both work.\n"
    "\n"
    "run:\n"
    "  --preset NAME         exp1: the paper's motor, 60 Hz, 230 V applied at standstill, no load,\n"
    "                        2 s; exp2: the paper's motor, 30 Hz V/f (115 V) at rated load\n"
    "                        2.064 N m, 3600 s; 4kw|11kw|15kw|37kw|75kw: a 400 V 50 Hz motor on a\n"
    "                        560 V 8 kHz drive (svpwm, firmware timing, fs 8 kHz), steady at\n"
    "                        rated load, 390 V 50 Hz, 10 s (see sim/README.md, Presets)\n"
    "  --duration S          simulated time, rows t = 0 .. S (exp1 2, exp2 3600)\n"
    "  --fs HZ               sample rate (4000)\n"
    "  -o, --output FILE     output file, '-' = stdout (-); --out FILE is the same (the older\n"
    "                        spelling; in the other tools --out names a folder)\n"
    "  --decimate N          write every N-th sample (1)\n"
    "  --progress, --no-progress   bar on stderr (default: when stderr is a terminal)\n"
    "  -h, --help            this text\n"
    "  --version             the version and licence\n"
    "motor (default: the paper's motor; resistances cold, at --t-amb):\n"
    "  --pole-pairs N (2)  --ls H (0.2908)  --lr H (0.2908)  --sigma X (0.096)\n"
    "  --rs OHM (5.04)  --tr S (0.12)  --j KGM2 (1.2e-3)  --b NMS (1e-4, viscous friction)\n"
    "supply:\n"
    "  --supply sine|vf|pwm|ifoc   ideal sine applied at once | ideal V/f ramp | PWM inverter on\n"
    "                        the V/f reference | IFOC driving the PWM inverter (exp1 sine, exp2 vf)\n"
    "  --vll V               line-to-line rms voltage (exp1 230, exp2 115)\n"
    "  --freq HZ             electrical frequency (exp1 60, exp2 30)\n"
    "  --vf-ramp S           V/f ramp from 0 to --freq (exp1 0 = at once, exp2 1)\n"
    "  --vf-boost V          V/f voltage at 0 Hz (0)\n"
    "  --start rest|steady   rest: standstill, zero flux; steady: the sinusoidal steady state at\n"
    "                        full load from t = 0 (IFOC: at --speed-ref and --load-nm, speed\n"
    "                        mode) (rest)\n"
    "PWM inverter (--supply pwm|ifoc):\n"
    "  --carrier-hz HZ (10000)  --vdc V (400)\n"
    "  --modulation spwm|svpwm   sine-triangle | min-max zero sequence (spwm)\n"
    "  --timing ideal|firmware   ideal: reference at every half period's centre; firmware:\n"
    "                        sample at a carrier valley every N = f_c/fs periods, duties from\n"
    "                        sample k applied during [t_k+1, t_k+2) (ideal)\n"
    "  --dead-time S         dead time incl. switching delays (0)\n"
    "  --v-switch V  --r-switch OHM  --v-diode V  --r-diode OHM   device drops, threshold +\n"
    "                        slope: switch V_sw + r_sw |i|, diode V_d + r_d |i| (0: ideal)\n"
    "  --pwm-segments        integrate piecewise between switching instants (reference accuracy,\n"
    "                        about 2.3x slower; default: one step per half carrier period)\n"
    "load:\n"
    "  --load-nm NM (exp1 0, exp2 2.064)  --load-on S (exp2 1.5)  --load-ramp S (exp2 1)\n"
    "  --load-kind passive|active   passive: friction-like, |NM| opposes the motion and holds\n"
    "                        a rotor at rest while the motor's torque is below it (a fan, pump,\n"
    "                        conveyor); active: NM opposes positive rotation at any speed and\n"
    "                        drives a stopped rotor backwards (a hoist's weight) (passive)\n"
    "  --load-step NM  --load-step-on S  --load-step-ramp S (0)   a second change of the load:\n"
    "                        from S, linearly from --load-nm to NM over the ramp (0 = a step);\n"
    "                        none unless --load-step-on is given\n"
    "IFOC (--supply ifoc):\n"
    "  --ifoc-mode speed|torque (speed)\n"
    "  --speed-ref RPM (exp1 1750, exp2 850)  --speed-ramp S (exp1 0.5, exp2 1)\n"
    "  --speed-step RPM  --speed-step-on S  --speed-step-ramp S (0)   speed mode: a second\n"
    "                        reference from S, reached linearly from --speed-ref over the ramp\n"
    "                        (0 = a step); none unless --speed-step-on is given\n"
    "  --torque-ref NM (0)  --torque-limit NM (4)\n"
    "  --ifoc-tr S           the controller's T_R (default: the motor's cold T_R)\n"
    "  --ifoc-flux WB        rotor-flux reference (default: the steady-state flux at --vll/--freq)\n"
    "  --ifoc-ideal-stage    ideal voltage source instead of the PWM inverter\n"
    "sensors:\n"
    "  --ideal-sensors       exact samples: no quantisation, noise, clipping, AA filter, encoder\n"
    "  --adc-bits N (12)  --i-range A (20)  --u-range V (400): ADC full scale is +-range\n"
    "  --vdc-range V         DC-bus ADC full scale, 0 .. V (800)\n"
    "  --noise-lsb X (1)     white Gaussian noise before the ADC, rms in LSB\n"
    "  --seed N (1)          noise seed\n"
    "  --encoder-counts N    counts per mechanical revolution (4096)\n"
    "  --i-offset A,A,A  --u-offset V,V,V  --i-gain-err X,X,X   per-phase (a,b,c) sensor offsets\n"
    "                        and relative gain errors, 0.01 = reads 1 % high (0,0,0)\n"
    "  --aa-hz HZ            2nd-order Butterworth anti-alias filter on every electrical\n"
    "                        channel (0 = off)\n"
    "  --vmeas auto|avg|aa|inst   voltage channel: avg = phase voltage from the commanded duties\n"
    "                        and Vdc (PWM only); aa = through the AA filter; inst = instantaneous\n"
    "                        (ideal supplies only); auto = avg with PWM, inst otherwise (auto)\n"
    "thermal:\n"
    "  --no-thermal          freeze R_S and R_R\n"
    "  --t-amb C (22)  --thermal-speedup X (1; multiplies both thermal rates)\n"
    "integrator:\n"
    "  --integrator fast|rk4 (fast; rk4 = slow reference)  --rk4-substeps N (8)\n"
    "  --steps-per-sample N  steps per sample for the ideal supplies (0 = auto: 5; PWM: fixed)\n"
    "real-motor effects (all off by default; any on: flux-linkage model, sub-stepped RK4, and the\n"
    "CSV gains psi_m_wb,lm_h,lr_eff_h,rr_eff_ohm,p_fe_w,T_R_ifoc_s; see sim/README.md, Real-motor\n"
    "effects):\n"
    "  --saturation F        main-flux saturation: static L_m at rated flux F below unsaturated,\n"
    "                        0 <= F < 0.6 (0)\n"
    "  --iron-loss F         core-loss resistance across the magnetising branch, sized to F x rated\n"
    "                        power at rated V/f, 0 <= F < 0.2 (0)\n"
    "  --rotor single|double-cage:RATIO   double cage whose R_R at rated frequency is RATIO x its\n"
    "                        DC value, 1 < RATIO <= 4 (single)\n"
    "  --real-motor          the preset's realistic sizes of all three (4kw: 0.25, 0.035, 1.3;\n"
    "                        11kw: 0.22, 0.03, 1.6; 15kw: 0.20, 0.025, 1.5; 37kw: 0.18, 0.02, 1.8;\n"
    "                        75kw: 0.15, 0.015, 2.0; exp1/exp2: 0.25, 0.04, 1.5); flags after it\n"
    "                        override\n"
    "\n"
    "Exit status: 0 done (a warning on stderr says when the PWM modulation was clipped; a note\n"
    "when the motor stalled: the load stopped it, or an active load turned it backwards);\n"
    "1 the output cannot be written; 2 a bad flag or value, or an impossible configuration.\n";

/* ---- parse ------------------------------------------------------------------------------ */

static int perr(char *err, size_t n, const char *a, const char *b)
{
  snprintf(err, n, "%s%s", a, b);
  return -1;
}

static int num(const char *s, double *v)
{
  if (s == NULL || *s == '\0') return -1;
  char *end = NULL;
  errno = 0;
  const double d = strtod(s, &end);
  if (errno != 0 || end == s || *end != '\0' || !isfinite(d)) return -1;
  *v = d;
  return 0;
}

static int inum(const char *s, long *v)
{
  if (s == NULL || *s == '\0') return -1;
  char *end = NULL;
  errno = 0;
  const long d = strtol(s, &end, 10);
  if (errno != 0 || end == s || *end != '\0') return -1;
  *v = d;
  return 0;
}

#define CFG(field) offsetof(imsim_config_t, field)
/* INFINITY is a float; the bounds are double (clang's -Wdouble-promotion). */
#define NONE_LO    (-(double)INFINITY)
#define NONE_HI    ((double)INFINITY)

/* Real-valued flags: value in (lo, hi) or [lo, hi] as lo_open/hi_open say. */
typedef struct {
  const char *flag;
  size_t off;
  double lo, hi;
  bool lo_open, hi_open;
  const char *what;
} real_flag;

static const real_flag REAL_FLAGS[] = {
    {"--duration", CFG(duration_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--fs", CFG(fs_hz), 0.0, NONE_HI, true, true, "> 0 Hz"},
    {"--ls", CFG(ls_h), 0.0, NONE_HI, true, true, "> 0 H"},
    {"--lr", CFG(lr_h), 0.0, NONE_HI, true, true, "> 0 H"},
    {"--sigma", CFG(sigma), 0.0, 1.0, true, true, "0 < sigma < 1"},
    {"--rs", CFG(rs_ohm), 0.0, NONE_HI, true, true, "> 0 ohm"},
    {"--tr", CFG(tr_s), 0.0, NONE_HI, true, true, "> 0 s"},
    {"--j", CFG(j_kgm2), 0.0, NONE_HI, true, true, "> 0 kg m^2"},
    {"--b", CFG(b_nms), 0.0, NONE_HI, false, true, ">= 0 N m s"},
    {"--vll", CFG(vll_v), 0.0, NONE_HI, false, true, ">= 0 V"},
    {"--freq", CFG(freq_hz), 0.0, NONE_HI, false, true, ">= 0 Hz"},
    {"--vf-ramp", CFG(vf_ramp_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--vf-boost", CFG(vf_boost_v), 0.0, NONE_HI, false, true, ">= 0 V"},
    {"--load-nm", CFG(load_nm), NONE_LO, NONE_HI, true, true, "N m"},
    {"--load-on", CFG(load_on_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--load-ramp", CFG(load_ramp_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--load-step", CFG(load_step_nm), NONE_LO, NONE_HI, true, true, "N m"},
    {"--load-step-on", CFG(load_step_on_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--load-step-ramp", CFG(load_step_ramp_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--carrier-hz", CFG(carrier_hz), 0.0, NONE_HI, true, true, "> 0 Hz"},
    {"--vdc", CFG(vdc_v), 0.0, NONE_HI, true, true, "> 0 V"},
    {"--dead-time", CFG(dead_time_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--v-switch", CFG(v_switch_v), 0.0, NONE_HI, false, true, ">= 0 V"},
    {"--r-switch", CFG(r_switch_ohm), 0.0, NONE_HI, false, true, ">= 0 ohm"},
    {"--v-diode", CFG(v_diode_v), 0.0, NONE_HI, false, true, ">= 0 V"},
    {"--r-diode", CFG(r_diode_ohm), 0.0, NONE_HI, false, true, ">= 0 ohm"},
    {"--vdc-range", CFG(vdc_range_v), 0.0, NONE_HI, true, true, "> 0 V"},
    {"--ifoc-tr", CFG(ifoc_tr_s), 0.0, NONE_HI, true, true, "> 0 s"},
    {"--ifoc-flux", CFG(ifoc_flux_wb), 0.0, NONE_HI, true, true, "> 0 Wb"},
    {"--speed-ref", CFG(speed_ref_rpm), NONE_LO, NONE_HI, true, true, "rpm"},
    {"--speed-ramp", CFG(speed_ramp_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--speed-step", CFG(speed_step_rpm), NONE_LO, NONE_HI, true, true, "rpm"},
    {"--speed-step-on", CFG(speed_step_on_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--speed-step-ramp", CFG(speed_step_ramp_s), 0.0, NONE_HI, false, true, ">= 0 s"},
    {"--torque-ref", CFG(torque_ref_nm), NONE_LO, NONE_HI, true, true, "N m"},
    {"--torque-limit", CFG(torque_limit_nm), 0.0, NONE_HI, true, true, "> 0 N m"},
    {"--i-range", CFG(i_range_a), 0.0, NONE_HI, true, true, "> 0 A"},
    {"--u-range", CFG(u_range_v), 0.0, NONE_HI, true, true, "> 0 V"},
    {"--noise-lsb", CFG(noise_lsb), 0.0, NONE_HI, false, true, ">= 0 LSB"},
    {"--aa-hz", CFG(aa_hz), 0.0, NONE_HI, false, true, ">= 0 Hz (0 = off)"},
    {"--t-amb", CFG(t_amb_c), -273.15, NONE_HI, true, true, "degC"},
    {"--thermal-speedup", CFG(thermal_speedup), 0.0, NONE_HI, true, true, "> 0"},
    {"--saturation", CFG(sat_fraction), 0.0, 0.6, false, true, "0 <= F < 0.6"},
    {"--iron-loss", CFG(iron_loss_fraction), 0.0, 0.2, false, true, "0 <= F < 0.2"},
};

/* Integer flags (int fields), value in [lo, hi]. */
typedef struct {
  const char *flag;
  size_t off;
  long lo, hi;
} int_flag;

static const int_flag INT_FLAGS[] = {
    {"--pole-pairs", CFG(pole_pairs), 1, 64},
    {"--adc-bits", CFG(adc_bits), 2, 30},
    {"--encoder-counts", CFG(encoder_counts), 1, 1000000000},
    {"--rk4-substeps", CFG(rk4_substeps), 1, 100000},
    {"--steps-per-sample", CFG(steps_per_sample), 0, 100000},
};

/* Flags that name one of a few choices (enum fields, stored as int). */
_Static_assert(sizeof(imsim_supply_t) == sizeof(int) && sizeof(imsim_vmeas_t) == sizeof(int) &&
                   sizeof(imsim_start_t) == sizeof(int) && sizeof(imsim_ifoc_mode_t) == sizeof(int) &&
                   sizeof(imsim_integrator_t) == sizeof(int) && sizeof(imsim_timing_t) == sizeof(int) &&
                   sizeof(imsim_modulation_t) == sizeof(int) && sizeof(imsim_load_kind_t) == sizeof(int),
               "choice flags store enums as int");
typedef struct {
  const char *flag;
  size_t off;
  const char *names[5]; /* NULL-terminated */
  int values[5];
} choice_flag;

static const choice_flag CHOICE_FLAGS[] = {
    {"--supply",
     CFG(supply),
     {"sine", "vf", "pwm", "ifoc", NULL},
     {IMSIM_SUPPLY_SINE, IMSIM_SUPPLY_VF, IMSIM_SUPPLY_PWM, IMSIM_SUPPLY_IFOC, 0}},
    {"--vmeas",
     CFG(vmeas),
     {"auto", "avg", "aa", "inst", NULL},
     {IMSIM_VMEAS_AUTO, IMSIM_VMEAS_AVG, IMSIM_VMEAS_AA, IMSIM_VMEAS_INST, 0}},
    {"--start",
     CFG(start),
     {"rest", "steady", NULL, NULL, NULL},
     {IMSIM_START_REST, IMSIM_START_STEADY, 0, 0, 0}},
    {"--ifoc-mode",
     CFG(ifoc_mode),
     {"speed", "torque", NULL, NULL, NULL},
     {IMSIM_IFOC_SPEED, IMSIM_IFOC_TORQUE, 0, 0, 0}},
    {"--integrator",
     CFG(integrator),
     {"fast", "rk4", NULL, NULL, NULL},
     {IMSIM_INTEGRATOR_FAST, IMSIM_INTEGRATOR_RK4, 0, 0, 0}},
    {"--timing",
     CFG(timing),
     {"ideal", "firmware", NULL, NULL, NULL},
     {IMSIM_TIMING_IDEAL, IMSIM_TIMING_FIRMWARE, 0, 0, 0}},
    {"--modulation",
     CFG(modulation),
     {"spwm", "svpwm", NULL, NULL, NULL},
     {IMSIM_MOD_SPWM, IMSIM_MOD_SVPWM, 0, 0, 0}},
    {"--load-kind",
     CFG(load_kind),
     {"passive", "active", NULL, NULL, NULL},
     {IMSIM_LOAD_PASSIVE, IMSIM_LOAD_ACTIVE, 0, 0, 0}},
};

/* Per-phase flags: three comma-separated numbers for phases a, b, c. */
typedef struct {
  const char *flag;
  size_t off;
} phase_flag;

static const phase_flag PHASE_FLAGS[] = {
    {"--i-offset", CFG(i_offset_a)},
    {"--u-offset", CFG(u_offset_v)},
    {"--i-gain-err", CFG(i_gain_err)},
};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static void *field(imsim_config_t *c, size_t off)
{
  return (char *)c + off;
}

/* Flags without a value, and the valued flags handled one by one in parse_valued. */
static const char *const SWITCH_FLAGS[] = {"--help",        "--version",          "--ideal-sensors",
                                           "--no-thermal",  "--ifoc-ideal-stage", "--progress",
                                           "--no-progress", "--pwm-segments",     "--real-motor"};
static const char *const OTHER_FLAGS[] = {"--preset", "--output", "--out", "--decimate", "--seed", "--rotor"};

size_t imsim_cli_flags(const char **names, size_t max)
{
  size_t n = 0;
#define ADD(x)                                                                                               \
  do {                                                                                                       \
    if (n < max) names[n] = (x);                                                                             \
    ++n;                                                                                                     \
  } while (0)
  for (size_t k = 0; k < COUNT(SWITCH_FLAGS); ++k) ADD(SWITCH_FLAGS[k]);
  for (size_t k = 0; k < COUNT(OTHER_FLAGS); ++k) ADD(OTHER_FLAGS[k]);
  for (size_t k = 0; k < COUNT(PHASE_FLAGS); ++k) ADD(PHASE_FLAGS[k].flag);
  for (size_t k = 0; k < COUNT(CHOICE_FLAGS); ++k) ADD(CHOICE_FLAGS[k].flag);
  for (size_t k = 0; k < COUNT(REAL_FLAGS); ++k) ADD(REAL_FLAGS[k].flag);
  for (size_t k = 0; k < COUNT(INT_FLAGS); ++k) ADD(INT_FLAGS[k].flag);
#undef ADD
  return n;
}

const char *imsim_cli_usage(void)
{
  return USAGE;
}

/* Flags without a value. Returns 1 if name is one (and applies it), 0 otherwise. */
static int parse_switch(const char *name, imsim_config_t *c, imsim_cli_opts_t *o)
{
  if (strcmp(name, "--help") == 0)
    o->help = 1;
  else if (strcmp(name, "--version") == 0)
    o->version = 1;
  else if (strcmp(name, "--ideal-sensors") == 0)
    c->ideal_sensors = true;
  else if (strcmp(name, "--no-thermal") == 0)
    c->thermal = false;
  else if (strcmp(name, "--ifoc-ideal-stage") == 0)
    c->ifoc_ideal_stage = true;
  else if (strcmp(name, "--progress") == 0)
    o->progress = 1;
  else if (strcmp(name, "--no-progress") == 0)
    o->progress = 0;
  else if (strcmp(name, "--pwm-segments") == 0)
    c->pwm_moments = false;
  else if (strcmp(name, "--real-motor") == 0)
    imsim_config_real_motor(c);
  else
    return 0;
  return 1;
}

/* Flags with a value. Returns 0 (applied), -1 (bad value, message in err) or 1 (unknown). */
static int parse_valued(const char *name, const char *val, imsim_config_t *c, imsim_cli_opts_t *o, char *err,
                        size_t errlen)
{
  if (strcmp(name, "--preset") == 0) return 0; /* applied in the first pass */
  if (strcmp(name, "--output") == 0 || strcmp(name, "--out") == 0) {
    if (val[0] == '\0') return perr(err, errlen, "empty value for ", name);
    o->out = val;
    return 0;
  }
  long l = 0;
  if (strcmp(name, "--decimate") == 0) {
    if (inum(val, &l) != 0 || l < 1)
      return perr(err, errlen, "invalid value for --decimate (integer >= 1): ", val);
    o->decimate = l;
    return 0;
  }
  if (strcmp(name, "--seed") == 0) {
    char *end = NULL;
    errno = 0;
    const unsigned long long u = strtoull(val, &end, 10);
    if (errno != 0 || end == val || *end != '\0' || val[0] == '-')
      return perr(err, errlen, "invalid value for --seed (unsigned integer): ", val);
    c->seed = (uint64_t)u;
    return 0;
  }
  if (strcmp(name, "--rotor") == 0) {
    static const char DC[] = "double-cage:";
    double r = 0.0;
    if (strcmp(val, "single") == 0) {
      c->rotor_cage_ratio = 0.0;
    } else if (strncmp(val, DC, sizeof DC - 1) == 0 && num(val + sizeof DC - 1, &r) == 0 && r > 1.0 &&
               r <= 4.0) {
      c->rotor_cage_ratio = r;
    } else {
      return perr(err, errlen, "invalid value for --rotor (single|double-cage:RATIO, 1 < RATIO <= 4): ", val);
    }
    return 0;
  }
  for (size_t k = 0; k < COUNT(PHASE_FLAGS); ++k) {
    if (strcmp(name, PHASE_FLAGS[k].flag) != 0) continue;
    double *per_phase = field(c, PHASE_FLAGS[k].off);
    const char *p = val;
    for (int q = 0; q < 3; ++q) {
      char *end = NULL;
      const double x = strtod(p, &end);
      if (end == p || !isfinite(x) || (q < 2 ? *end != ',' : *end != '\0'))
        return perr(err, errlen, "expected three comma-separated numbers (phases a,b,c) for ", name);
      per_phase[q] = x;
      p = end + 1;
    }
    return 0;
  }
  for (size_t k = 0; k < COUNT(CHOICE_FLAGS); ++k) {
    const choice_flag *f = &CHOICE_FLAGS[k];
    if (strcmp(name, f->flag) != 0) continue;
    char list[64] = "";
    for (int q = 0; f->names[q] != NULL; ++q) {
      if (strcmp(val, f->names[q]) == 0) {
        memcpy(field(c, f->off), &f->values[q], sizeof(int));
        return 0;
      }
      if (q > 0) strncat(list, "|", sizeof list - strlen(list) - 1);
      strncat(list, f->names[q], sizeof list - strlen(list) - 1);
    }
    snprintf(err, errlen, "invalid value for %s (%s): %s", name, list, val);
    return -1;
  }
  for (size_t k = 0; k < COUNT(REAL_FLAGS); ++k) {
    const real_flag *f = &REAL_FLAGS[k];
    if (strcmp(name, f->flag) != 0) continue;
    double d = 0.0;
    const bool ok =
        num(val, &d) == 0 && (f->lo_open ? d > f->lo : d >= f->lo) && (f->hi_open ? d < f->hi : d <= f->hi);
    if (!ok) {
      snprintf(err, errlen, "invalid value for %s: '%s' (%s)", name, val, f->what);
      return -1;
    }
    *(double *)field(c, f->off) = d;
    return 0;
  }
  for (size_t k = 0; k < COUNT(INT_FLAGS); ++k) {
    const int_flag *f = &INT_FLAGS[k];
    if (strcmp(name, f->flag) != 0) continue;
    if (inum(val, &l) != 0 || l < f->lo || l > f->hi) {
      snprintf(err, errlen, "invalid value for %s: '%s' (integer %ld..%ld)", name, val, f->lo, f->hi);
      return -1;
    }
    *(int *)field(c, f->off) = (int)l;
    return 0;
  }
  return 1;
}

/* Whether name is a flag that takes a value (so that an unknown flag is not read as one missing
   its value). */
static int is_valued(const char *name)
{
  for (size_t k = 0; k < COUNT(OTHER_FLAGS); ++k)
    if (strcmp(name, OTHER_FLAGS[k]) == 0) return 1;
  for (size_t k = 0; k < COUNT(PHASE_FLAGS); ++k)
    if (strcmp(name, PHASE_FLAGS[k].flag) == 0) return 1;
  for (size_t k = 0; k < COUNT(CHOICE_FLAGS); ++k)
    if (strcmp(name, CHOICE_FLAGS[k].flag) == 0) return 1;
  for (size_t k = 0; k < COUNT(REAL_FLAGS); ++k)
    if (strcmp(name, REAL_FLAGS[k].flag) == 0) return 1;
  for (size_t k = 0; k < COUNT(INT_FLAGS); ++k)
    if (strcmp(name, INT_FLAGS[k].flag) == 0) return 1;
  return 0;
}

static int unknown(char *err, size_t n, const char *name)
{
  snprintf(err, n, "unknown option '%s'", name);
  return -1;
}

/* Pass 1: the preset, wherever it stands, so that every other flag overrides it. */
static int parse_preset(int argc, char **argv, imsim_config_t *c, char *err, size_t errlen)
{
  imsim_config_default(c);
  for (int a = 1; a < argc; ++a) {
    const char *arg = argv[a];
    const char *val = NULL;
    // argv[a] for a < argc is never NULL (C11 5.1.2.2.1); the analyzer infers one from the test of
    // val = argv[a + 1] below
    // NOLINTNEXTLINE(clang-analyzer-core.NonNullParamChecker): see the line above
    if (strncmp(arg, "--preset=", 9) == 0)
      val = arg + 9;
    else if (strcmp(arg, "--preset") == 0) {
      if (a + 1 >= argc) return perr(err, errlen, "missing value for ", arg);
      val = argv[a + 1];
    }
    if (val != NULL && imsim_config_preset(c, val) != 0) {
      snprintf(err, errlen, "unknown preset (%s): %s", imsim_preset_names(), val);
      return -1;
    }
  }
  return 0;
}

int imsim_cli_parse(int argc, char **argv, imsim_config_t *c, imsim_cli_opts_t *o, char *err, size_t errlen)
{
  o->out = "-";
  o->decimate = 1;
  o->progress = -1;
  o->help = 0;
  o->version = 0;
  err[0] = '\0';
  if (parse_preset(argc, argv, c, err, errlen) != 0) return -1;
  /* pass 2: every flag, in order (--opt value or --opt=value) */
  for (int a = 1; a < argc; ++a) {
    char name[64];
    const char *arg = argv[a];
    if (strcmp(arg, "-h") == 0) {
      o->help = 1;
      continue;
    }
    if (strcmp(arg, "-o") == 0) { /* -o FILE: --output FILE */
      if (a + 1 >= argc) return perr(err, errlen, "missing value for ", arg);
      const int r = parse_valued("--output", argv[++a], c, o, err, errlen);
      if (r != 0) return -1;
      continue;
    }
    if (strncmp(arg, "--", 2) != 0) {
      if (arg[0] == '-' && arg[1] != '\0') return unknown(err, errlen, arg);
      return perr(err, errlen, "unexpected argument: ", arg);
    }
    const char *eq = strchr(arg, '=');
    const size_t len = eq != NULL ? (size_t)(eq - arg) : strlen(arg);
    if (len >= sizeof name) return unknown(err, errlen, arg);
    memcpy(name, arg, len);
    name[len] = '\0';
    const char *val = eq != NULL ? eq + 1 : NULL;
    if (parse_switch(name, c, o)) {
      if (eq != NULL) return perr(err, errlen, "flag takes no value: ", name);
      continue;
    }
    if (!is_valued(name)) return unknown(err, errlen, name);
    if (val == NULL) {
      if (a + 1 >= argc) return perr(err, errlen, "missing value for ", name);
      val = argv[++a];
    }
    const int r = parse_valued(name, val, c, o, err, errlen);
    if (r < 0) return -1;
    if (r > 0) return unknown(err, errlen, name);
  }
  return 0;
}

/* ---- run -------------------------------------------------------------------------------- */

/* %.9g is exact to ~1e-9 relative, which is what the spec asks for. */
void imsim_cli_write_row(FILE *f, const imsim_sample_t *s)
{
  fprintf(f,
          "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,"
          "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g",
          s->t, s->u_abc[0], s->u_abc[1], s->u_abc[2], s->i_abc[0], s->i_abc[1], s->i_abc[2], s->theta,
          s->tr_s, s->rs_ohm, s->speed_rad_s, s->torque_nm, s->load_nm, s->psi_r_wb, s->temp_stator_c,
          s->temp_rotor_c, s->i_abc_true[0], s->i_abc_true[1], s->i_abc_true[2], s->theta_true,
          s->u_abc_true[0], s->u_abc_true[1], s->u_abc_true[2], s->ifoc_torque_ref_nm, s->ifoc_flux_ref_wb,
          s->ifoc_tr_s, s->ifoc_speed_ref_rad_s, s->duty[0], s->duty[1], s->duty[2], s->vdc_v);
  /* real-motor truth: only when an effect is on (NaN otherwise), so that the record of the
     linear machine keeps its columns */
  if (!isnan(s->psi_m_wb))
    fprintf(f, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", s->psi_m_wb, s->lm_h, s->lr_eff_h, s->rr_eff_ohm, s->p_fe_w,
            s->tr_ifoc_s);
  fputc('\n', f);
}

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Progress bar on stderr. */
typedef struct {
  int on;
  double t0_wall, total_s;
  uint64_t total, next, step;
} progress;

static void progress_start(progress *p, int on, uint64_t total, double total_s)
{
  p->on = on;
  p->t0_wall = now_s();
  p->total = total;
  p->total_s = total_s;
  p->next = 0;
  p->step = total / 200u + 1u;
}

static void progress_update(progress *p, uint64_t n, double t)
{
  if (!p->on || n < p->next) return;
  p->next = n + p->step;
  const double frac = (double)n / (double)p->total;
  const int w = (int)(frac * 40.0);
  char line[48];
  for (int k = 0; k < 40; ++k) line[k] = k < w ? '#' : ' ';
  line[40] = '\0';
  fprintf(stderr, "\r[%s] %5.1f%%  %.1f/%.1f s motor  %.1f s wall  ", line, 100.0 * frac, t, p->total_s,
          now_s() - p->t0_wall);
  fflush(stderr);
}

/* Opens the output ('-' = stdout) with a large buffer. NULL on failure (message printed). */
static FILE *open_output(const char *path)
{
  static char buf[1 << 20];
  FILE *f = stdout;
  if (strcmp(path, "-") != 0) {
    f = fopen(path, "w");
    if (f == NULL) {
      fprintf(stderr, "imest-sim: cannot open '%s': %s\n", path, strerror(errno));
      return NULL;
    }
  }
  setvbuf(f, buf, _IOFBF, sizeof buf);
  return f;
}

/* A bus too low for the reference saturates the inverter, as in a real drive: the run is
   valid, but the voltage is not the commanded one, so say so with the numbers. */
static void report_clipping(const imsim_t *sim, const imsim_config_t *c)
{
  imsim_pwm_stats_t st;
  imsim_get_pwm_stats(sim, &st);
  if (st.clipped_half_periods == 0u) return;
  fprintf(
      stderr,
      "imest-sim: warning: the PWM reference exceeded the DC bus in %.3g %% of the half carrier periods "
      "(%llu of %llu) and was clipped: it needs Vdc >= %.1f V, given --vdc %.1f V. The applied voltage is "
      "not the commanded sine; raise --vdc or lower --vll.\n",
      100.0 * (double)st.clipped_half_periods / (double)st.half_periods,
      (unsigned long long)st.clipped_half_periods, (unsigned long long)st.half_periods, st.vdc_needed_v,
      c->vdc_v);
}

/* A motor that the load stops is no longer at the operating point the flags describe: say so
   when it happens (note_stall) and at the end (report_stall), with the numbers. */
static void note_stall(const imsim_t *sim, const imsim_config_t *c)
{
  imsim_stall_t st;
  imsim_get_stall(sim, &st);
  const double w_sync = 2.0 * 3.14159265358979323846 * c->freq_hz / (double)c->pole_pairs;
  fprintf(stderr,
          "imest-sim: note: the motor stalled at t = %.4f s: the load (%.4g N m) exceeded the motor's torque "
          "(%.4g N m) and %s (--freq %.4g Hz, synchronous speed %.4g rad/s)\n",
          st.first_t_s, st.first_load_nm, st.first_torque_nm,
          c->load_kind == IMSIM_LOAD_ACTIVE ? "turned the rotor backwards (active load)"
                                            : "the rotor stopped (speed 0 rad/s)",
          c->freq_hz, w_sync);
}

static void report_stall(const imsim_t *sim, const imsim_config_t *c)
{
  imsim_stall_t st;
  imsim_get_stall(sim, &st);
  if (st.events == 0u && !st.at_rest_now) return;
  if (st.events == 0u) {
    fprintf(
        stderr,
        "imest-sim: note: the motor did not start: the load holds the rotor at rest at the end of the run "
        "(%.4g s at rest in all)\n",
        st.held_s);
    return;
  }
  fprintf(stderr,
          "imest-sim: note: stalled: %llu stall%s, the first at t = %.4f s (load %.4g N m, motor torque "
          "%.4g N m); %.4g s held at rest by the load%s. The record is not of a running motor; "
          "lower --load-nm or raise --vll.%s\n",
          (unsigned long long)st.events, st.events == 1u ? "" : "s", st.first_t_s, st.first_load_nm,
          st.first_torque_nm, st.held_s, st.at_rest_now ? ", at rest at the end" : "",
          c->load_kind == IMSIM_LOAD_ACTIVE ? " (active load: the rotor was turned backwards)" : "");
}

/* Simulates c and writes the CSV. Returns the exit status. */
static int run(const imsim_config_t *c, const imsim_cli_opts_t *o)
{
  static imsim_t sim;
  imsim_sample_t smp;
  if (imsim_init(&sim, c, &smp) != 0) {
    fprintf(stderr, "imest-sim: %s\n", imsim_error(&sim));
    return 2;
  }
  FILE *f = open_output(o->out);
  if (f == NULL) return 1;
  const uint64_t total = (uint64_t)llround(c->duration_s * c->fs_hz);
  progress bar;
  progress_start(&bar, o->progress < 0 ? isatty(STDERR_FILENO) : o->progress, total, c->duration_s);
  fprintf(f, "%s%s\n", HEADER, isnan(smp.psi_m_wb) ? "" : HEADER_REAL);
  imsim_cli_write_row(f, &smp);
  bool stall_noted = false;
  for (uint64_t n = 1; n <= total; ++n) {
    imsim_step(&sim, &smp);
    if (sim.stall_events != 0u && !stall_noted) {
      stall_noted = true;
      if (bar.on) fprintf(stderr, "\n");
      note_stall(&sim, c);
    }
    if ((n % (uint64_t)o->decimate) == 0u) imsim_cli_write_row(f, &smp);
    progress_update(&bar, n, smp.t);
  }
  if (bar.on) fprintf(stderr, "\n");
  report_clipping(&sim, c);
  report_stall(&sim, c);
  int rc = 0;
  if (fflush(f) != 0 || ferror(f)) {
    fprintf(stderr, "imest-sim: write error\n");
    rc = 1;
  }
  if (f != stdout && fclose(f) != 0) rc = 1;
  return rc;
}

int imsim_cli_main(int argc, char **argv)
{
  imsim_config_t c;
  imsim_cli_opts_t o;
  char err[256];
  if (imsim_cli_parse(argc, argv, &c, &o, err, sizeof err) != 0) {
    fprintf(stderr, "imest-sim: %s\nTry 'imest-sim --help'.\n", err);
    return TOOL_EXIT_USAGE;
  }
  if (o.help) {
    fputs(USAGE, stdout);
    return TOOL_EXIT_OK;
  }
  if (o.version) {
    tool_version("imest-sim");
    return TOOL_EXIT_OK;
  }
  return run(&c, &o);
}
