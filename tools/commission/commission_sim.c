/* SPDX-License-Identifier: Apache-2.0 */
/* The commissioning routine closed loop on the simulator (commission_sim.h). */
#include "commission_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TWO_PI 6.283185307179586476925

int comm_sim_defaults(comm_sim_opts_t *o, const char *preset)
{
  memset(o, 0, sizeof *o);
  imsim_config_t sc;
  if (imsim_config_preset(&sc, preset) != 0) return -1;
  snprintf(o->preset, sizeof o->preset, "%s", preset);
  /* an IGBT inverter: 2 us dead time, switch 1 V and diode 0.8 V thresholds, slope resistances
     scaled with the drive's current (the 4 kW drive's 0.02 / 0.01 ohm of sim/README.md) */
  const double i_rated = sc.rated_current_a > 0.0 ? sc.rated_current_a : 1.6;
  o->dead_time_s = 2e-6;
  o->v_switch_v = 1.0;
  o->v_diode_v = 0.8;
  o->r_switch_ohm = 0.02 * 8.2 / i_rated;
  o->r_diode_ohm = 0.01 * 8.2 / i_rated;
  /* sensors: offsets of 1 % / 0.6 % / 0.4 % of full scale, gains +1 %, -0.4 %, -0.6 % (zero mean:
     a common gain error is not observable and scales R_S and L_S one to one) */
  const double fs_i = sc.i_range_a;
  o->i_offset_a[0] = 0.010 * fs_i;
  o->i_offset_a[1] = -0.006 * fs_i;
  o->i_offset_a[2] = 0.004 * fs_i;
  o->i_gain_err[0] = 0.010;
  o->i_gain_err[1] = -0.004;
  o->i_gain_err[2] = -0.006;
  o->encoder_counts = 4096;
  o->cpr_assumed = 0.0;
  o->allow_rotation = 1;
  o->nameplate_speed = sc.rated_speed_rpm > 0.0;
  o->seed = 1;
  o->max_time_s = 400.0;
  o->trace_decimate = 1;
  return 0;
}

int comm_sim_config(const comm_sim_opts_t *o, imsim_config_t *sc)
{
  if (imsim_config_preset(sc, o->preset) != 0) return -1;
  const int paper = sc->rated_power_w <= 0.0; /* exp1/exp2: the paper's motor */
  sc->supply = IMSIM_SUPPLY_EXT;
  sc->timing = IMSIM_TIMING_FIRMWARE;
  sc->modulation = IMSIM_MOD_SVPWM;
  if (paper) {
    /* its drive: 230 V rectified, 8 kHz, one sample per period, +-10 A current sensors */
    sc->vdc_v = 325.0;
    sc->carrier_hz = 8000.0;
    sc->fs_hz = 8000.0;
    sc->i_range_a = 10.0;
    sc->vdc_range_v = 500.0;
    sc->rated_voltage_v = 230.0;
    sc->rated_freq_hz = 60.0;
    sc->rated_current_a = 1.6;
  }
  sc->start = IMSIM_START_REST;
  sc->load_nm = 0.0;
  sc->thermal = false;
  sc->dead_time_s = o->dead_time_s;
  sc->v_switch_v = o->v_switch_v;
  sc->r_switch_ohm = o->r_switch_ohm;
  sc->v_diode_v = o->v_diode_v;
  sc->r_diode_ohm = o->r_diode_ohm;
  sc->ideal_sensors = o->ideal_sensors != 0;
  sc->encoder_counts = o->encoder_counts > 0 ? o->encoder_counts : 4096;
  for (int x = 0; x < 3; ++x) {
    sc->i_offset_a[x] = o->i_offset_a[x];
    sc->i_gain_err[x] = o->i_gain_err[x];
  }
  sc->seed = o->seed;
  sc->steps_per_sample = 0;
  if (o->real_motor) imsim_config_real_motor(sc);
  if (o->sat_fraction > 0.0) sc->sat_fraction = o->sat_fraction;
  if (o->iron_loss_fraction > 0.0) sc->iron_loss_fraction = o->iron_loss_fraction;
  if (o->rotor_cage_ratio > 0.0) sc->rotor_cage_ratio = o->rotor_cage_ratio;
  if (o->real_off & COMM_SIM_OFF_SATURATION) sc->sat_fraction = 0.0;
  if (o->real_off & COMM_SIM_OFF_IRON_LOSS) sc->iron_loss_fraction = 0.0;
  if (o->real_off & COMM_SIM_OFF_DOUBLE_CAGE) sc->rotor_cage_ratio = 0.0;
  return 0;
}

int comm_sim_true_at(const imsim_config_t *sc, double i_a, double *ls_h, double *sigma, double *tr_s)
{
  imsim_real_params_t p;
  if (imsim_real_params(sc, &p) != 0) return -1;
  const double m0 = sqrt((1.0 - sc->sigma) * sc->ls_h * sc->lr_h), rr = sc->lr_h / sc->tr_s;
  double lm = m0, lls = sc->ls_h - m0, llr = sc->lr_h - m0;
  if (p.lm0_h > 0.0 && p.sat_a > 0.0 && i_a > 0.0) {
    /* no load: i_a = psi/L_m0 (1 + a (psi/psi_n)^6), increasing in psi: bisection */
    double lo = 0.0, hi = p.lm0_h * i_a;
    for (int it = 0; it < 200; ++it) {
      const double psi = 0.5 * (lo + hi), q = psi / p.psi_n_wb;
      const double im = psi / p.lm0_h * (1.0 + p.sat_a * q * q * q * q * q * q);
      if (im > i_a)
        hi = psi;
      else
        lo = psi;
    }
    lm = 0.5 * (lo + hi) / i_a;
  } else if (p.lm0_h > 0.0) {
    lm = p.lm0_h;
  }
  if (p.lm0_h > 0.0) {
    lls = p.lls_h;
    llr = p.llr_h;
  }
  if (ls_h) *ls_h = lls + lm;
  if (sigma) *sigma = 1.0 - lm * lm / ((lls + lm) * (llr + lm));
  if (tr_s) *tr_s = (llr + lm) / rr;
  return 0;
}

double comm_sim_current_at_flux(const imsim_config_t *sc, double psi_wb)
{
  /* L_S(i) i increases with i (the static curve's flux does): bisection */
  double lo = 0.0, hi = psi_wb / (sc->ls_h * (1.0 - sc->sigma)) * 4.0;
  for (int it = 0; it < 200; ++it) {
    const double i = 0.5 * (lo + hi);
    double ls = sc->ls_h;
    (void)comm_sim_true_at(sc, i, &ls, NULL, NULL);
    if (ls * i > psi_wb)
      hi = i;
    else
      lo = i;
  }
  return 0.5 * (lo + hi);
}

int comm_sim_operating(const comm_sim_opts_t *o, double load_frac, imsim_config_t *sc)
{
  if (comm_sim_config(o, sc) != 0) return -1;
  sc->supply = IMSIM_SUPPLY_PWM;
  sc->timing = IMSIM_TIMING_FIRMWARE;
  sc->start = IMSIM_START_STEADY;
  if (sc->rated_torque_nm > 0.0) {
    sc->load_nm = load_frac * sc->rated_torque_nm;
  } else {
    sc->freq_hz = 30.0;
    sc->vll_v = 115.0;
    sc->load_nm = load_frac * 2.064;
  }
  return 0;
}

void comm_sim_comm_config(const comm_sim_opts_t *o, const imsim_config_t *sc, imest_comm_config_t *cc)
{
  imest_comm_config_default(cc);
  cc->fs_hz = (float)sc->fs_hz;
  cc->pwm_hz = (float)sc->carrier_hz;
  cc->i_max_a = (float)(o->i_max_a > 0.0 ? o->i_max_a : sqrt(2.0) * sc->rated_current_a);
  cc->encoder_cpr = (float)(o->cpr_assumed > 0.0 ? o->cpr_assumed : (double)sc->encoder_counts);
  cc->r_series_ohm = (float)o->r_series_ohm;
  cc->n_sensors = o->two_sensors ? 2u : 3u;
  cc->allow_rotation = o->allow_rotation;
  cc->rated_voltage_v = (float)sc->rated_voltage_v;
  cc->rated_freq_hz = (float)sc->rated_freq_hz;
  cc->rated_speed_rpm = o->nameplate_speed ? (float)sc->rated_speed_rpm : 0.0f;
  if (o->speed_frac > 0.0) cc->speed_frac = (float)o->speed_frac;
}

double comm_sim_true_leg_error(const imsim_config_t *sc, double i, double d)
{
  /* sim/README.md, Inverter: the mean leg voltage's departure from d V_dc over a period */
  const double f = sc->carrier_hz, td = sc->dead_time_s, vdc = sc->vdc_v;
  const double vs = sc->v_switch_v, rs = sc->r_switch_ohm, vd = sc->v_diode_v, rd = sc->r_diode_ohm;
  if (i > 0.0)
    return td * f * (vdc - vs - rs * i + vd + rd * i) + d * (vs + rs * i) + (1.0 - d) * (vd + rd * i);
  if (i < 0.0) {
    const double a = -i;
    return -(td * f * (vdc + vd + rd * a - vs - rs * a) + d * (vd + rd * a) + (1.0 - d) * (vs + rs * a));
  }
  return 0.0;
}

double comm_sim_model_leg_error(const imest_inverter_t *m, double vdc, double fpwm, double i, double d)
{
  const double band = m->i_band_a > 0.0f ? (double)m->i_band_a : 1e-9;
  double s = i / band;
  if (s > 1.0) s = 1.0;
  if (s < -1.0) s = -1.0;
  const double a = fabs(i), dc = i > 0.0 ? d : 1.0 - d;
  const double vs = (double)m->v_switch_v, vd = (double)m->v_diode_v, rs = (double)m->r_switch_ohm,
               rd = (double)m->r_diode_ohm;
  return s * ((double)m->dead_time_s * fpwm * vdc + vd + rd * a + dc * ((vs - vd) + (rs - rd) * a));
}

static void compare_inverter(const imsim_config_t *sc, const imest_comm_config_t *cc, comm_sim_out_t *out)
{
  const imest_inverter_t *m = &out->r.inverter;
  const double m_true = fmin(sc->r_switch_ohm, sc->r_diode_ohm);
  const double m_fit = (double)out->r.rs_ohm.value - sc->rs_ohm;
  /* compared from twice the PWM ripple's peak up, where the leg's sign no longer depends on the band */
  const double sls = (double)out->r.sigma_ls_h.value;
  out->ripple_peak_a = sls > 0.0 ? sc->vdc_v / (8.0 * sls * sc->carrier_hz) : 0.0;
  const double lo = 2.0 * out->ripple_peak_a, hi = (double)cc->i_max_a;
  double w_model = 0.0, w_total = 0.0, sum2 = 0.0;
  int n = 0;
  for (int a = 0; a <= 20; ++a)
    for (int b = 0; b <= 18; ++b)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        const double i = sgn * (lo + (hi - lo) * a / 20.0), d = 0.05 + 0.05 * b;
        const double et = comm_sim_true_leg_error(sc, i, d);
        const double ef = comm_sim_model_leg_error(m, sc->vdc_v, sc->carrier_hz, i, d);
        const double em = fabs(ef - (et - m_true * i)), etot = fabs(ef + m_fit * i - et);
        if (em > w_model) w_model = em;
        if (etot > w_total) w_total = etot;
        sum2 += etot * etot;
        n++;
      }
  out->inv_err_model_v = w_model;
  out->inv_err_total_v = w_total;
  out->inv_err_rms_v = sqrt(sum2 / n);
}

static float wrap(double th)
{
  double t = fmod(th, TWO_PI);
  if (t < 0.0) t += TWO_PI;
  float f = (float)t;
  return f >= (float)TWO_PI ? 0.0f : f;
}

int comm_sim_run(const comm_sim_opts_t *o, comm_sim_out_t *out)
{
  memset(out, 0, sizeof *out);
  if (comm_sim_config(o, &out->sim) != 0) {
    fprintf(stderr, "commission: unknown preset '%s'\n", o->preset);
    return -1;
  }
  const imsim_config_t *sc = &out->sim;
  comm_sim_comm_config(o, sc, &out->cc);
  imsim_t *simp = (imsim_t *)calloc(1, sizeof *simp);
  imsim_sample_t s;
  if (simp == NULL || imsim_init(simp, sc, &s) != 0) {
    fprintf(stderr, "commission: simulator: %s\n", simp ? imsim_error(simp) : "out of memory");
    free(simp);
    return -1;
  }
  /* truth, at the rated flux: the stator flux at rated voltage and frequency at no load, the
     R_S drop (in quadrature with the flux's voltage) taken off, at the motor's own L_S there */
  const double wn = TWO_PI * (double)out->cc.rated_freq_hz, psi_vf = (double)out->cc.rated_voltage_v / wn;
  out->i_rated_flux_a = comm_sim_current_at_flux(sc, psi_vf);
  for (int it = 0; it < 3; ++it) {
    double ls = sc->ls_h;
    (void)comm_sim_true_at(sc, out->i_rated_flux_a, &ls, NULL, NULL);
    const double x = sc->rs_ohm / (wn * ls);
    out->i_rated_flux_a = comm_sim_current_at_flux(sc, psi_vf / sqrt(1.0 + x * x));
  }
  out->ls_h = sc->ls_h;
  out->sigma = sc->sigma;
  out->tr_s = sc->tr_s;
  (void)comm_sim_true_at(sc, out->i_rated_flux_a, &out->ls_h, &out->sigma, &out->tr_s);
  out->ls_preset_h = sc->ls_h;
  out->rs_ohm = sc->rs_ohm;
  out->sigma_ls_h = out->sigma * out->ls_h;
  out->lm_h = (1.0 - out->sigma) * out->ls_h;
  out->rr_ohm = out->lm_h / out->tr_s;
  out->pole_pairs = (unsigned int)sc->pole_pairs;
  out->rs_identifiable_ohm = sc->rs_ohm + fmin(sc->r_switch_ohm, sc->r_diode_ohm);

  imest_comm_t *c = (imest_comm_t *)calloc(1, sizeof *c);
  if (c == NULL || imest_comm_init(c, &out->cc) != IMEST_OK) {
    const char *field = NULL;
    imest_comm_config_check(&out->cc, &field);
    fprintf(stderr, "commission: bad routine config (%s)\n", field ? field : "?");
    free(c);
    free(simp);
    return -1;
  }
  const double scale = o->cpr_assumed > 0.0 ? (double)sc->encoder_counts / o->cpr_assumed : 1.0;
  const uint64_t n_max = (uint64_t)((o->max_time_s > 0.0 ? o->max_time_s : 400.0) * sc->fs_hz);
  const unsigned int bg_every = (unsigned int)(sc->fs_hz / 1000.0 + 0.5);
  if (o->trace) fprintf(o->trace, "t,stage,i_a,i_b,i_c,d_a,d_b,d_c,speed_rad_s,theta\n");
  for (uint64_t n = 0; n < n_max; ++n) {
    float i[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
    if (o->two_sensors) i[2] = -i[0] - i[1];
    if (o->swap_sensors_bc) {
      const float t = i[1];
      i[1] = i[2];
      i[2] = t;
    }
    const double th = o->encoder_stuck ? 0.0 : (o->encoder_reversed ? -s.theta : s.theta) * scale;
    float d[3];
    const int run = imest_comm_isr(c, i, (float)s.vdc_v, wrap(th), d);
    const unsigned int stg = c->stage < 8u ? c->stage : 7u;
    out->stage_s[stg] += 1.0 / sc->fs_hz;
    for (int x = 0; x < 3; ++x) {
      const double it = fabs(s.i_abc_true[x]);
      if (it > out->i_peak_true_a) out->i_peak_true_a = it;
      if (it > out->stage_ipk_a[stg]) out->stage_ipk_a[stg] = it;
    }
    if (c->stage < IMEST_COMM_STAGE_ROTATE && fabs(s.theta_true) > out->theta_max_standstill_rad)
      out->theta_max_standstill_rad = fabs(s.theta_true);
    if (o->trace && n % (o->trace_decimate ? o->trace_decimate : 1u) == 0u)
      fprintf(o->trace, "%.6f,%u,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%.6f\n", s.t, (unsigned int)c->stage,
              s.i_abc[0], s.i_abc[1], s.i_abc[2], (double)d[0], (double)d[1], (double)d[2], s.speed_rad_s,
              s.theta);
    const double dd[3] = {(double)d[0], (double)d[1], (double)d[2]};
    imsim_set_duty(simp, dd);
    if (bg_every == 0u || n % bg_every == 0u)
      while (imest_comm_background(c) == 1) {}
    const int st = c->state;
    if (!run && st != IMEST_COMM_RUNNING && st != IMEST_COMM_IDLE && st != IMEST_COMM_COMPUTING) break;
    imsim_step(simp, &s);
  }
  while (imest_comm_background(c) == 1) {}
  out->sim_time_s = s.t;
  imest_comm_result(c, &out->r);
  for (int k = 0; k < 3; ++k) out->fit[k] = c->fit[k];
  free(c);
  free(simp);
  if (out->r.flags & IMEST_COMM_FLAG_STANDSTILL) compare_inverter(sc, &out->cc, out);
  return 0;
}
