/* SPDX-License-Identifier: Apache-2.0 */
/* Prints what imest_config_default() sets, one "field value" line per field
 * of imest_config_t (inverter fields as inverter.NAME), then "sizeof imest_t
 * N" for this host. test_documented_defaults.py compares it with the
 * defaults the header's comments and imest-replay --help state, and checks
 * that every field the header declares is listed here; likewise the T_R
 * tracker's imest_tracker_config_default() (tracker.NAME) and the temperature module's
 * imest_temperature_config_default() (temperature.NAME). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>

#include "imest/imest.h"
#include "imest/imest_temperature.h"
#include "imest/imest_tracker.h"

#define F(name)                                                                                              \
  {                                                                                                          \
#name, offsetof(imest_config_t, name)                                                                    \
  }

static const struct {
  const char *name;
  size_t offset;
} k_float[] = {
    F(ls_h),
    F(sigma),
    F(ls_uncertainty),
    F(sigma_uncertainty),
    F(fs_hz),
    F(window_s),
    F(filter_hz),
    F(aa_hz),
    F(u_delay_s),
    F(angle_observer_hz),
    F(encoder_counts_per_rev),
    F(dc_block_hz),
    F(warmup_s),
    F(pwm_hz),
    F(inverter.dead_time_s),
    F(inverter.v_switch_v),
    F(inverter.r_switch_ohm),
    F(inverter.v_diode_v),
    F(inverter.r_diode_ohm),
    F(inverter.i_band_a),
    F(inverter.edge_band_a),
    F(inverter.uncertainty),
    F(tr_nominal_s),
    F(tr_min_s),
    F(tr_max_s),
    F(rs_min_ohm),
    F(rs_max_ohm),
    F(max_pe_k2_rel),
    F(max_ei),
    F(min_current_a),
    F(min_slip_ratio),
    F(rs_tolerance),
    F(tr_tolerance),
    F(u_uncertainty_v),
    F(timing_uncertainty_s),
    F(rs_nominal_ohm),
    F(rotor_hf_rr_ratio),
    F(rotor_hf_sigma_ratio),
    F(inverter_vdc_v),
    F(i_limit_a),
    F(u_limit_v),
    F(i_absurd_a),
    F(u_absurd_v),
    F(speed_limit_rad_s),
};

int main(void)
{
  imest_config_t c;
  imest_config_default(&c);
  for (size_t k = 0; k < sizeof k_float / sizeof k_float[0]; ++k) {
    const float v = *(const float *)(const void *)((const char *)&c + k_float[k].offset);
    printf("%s %.9g\n", k_float[k].name, (double)v);
  }
  /* an array field: the largest |element| (every one is the documented default, or this differs) */
  float ci = 0.0f, ch = 0.0f;
  for (int k = 0; k < IMEST_LS_CURVE_POINTS; ++k) {
    ci = fabsf(c.ls_curve_i_a[k]) > ci ? fabsf(c.ls_curve_i_a[k]) : ci;
    ch = fabsf(c.ls_curve_h[k]) > ch ? fabsf(c.ls_curve_h[k]) : ch;
  }
  printf("ls_curve_i_a %.9g\n", (double)ci);
  printf("ls_curve_h %.9g\n", (double)ch);
  printf("ls_curve_points %u\n", c.ls_curve_points);
  printf("pole_pairs %u\n", c.pole_pairs);
  printf("start_at_rest %d\n", c.start_at_rest);
  printf("tr_nominal_known %d\n", c.tr_nominal_known);
  printf("pwm_timing %s\n", c.pwm_timing == IMEST_PWM_NEXT_PERIOD ? "NEXT_PERIOD"
                            : c.pwm_timing == IMEST_PWM_CENTRED   ? "CENTRED"
                                                                  : "LAST_PERIOD");
  printf("voltage_kind %s\n", c.voltage_kind == IMEST_VOLTAGE_STAIRCASE ? "IMEST_VOLTAGE_STAIRCASE"
                              : c.voltage_kind == IMEST_VOLTAGE_SMOOTH  ? "IMEST_VOLTAGE_SMOOTH"
                                                                        : "?");
  /* the T_R tracker's defaults (imest_tracker.h), as tracker.NAME; the nominal T_R is the
     caller's argument, not a default */
  imest_tracker_config_t t;
  imest_tracker_config_default(&t, 0.1f);
  printf("tracker.nominal_bound_rel %.9g\n", (double)t.nominal_bound_rel);
  printf("tracker.rate_rel_per_s %.9g\n", (double)t.rate_rel_per_s);
  printf("tracker.stale_after_s %.9g\n", (double)t.stale_after_s);
  printf("tracker.fallback_rel_per_s %.9g\n", (double)t.fallback_rel_per_s);
  printf("tracker.gate_min_rel %.9g\n", (double)t.gate_min_rel);
  printf("tracker.confirm_windows %u\n", t.confirm_windows);
  printf("tracker.acquire_jump %d\n", t.acquire_jump);
  /* the temperature module's defaults (imest_temperature.h), as temperature.NAME; the references
     and L_R are the caller's */
  imest_temperature_config_t m;
  imest_temperature_config_default(&m, 20.0f, 1.0f, 0.1f, 0.2f);
  printf("temperature.t_ref_uncert_k %.9g\n", (double)m.t_ref_uncert_k);
  printf("temperature.rs_ref_bound_rel %.9g\n", (double)m.rs_ref_bound_rel);
  printf("temperature.tr_ref_bound_rel %.9g\n", (double)m.tr_ref_bound_rel);
  printf("temperature.stator_k_c %.9g\n", (double)m.stator_k_c);
  printf("temperature.rotor_k_c %.9g\n", (double)m.rotor_k_c);
  printf("temperature.stator_tol_k %.9g\n", (double)m.stator_tol_k);
  printf("temperature.rotor_tol_k %.9g\n", (double)m.rotor_tol_k);
  printf("sizeof imest_t %zu\n", sizeof(imest_t));
  return 0;
}
