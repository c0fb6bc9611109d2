/* SPDX-License-Identifier: Apache-2.0 */
/* Prints imest_config_default() field by field, straight from the C struct
 * (one "name value" line each, floats as exact hex %a): the reference the
 * Python module's defaults are compared with (test_imest.py). Written out by
 * hand on purpose, so that it shares nothing with the module's field table
 * in python/imest/_shim.c. */
#include <stdio.h>

#include "imest/imest.h"

_Static_assert(sizeof(imest_config_t) == 58 * sizeof(float),
               "imest_config_t changed: list the new field below");

#define F(name) printf(#name " %a\n", (double)cfg.name)
#define I(name) printf(#name " %d\n", (int)cfg.name)

int main(void)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  I(pole_pairs);
  F(ls_h);
  F(sigma);
  F(ls_uncertainty);
  F(sigma_uncertainty);
  F(fs_hz);
  F(window_s);
  F(filter_hz);
  F(aa_hz);
  F(u_delay_s);
  F(angle_observer_hz);
  F(encoder_counts_per_rev);
  F(dc_block_hz);
  F(warmup_s);
  I(start_at_rest);
  F(pwm_hz);
  I(pwm_timing);
  I(voltage_kind);
  F(inverter.dead_time_s);
  F(inverter.v_switch_v);
  F(inverter.r_switch_ohm);
  F(inverter.v_diode_v);
  F(inverter.r_diode_ohm);
  F(inverter.i_band_a);
  F(inverter.edge_band_a);
  F(inverter.uncertainty);
  F(tr_nominal_s);
  I(tr_nominal_known);
  F(tr_min_s);
  F(tr_max_s);
  F(rs_min_ohm);
  F(rs_max_ohm);
  F(max_pe_k2_rel);
  F(max_ei);
  F(min_current_a);
  F(min_slip_ratio);
  F(rs_tolerance);
  F(tr_tolerance);
  F(u_uncertainty_v);
  F(timing_uncertainty_s);
  F(rs_nominal_ohm);
  F(rotor_hf_rr_ratio);
  F(rotor_hf_sigma_ratio);
  F(inverter_vdc_v);
  F(ls_curve_i_a[0]);
  F(ls_curve_i_a[1]);
  F(ls_curve_i_a[2]);
  F(ls_curve_i_a[3]);
  F(ls_curve_h[0]);
  F(ls_curve_h[1]);
  F(ls_curve_h[2]);
  F(ls_curve_h[3]);
  I(ls_curve_points);
  F(i_limit_a);
  F(u_limit_v);
  F(i_absurd_a);
  F(u_absurd_v);
  F(speed_limit_rad_s);
  return 0;
}
