/* SPDX-License-Identifier: Apache-2.0 */
/* The commissioning routine closed loop on the simulator: imsim with an external controller
 * (IMSIM_SUPPLY_EXT, firmware timing, PWM inverter with dead time and device drops, 12-bit
 * sensors with offsets and gain errors, encoder), the routine's ISR call per sample and its
 * background call every millisecond, as a drive runs them. Host code, shared by
 * imest-commission, the tests (test/commission) and the demo. */
#ifndef IMEST_COMMISSION_SIM_H
#define IMEST_COMMISSION_SIM_H

#include <stdio.h>

#include "imest/imest_commission.h"
#include "imsim/imsim.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { COMM_SIM_OFF_SATURATION = 1, COMM_SIM_OFF_IRON_LOSS = 2, COMM_SIM_OFF_DOUBLE_CAGE = 4 };

typedef struct {
  char preset[16];    /* imsim preset: 4kw, 11kw, 15kw, 37kw, 75kw, exp1 (paper motor) */
  double dead_time_s; /* inverter (defaults: 2 us, 1 V + r_sw, 0.8 V + r_d) */
  double v_switch_v, r_switch_ohm, v_diode_v, r_diode_ohm;
  double i_offset_a[3]; /* sensor offsets [A] */
  double i_gain_err[3]; /* sensor gain errors (0.01 = 1 % high) */
  int ideal_sensors;    /* exact currents and angle (no ADC, noise, encoder) */
  int encoder_counts;   /* true counts per revolution (default 4096) */
  double cpr_assumed;   /* what the firmware assumes (default: the true counts) */
  int encoder_reversed; /* the angle counts against the a-b-c field */
  int swap_sensors_bc;  /* current channels b and c swapped (wiring error) */
  int encoder_stuck;    /* the angle never changes (encoder not connected) */
  int two_sensors;      /* the firmware computes i_c = -i_a - i_b (gain mismatch not observable) */
  int allow_rotation;
  int nameplate_speed; /* give the routine the rated speed (n_p from the nameplate) */
  double speed_frac;   /* V/f speed, fraction of rated (0: routine default) */
  double i_max_a;      /* 0: sqrt(2) x rated current */
  double r_series_ohm; /* known series resistance passed to the routine */
  /* real-motor effects (sim/README.md, Real-motor effects): real_motor turns on the three at the
     preset's sizes; a field above 0 sets (or overrides) that effect; a bit of real_off turns
     it off even with real_motor (COMM_SIM_OFF_*: the same motor as imest-sim's --real-motor
     --iron-loss 0 ...) */
  int real_motor;
  double sat_fraction, iron_loss_fraction, rotor_cage_ratio;
  unsigned int real_off;
  unsigned long seed;
  double max_time_s; /* simulated time limit (default 400) */
  FILE *trace;       /* per-sample CSV (t, stage, currents, duties, speed), or NULL */
  unsigned int trace_decimate;
} comm_sim_opts_t;

typedef struct {
  /* truth; L_S, sigma, sigma*L_S, T_R, L_m and R_R' at the rated flux at no load (the stator
     flux amplitude at rated voltage and frequency, rated_voltage_v / (2 pi rated_freq_hz) less
     the R_S drop, the flux the routine's rotating run aims at): with saturation they depend on
     the flux (comm_sim_true_at); for a linear motor they are the preset's */
  double rs_ohm, ls_h, sigma, sigma_ls_h, tr_s, lm_h, rr_ohm;
  double i_rated_flux_a; /* magnetising current at that flux (alpha/beta amplitude) [A] */
  double ls_preset_h;    /* the preset's L_S (= ls_h for a linear motor) */
  unsigned int pole_pairs;
  double rs_identifiable_ohm;      /* winding + min(r_sw, r_d): what terminal measurements can see */
  double i_peak_true_a;            /* largest true phase current */
  double theta_max_standstill_rad; /* rotor travel during the standstill part */
  /* inverter: the fitted model against the simulator's device model, per leg */
  double ripple_peak_a; /* the PWM current ripple's peak, V_dc / (8 sigma L_S f_pwm), from the result */
  double
      inv_err_model_v; /* max |e_fit - (e_true - min(r_sw,r_d) i)| over |i| in [2 ripple, i_max], d in [0.05, 0.95] */
  double
      inv_err_total_v; /* max |e_fit + (R_S,id - R_S) i - e_true| (what the estimator's voltage would miss) */
  double inv_err_rms_v; /* rms of the latter over the same grid */
  /* run */
  double sim_time_s;
  double stage_s[IMEST_COMM_STAGE_END + 1];     /* time spent in each stage (imest_comm_stage_t) */
  double stage_ipk_a[IMEST_COMM_STAGE_END + 1]; /* largest true phase current in each stage */
  imsim_config_t sim;
  imest_comm_config_t cc;
  imest_comm_result_t r;
  imest_comm_axis_fit_t fit[3]; /* per-axis fits (diagnostics) */
} comm_sim_out_t;

/* Defaults for a preset: the inverter and sensors of the README's Commissioning table. 0, or
   -1 for an unknown preset. */
int comm_sim_defaults(comm_sim_opts_t *o, const char *preset);

/* The simulator configuration for the options (drive, sensors, inverter; no load, at rest). */
int comm_sim_config(const comm_sim_opts_t *o, imsim_config_t *sc);

/* The same drive in operation (after commissioning): V/f at its rated point (the presets' 390 V,
   50 Hz; the paper's motor at its exp. 2 point, 30 Hz 115 V), in steady state at load_frac of
   rated torque (the paper's: 2.064 N m), firmware timing (duty columns). 0, or -1. */
int comm_sim_operating(const comm_sim_opts_t *o, double load_frac, imsim_config_t *sc);

/* The routine's configuration for that drive (fs, carrier, limits, nameplate). */
void comm_sim_comm_config(const comm_sim_opts_t *o, const imsim_config_t *sc, imest_comm_config_t *cc);

/* The motor's constants at no load with a magnetising current of amplitude i_a (alpha/beta) [A]:
   L_S, sigma and T_R = L_R / R_R(DC) with the static L_m at that current (sim/README.md,
   Magnetising curve); the preset's for a linear motor. Any output may be NULL. 0, or -1. */
int comm_sim_true_at(const imsim_config_t *sc, double i_a, double *ls_h, double *sigma, double *tr_s);

/* The magnetising current (alpha/beta amplitude) at which the no-load stator flux L_S(i) i is psi_wb. */
double comm_sim_current_at_flux(const imsim_config_t *sc, double psi_wb);

/* Run the routine closed loop. Returns 0 when it ran (out->r says whether it succeeded), -1 on a
   simulator set-up error (message on stderr). */
int comm_sim_run(const comm_sim_opts_t *o, comm_sim_out_t *out);

/* The per-leg voltage error of the simulator's devices (sim/README.md, Inverter) for a phase
   current i and duty d, and of the library's model (imest.h, imest_inverter_t). */
double comm_sim_true_leg_error(const imsim_config_t *sc, double i, double d);
double comm_sim_model_leg_error(const imest_inverter_t *m, double vdc, double fpwm, double i, double d);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_COMMISSION_SIM_H */
