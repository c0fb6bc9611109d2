/* SPDX-License-Identifier: Apache-2.0 */
#include "replay_advice.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "tool_args.h"

static const char *const k_prog = "imest-replay";

/* Where the sample rate came from, for messages that depend on it. */
static const char *fs_origin(const replay_opts_t *o)
{
  return o->fs_hz > 0 ? "--fs" : "t";
}

int replay_explain_config(const replay_opts_t *o, const replay_scan_t *s, const imest_config_t *cfg,
                          const char *field)
{
  int given = 0;
  const char *opt = replay_option_of(o, field, &given);
  const double fs = s->fs;
  const char *dflt = given ? "" : " (the default)";
  fprintf(stderr, "%s: ", k_prog);
  if (strcmp(field, "window_s") == 0) {
    fprintf(stderr,
            "--window %g s%s holds %.0f samples at %.6g Hz (from %s); a window needs 64 to 4e8 "
            "samples: give --window between %.3g and %.3g s\n",
            (double)cfg->window_s, dflt, (double)cfg->window_s * fs, fs, fs_origin(o), 64.0 / fs, 4e8 / fs);
  } else if (strcmp(field, "filter_hz") == 0) {
    /* measured on the simulated paper motor, 12-bit sensors (docs/feeding-logs.md) */
    fprintf(stderr,
            "the sample rate %.6g Hz (from %s) is too low for the front-end filter's cut-off, "
            "--filter-hz %g%s: the Butterworth filter needs fs above 2.5 x its cut-off (%.6g Hz). "
            "With the default 100 Hz the lowest usable rate is just above 250 Hz, for a record at "
            "constant speed; a record with fast speed changes (a direct-on-line start) needs "
            "about 1 kHz, because the derivatives lose (2 pi f/fs)^2/6 at the supply frequency f "
            "(9 %% at 60 Hz and 500 Hz). 100 Hz is the lowest cut-off that follows a run-up; "
            "for a record at constant speed, --filter-hz %.0f works at this rate.\n",
            fs, fs_origin(o), (double)cfg->filter_hz, dflt, 2.5 * (double)cfg->filter_hz, floor(fs / 5.0));
  } else if (strcmp(field, "aa_hz") == 0) {
    fprintf(stderr, "--aa-hz %g must be below 0.45 x the sample rate (%.6g Hz at %.6g Hz)\n",
            (double)cfg->aa_hz, 0.45 * fs, fs);
  } else if (strcmp(field, "u_delay_s") == 0) {
    fprintf(stderr,
            "--u-delay %g s must be within one sample period either way (|S| <= 1/fs = %.6g s at "
            "%.6g Hz)\n",
            (double)cfg->u_delay_s, 1.0 / fs, fs);
  } else if (strcmp(field, "pwm_hz") == 0) {
    fprintf(stderr,
            "--pwm-hz %g is below the sample rate %.6g Hz (from %s): a sample per carrier period "
            "at most; leave --pwm-hz out when the drive samples once per period\n",
            (double)cfg->pwm_hz, fs, fs_origin(o));
  } else if (strcmp(field, "inverter.dead_time_s") == 0) {
    const double fpwm = cfg->pwm_hz > 0.0f ? (double)cfg->pwm_hz : fs;
    fprintf(stderr,
            "--dead-time %g s must be below half a carrier period (%.6g s at %.6g Hz%s): is it in "
            "seconds (2e-6 for 2 us)?\n",
            (double)cfg->inverter.dead_time_s, 0.5 / fpwm, fpwm,
            cfg->pwm_hz > 0.0f ? "" : ", the sample rate");
  } else if (strcmp(field, "timing_uncertainty_s") == 0) {
    fprintf(stderr, "--timing-uncertainty %g s must be below one sample period (1/fs = %.6g s at %.6g Hz)\n",
            (double)cfg->timing_uncertainty_s, 1.0 / fs, fs);
  } else if (strcmp(field, "dc_block_hz") == 0) {
    fprintf(stderr,
            "--dc-block-hz %g%s must be between 0 and fs/100 (%.6g Hz at %.6g Hz from %s): "
            "give a lower one, or 0 for none\n",
            (double)cfg->dc_block_hz, dflt, 0.01 * fs, fs, fs_origin(o));
  } else if (strcmp(field, "speed_limit_rad_s") == 0) {
    fprintf(stderr,
            "--speed-limit %g rad/s is too high for %.6g Hz: the angle must move less than pi "
            "per sample, so the limit must stay below 3 x fs = %.6g rad/s\n",
            (double)cfg->speed_limit_rad_s, fs, 3.0 * fs);
  } else if (strcmp(field, "sigma") == 0) {
    fprintf(stderr, "--sigma %g: the leakage factor must be between 0 and 1\n", (double)cfg->sigma);
  } else if (strcmp(field, "tr_max_s") == 0) {
    fprintf(stderr, "--tr-max %g s must be above --tr-min %g s\n", (double)cfg->tr_max_s,
            (double)cfg->tr_min_s);
  } else if (opt != NULL) {
    fprintf(stderr, "%s: the value is out of range (see --help)\n", opt);
  } else {
    fprintf(stderr, "the estimator refuses its setting %s for this record (see --help)\n", field);
  }
  return given ? TOOL_EXIT_USAGE : TOOL_EXIT_DATA;
}

const char *replay_remedy(int status)
{
  switch (status) {
  case IMEST_REASON_INPUT_FAULT:
    return "samples are non-finite or absurd (beyond 1e4 A or 1e5 V): are the currents in A and "
           "the voltages in V (not mA, mV or ADC counts)?";
  case IMEST_REASON_ADC_SATURATION:
    return "currents or voltages sit at the ADC limit: the sensors clipped; if those plateaus are "
           "not clipping, give --i-limit 0 / --u-limit 0";
  case IMEST_REASON_ENCODER_FAULT:
    return "theta steps faster than --speed-limit: is theta the mechanical angle in rad (not "
           "degrees, encoder counts or the electrical angle)? If the motor really runs that "
           "fast, raise --speed-limit";
  case IMEST_REASON_WARMUP:
    return "the filters never settled: faults restart them, or the windows are shorter than "
           "the warm-up (a longer --window)";
  case IMEST_REASON_NO_CURRENT:
    return "the currents are below 0.05 A rms: is the motor running, and are the currents in A?";
  case IMEST_REASON_STANDSTILL:
  case IMEST_REASON_ZERO_SLIP:
    return "the rotor carries no current (no load at constant speed, or standstill): T_R is "
           "observable only under load or while the speed changes; record under load";
  case IMEST_REASON_NUMERIC: return "the window sums are degenerate: are the signals constant or all zero?";
  case IMEST_REASON_NO_ROOT:
  case IMEST_REASON_NOT_MINIMUM:
    return "the data contradict the motor model: check the current sign (positive into the "
           "motor), units (A; phase-to-neutral V), that theta increases with the a-b-c field, "
           "the motor constants (--pole-pairs, --ls, --sigma) and --u-delay";
  case IMEST_REASON_POORLY_DETERMINED:
    return "the data do not pin T_R down: too little slip (light load), noise, a coarse encoder, "
           "or a systematic error (voltage lag: --u-delay; uncompensated dead time); a longer "
           "--window helps against noise";
  case IMEST_REASON_HIGH_RESIDUAL:
    return "the data do not fit the model: are the voltages phase-to-neutral and dead-time "
           "compensated, --u-delay right, --ls and --sigma the motor's?";
  case IMEST_REASON_RS_OUT_OF_RANGE:
    return "R_S comes out negative or huge: the voltage scale (phase-to-phase instead of "
           "phase-to-neutral?), the current scale, or --u-delay";
  case IMEST_REASON_WIRING_MISMATCH:
    return "the data contradict the conventions: the current sign (positive into the motor), "
           "the encoder direction, the phase order, --pole-pairs, an electrical instead of a "
           "mechanical angle, or the units (A, V, rad)";
  case IMEST_REASON_CONSTANTS_MISMATCH:
    return "the motor constants cannot be this motor's (R_S far from what heating explains "
           "around --rs, T_R outside its band around a known --tr-nominal, or L_S measured at "
           "no load 6 % off --ls): check --ls, --sigma, --rs, and line-to-line voltages";
  case IMEST_REASON_RS_UNCERTAIN:
    return "R_S's error bound exceeds --rs-tolerance (T_R may still be valid: see the tr_valid "
           "column). With --voltage duty give the inverter's numbers (--dead-time, --v-switch, "
           "--v-diode ...) and how well they are known (--inverter-uncertainty); check "
           "--pwm-timing and --u-delay. Measured voltages from a sine source or a filtered "
           "channel (no PWM staircase): --voltage-kind smooth";
  case IMEST_REASON_TR_UNCERTAIN:
    return "T_R's error bound exceeds --tr-tolerance: light load at high speed, where the "
           "PWM staircase's aliased current (or the timing) moves T_R; a load of 25 % or more, "
           "or a lower speed, gives valid windows. With --voltage duty the inverter's voltage "
           "error bounds T_R too (its harmonics, at least 20 % of the modelled error): more "
           "load, or a smaller error (shorter dead time, lower drops), gives valid windows. "
           "With measured voltages from a PWM faster than the samples give its rate with "
           "--pwm-hz; from a sine source or a filtered channel, --voltage-kind smooth";
  case IMEST_REASON_CONSTANTS_UNCERTAIN:
    return "the stated uncertainty of the motor constants alone (--ls-uncertainty, default "
           "0.1, and --sigma-uncertainty, default 0.2: data-sheet values) moves T_R or R_S by "
           "more than their tolerance: commission the motor and give its constants with the "
           "uncertainty it states, or state how well --ls and --sigma are known";
  case IMEST_REASON_TRANSIENT:
    return "the speed changed inside the window (a load or speed step) faster than the angle "
           "observer follows, which moves T_R or R_S by more than their tolerance: the windows "
           "at steady speed around it are estimated; if most windows are transients, use "
           "windows shorter than the time between steps (--window), or turn the observer off "
           "(--angle-observer-hz -1) where the encoder is fine enough (16384 counts)";
  case IMEST_REASON_GAIN_MISMATCH:
    return "the three current sensors' gains differ by more than R_S tolerates: calibrate them";
  default: return NULL;
  }
}
