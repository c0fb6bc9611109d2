/* SPDX-License-Identifier: Apache-2.0 */
/* Commission, then estimate: the routine identifies the drive (commission_sim.c), then the online
 * estimator runs on the same drive at a steady load with the identified constants and inverter
 * model and the duty-cycle input (imest_isr_duty), as a firmware without voltage sensors would.
 * Host code (imest-commission --online, test/commission). */
#include "commission_online.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
  double t_from;
  double tr, rs, tr_all, rs_all;
  int n, n_tr, n_rs, n_all;
} online_acc_t;

int comm_online_run(const comm_sim_opts_t *o, double load_frac, double duration_s,
                    const imest_comm_result_t *id, comm_online_t *out)
{
  memset(out, 0, sizeof *out);
  imsim_config_t sc;
  if (comm_sim_operating(o, load_frac, &sc) != 0) return -1; /* the same drive, now in operation */
  imsim_t *sim = (imsim_t *)calloc(1, sizeof *sim);
  imest_t *est = (imest_t *)calloc(1, sizeof *est);
  imsim_sample_t s;
  int rc = -1;
  if (sim == NULL || est == NULL || imsim_init(sim, &sc, &s) != 0) goto done;
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.fs_hz = (float)sc.fs_hz;
  cfg.pwm_hz = (float)sc.carrier_hz;
  if (id != NULL) {
    /* a rotor the routine flags as deep-bar or double cage: sigma from the data sheet (here the
       preset's: its equivalent circuit at rated load), as the header tells the user */
    cfg.sigma = (float)sc.sigma;
    if (imest_comm_apply(id, &cfg) < 0) goto done;
  } else { /* the true constants and devices (for comparison) */
    cfg.pole_pairs = (unsigned int)sc.pole_pairs;
    cfg.ls_h = (float)sc.ls_h;
    cfg.sigma = (float)sc.sigma;
    cfg.ls_uncertainty = 0.0f; /* exact */
    cfg.sigma_uncertainty = 0.0f;
    cfg.tr_nominal_s = (float)sc.tr_s;
    cfg.inverter.dead_time_s = (float)sc.dead_time_s;
    cfg.inverter.v_switch_v = (float)sc.v_switch_v;
    cfg.inverter.r_switch_ohm = (float)sc.r_switch_ohm;
    cfg.inverter.v_diode_v = (float)sc.v_diode_v;
    cfg.inverter.r_diode_ohm = (float)sc.r_diode_ohm;
    cfg.inverter.uncertainty = 0.05f;
  }
  if (imest_init(est, &cfg) != IMEST_OK) goto done;
  online_acc_t acc = {0.3 * duration_s, 0, 0, 0, 0, 0, 0, 0, 0}; /* windows after the first 30 % */
  const long n = lround(duration_s * sc.fs_hz);
  double tr_sum = 0.0, rs_sum = 0.0;
  int last_reason = 0;
  long in_win = 0;
  for (long k = 0; k < n; ++k) {
    const float d[3] = {(float)s.duty[0], (float)s.duty[1], (float)s.duty[2]};
    const float i[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
    const double two_pi = 6.283185307179586;
    double th = fmod(s.theta, two_pi);
    if (th < 0.0) th += two_pi;
    tr_sum += s.tr_s;
    rs_sum += s.rs_ohm;
    in_win++;
    if (imest_isr_duty(est, d, (float)s.vdc_v, i, (float)th)) {
      imest_result_t r;
      const double tr_t = tr_sum / (double)in_win, rs_t = rs_sum / (double)in_win;
      tr_sum = rs_sum = 0.0;
      in_win = 0;
      while (imest_background(est, &r) == 1) {
        if (r.t_end_s < acc.t_from) continue;
        last_reason = r.status;
        acc.n++;
        if (isfinite(r.tr_s) && isfinite(r.rs_ohm)) {
          acc.tr_all += r.tr_s / tr_t - 1.0;
          acc.rs_all += r.rs_ohm / rs_t - 1.0;
          acc.n_all++;
        }
        if (r.tr_valid && isfinite(r.tr_s)) {
          acc.tr += r.tr_s / tr_t - 1.0;
          acc.n_tr++;
        }
        if (r.rs_valid && isfinite(r.rs_ohm)) {
          acc.rs += r.rs_ohm / rs_t - 1.0;
          acc.n_rs++;
        }
      }
    }
    imsim_step(sim, &s);
  }
  out->windows = acc.n;
  out->tr_valid = acc.n_tr;
  out->rs_valid = acc.n_rs;
  out->tr_rel = acc.n_tr ? acc.tr / acc.n_tr : (double)NAN;
  out->rs_rel = acc.n_rs ? acc.rs / acc.n_rs : (double)NAN;
  out->tr_all_rel = acc.n_all ? acc.tr_all / acc.n_all : (double)NAN;
  out->rs_all_rel = acc.n_all ? acc.rs_all / acc.n_all : (double)NAN;
  out->reason = out->windows > 0 ? last_reason : 0;
  rc = 0;
done:
  free(sim);
  free(est);
  return rc;
}
