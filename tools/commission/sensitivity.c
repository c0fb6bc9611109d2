/* SPDX-License-Identifier: Apache-2.0 */
/* How well to commission: the online estimator's T_R and R_S error per 1 % error in L_S and in
 * sigma and per 0.1 V error of the inverter's voltage-error model, measured on the simulator
 * (imest-commission --sensitivity). Host code. */
#include "commission_sensitivity.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commission_sim.h"
#include "drive_loop.h"

typedef struct {
  double t_from; /* windows ending after this count */
  double tr, rs;
  int n, n_valid;
} sens_acc_t;

static void on_window(void *ctx, const imest_result_t *r)
{
  sens_acc_t *a = (sens_acc_t *)ctx;
  if (r->t_end_s < a->t_from || !isfinite(r->tr_s) || !isfinite(r->rs_ohm)) return;
  a->tr += r->tr_s;
  a->rs += r->rs_ohm;
  a->n++;
  a->n_valid += r->tr_valid ? 1 : 0;
}

/* One run: the estimator with L_S x ls_k and sigma x sig_k, and dv_v of voltage error per leg
   in phase with the leg's current: added to the measured phase voltages, or (duty-cycle input)
   taken off the inverter model's thresholds, which leaves the same error in its voltage. */
static int run_one(const comm_sens_opts_t *o, double ls_k, double sig_k, double dv_v, comm_sens_run_t *out)
{
  imsim_config_t sc;
  if (o->duty) { /* the commissioned drive of imest-commission: 2 us, 1 V / 0.8 V devices */
    comm_sim_opts_t co;
    if (comm_sim_defaults(&co, o->preset) != 0 || comm_sim_operating(&co, o->load_frac, &sc) != 0) return -1;
  } else {
    if (imsim_config_preset(&sc, o->preset) != 0) return -1;
    sc.start = IMSIM_START_STEADY;
    sc.load_nm = o->load_frac * (sc.rated_torque_nm > 0.0 ? sc.rated_torque_nm : 2.064); /* the paper's */
  }
  sc.thermal = false;
  sc.seed = o->seed;
  imsim_t *sim = (imsim_t *)calloc(1, sizeof *sim);
  imest_t *est = (imest_t *)calloc(1, sizeof *est);
  imsim_sample_t s;
  int rc = -1;
  if (sim == NULL || est == NULL || imsim_init(sim, &sc, &s) != 0) {
    if (sim != NULL) fprintf(stderr, "sensitivity: simulator: %s\n", imsim_error(sim));
    goto done;
  }
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = (unsigned int)sc.pole_pairs;
  cfg.ls_h = (float)(sc.ls_h * ls_k);
  cfg.sigma = (float)(sc.sigma * sig_k);
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = (float)sc.fs_hz;
  cfg.tr_nominal_s = (float)sc.tr_s;
  if (sc.supply == IMSIM_SUPPLY_PWM && !o->duty) cfg.u_delay_s = (float)(0.5 / sc.fs_hz); /* last period's */
  if (o->duty) {
    cfg.pwm_hz = (float)sc.carrier_hz;
    cfg.inverter.dead_time_s = (float)sc.dead_time_s;
    cfg.inverter.v_switch_v = (float)(sc.v_switch_v - dv_v);
    cfg.inverter.r_switch_ohm = (float)sc.r_switch_ohm;
    cfg.inverter.v_diode_v = (float)(sc.v_diode_v - dv_v);
    cfg.inverter.r_diode_ohm = (float)sc.r_diode_ohm;
    cfg.inverter.uncertainty = 0.05f;
  }
  if (imest_init(est, &cfg) != IMEST_OK) {
    const char *field = NULL;
    (void)imest_config_check(&cfg, &field);
    fprintf(stderr, "sensitivity: estimator config: bad %s\n", field ? field : "?");
    goto done;
  }
  sens_acc_t acc = {o->settle_s, 0.0, 0.0, 0, 0};
  drive_t d;
  drive_init(&d, est, on_window, &acc);
  const long n = lround(o->duration_s * sc.fs_hz);
  for (long k = 0; k < n; ++k) {
    if (o->duty) {
      const float dd[3] = {(float)s.duty[0], (float)s.duty[1], (float)s.duty[2]};
      const float ii[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
      if (imest_isr_duty(est, dd, (float)s.vdc_v, ii, drive_wrap_angle(s.theta))) {
        imest_result_t r;
        while (imest_background(est, &r) == 1) on_window(&acc, &r);
      }
      imsim_step(sim, &s);
      continue;
    }
    double u[3] = {s.u_abc[0], s.u_abc[1], s.u_abc[2]};
    if (dv_v != 0.0) {
      double e[3], m = 0.0;
      for (int x = 0; x < 3; ++x) {
        e[x] = s.i_abc[x] > 0.0 ? dv_v : -dv_v;
        m += e[x] / 3.0;
      }
      for (int x = 0; x < 3; ++x) u[x] += e[x] - m;
    }
    if (drive_sample(&d, u, s.i_abc, s.theta) < 0) goto done;
    imsim_step(sim, &s);
  }
  if (acc.n == 0) goto done;
  out->tr_rel = acc.tr / acc.n / sc.tr_s - 1.0;
  out->rs_rel = acc.rs / acc.n / sc.rs_ohm - 1.0;
  out->windows = acc.n;
  out->valid = acc.n_valid;
  rc = 0;
done:
  free(sim);
  free(est);
  return rc;
}

int comm_sensitivity(const comm_sens_opts_t *o, comm_sens_t *out)
{
  memset(out, 0, sizeof *out);
  if (run_one(o, 1.0, 1.0, 0.0, &out->base) != 0) return -1;
  comm_sens_run_t p, m;
  if (run_one(o, 1.01, 1.0, 0.0, &p) != 0 || run_one(o, 0.99, 1.0, 0.0, &m) != 0) return -1;
  out->tr_per_ls = 0.5 * (p.tr_rel - m.tr_rel);
  out->rs_per_ls = 0.5 * (p.rs_rel - m.rs_rel);
  if (run_one(o, 1.0, 1.01, 0.0, &p) != 0 || run_one(o, 1.0, 0.99, 0.0, &m) != 0) return -1;
  out->tr_per_sigma = 0.5 * (p.tr_rel - m.tr_rel);
  out->rs_per_sigma = 0.5 * (p.rs_rel - m.rs_rel);
  if (run_one(o, 1.0, 1.0, 0.1, &p) != 0 || run_one(o, 1.0, 1.0, -0.1, &m) != 0) return -1;
  out->tr_per_dv = 0.5 * (p.tr_rel - m.tr_rel);
  out->rs_per_dv = 0.5 * (p.rs_rel - m.rs_rel);
  return 0;
}
