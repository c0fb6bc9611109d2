/* SPDX-License-Identifier: Apache-2.0 */
/* Indirect field-oriented control: run once per sample from the measured currents and the
 * encoder angle, slip from the controller's T_R (which the estimator may update). */
#include "imsim_internal.h"

void ims_ifoc_update(imsim_t *s)
{
  const imsim_config_t *c = &s->c;
  const double ts = s->ts_s;
  const double np = (double)c->pole_pairs;
  const double m = s->m_h;
  const double sl = c->sigma * c->ls_h;
  /* speed from encoder differences, first-order low-pass */
  const double w_raw = (s->th_meas - s->th_meas_prev) / ts;
  s->th_meas_prev = s->th_meas;
  s->w_meas += (1.0 - exp(-2.0 * PI * c->speed_filter_hz * ts)) * (w_raw - s->w_meas);
  const double psi_ref = s->ifoc_flux;
  const double id_ref = psi_ref / m;
  double te_ref;
  if (c->ifoc_mode == IMSIM_IFOC_SPEED) {
    double wref = s->speed_ref;
    if (c->speed_ramp_s > 0.0 && s->t < c->speed_ramp_s) wref *= s->t / c->speed_ramp_s;
    if (s->t >= c->speed_step_on_s) { /* the second reference (INFINITY: none) */
      const double w2 = c->speed_step_rpm * 2.0 * PI / 60.0;
      const double f =
          c->speed_step_ramp_s > 0.0 ? fmin(1.0, (s->t - c->speed_step_on_s) / c->speed_step_ramp_s) : 1.0;
      wref = s->speed_ref + (w2 - s->speed_ref) * f;
    }
    const double kp = c->j_kgm2 * 2.0 * PI * c->speed_bw_hz;
    const double ki = kp * 2.0 * PI * c->speed_bw_hz / 4.0;
    const double e = wref - s->w_meas;
    te_ref = kp * e + s->integ_w;
    if (te_ref > c->torque_limit_nm)
      te_ref = c->torque_limit_nm;
    else if (te_ref < -c->torque_limit_nm)
      te_ref = -c->torque_limit_nm;
    else
      s->integ_w += ki * e * ts;
  } else {
    te_ref = c->torque_ref_nm;
    if (te_ref > c->torque_limit_nm) te_ref = c->torque_limit_nm;
    if (te_ref < -c->torque_limit_nm) te_ref = -c->torque_limit_nm;
  }
  const double iq_ref = te_ref * c->lr_h / (np * m * psi_ref);
  const double w_sl = iq_ref / (s->ifoc_tr * id_ref);
  const double rho = np * s->th_meas + s->slip_angle;
  const cpx rot = cexpj(-rho);
  const cpx idq = cmul(rot, cx(s->i_meas_ab[0], s->i_meas_ab[1]));
  const double we = np * s->w_meas + w_sl;
  const double wbw = 2.0 * PI * c->current_bw_hz;
  const double kp = sl * wbw;
  const double req = c->rs_ohm + c->lr_h / s->ifoc_tr * (m / c->lr_h) * (m / c->lr_h);
  const double ki = req * wbw;
  const double ed = id_ref - idq.re, eq = iq_ref - idq.im;
  double vd = kp * ed + s->integ_d - we * sl * iq_ref;
  double vq = kp * eq + s->integ_q + we * (sl * id_ref + m / c->lr_h * psi_ref);
  /* linear-modulation limit of |u| (= V_ll rms): V_dc/2 phase peak without zero sequence,
     V_dc/sqrt(3) with it */
  const double vmax = c->modulation == IMSIM_MOD_SVPWM ? c->vdc_v / SQRT2 : sqrt(1.5) * 0.5 * c->vdc_v;
  const double vm = sqrt(vd * vd + vq * vq);
  if (vm > vmax) {
    vd *= vmax / vm;
    vq *= vmax / vm;
  } else {
    s->integ_d += ki * ed * ts;
    s->integ_q += ki * eq * ts;
  }
  s->v_dq[0] = vd;
  s->v_dq[1] = vq;
  s->rho = rho;
  s->we_ctrl = we;
  s->t_ctrl = s->t;
  s->te_ref = te_ref;
  s->id_ref = id_ref;
  s->iq_ref = iq_ref;
  s->slip_angle += w_sl * ts;
}

cpx ims_ifoc_vref(const imsim_t *s, double t)
{
  return cmul(cx(s->v_dq[0], s->v_dq[1]), cexpj(s->rho + s->we_ctrl * (t - s->t_ctrl)));
}

void imsim_set_ifoc_tr(imsim_t *s, double tr_s)
{
  if (tr_s > 0.0) s->ifoc_tr = tr_s;
}
void imsim_set_speed_ref(imsim_t *s, double rpm)
{
  s->speed_ref = rpm * 2.0 * PI / 60.0;
  s->c.speed_ramp_s = 0.0;
}
void imsim_set_torque_ref(imsim_t *s, double nm)
{
  s->c.torque_ref_nm = nm;
}

/* The current magnitude the IFOC imposes at slip w_sl, the supply that drives it at speed w, and
   the torque surplus there (ims_ifoc_steady). */
typedef struct {
  const imsim_t *s;
  double w, id, tl;
} ifoc_ss_ctx_t;

static double ifoc_surplus(const ifoc_ss_ctx_t *x, double w_sl, double *vll, imsim_steady_t *st)
{
  const imsim_config_t *c = &x->s->c;
  const double we = (double)c->pole_pairs * x->w + w_sl;
  const double iq = w_sl * x->s->ifoc_tr * x->id;
  const double i_amp = sqrt(x->id * x->id + iq * iq);
  /* |i| grows with the voltage at a fixed speed and frequency: double, then bisect */
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 60; ++k) {
    ims_steady_at(c, &x->s->rm, hi, we, x->w, st, NULL);
    if (st->i_rms_phase * sqrt(3.0) >= i_amp) break;
    lo = hi;
    hi *= 2.0;
  }
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    ims_steady_at(c, &x->s->rm, mid, we, x->w, st, NULL);
    if (st->i_rms_phase * sqrt(3.0) < i_amp)
      lo = mid;
    else
      hi = mid;
  }
  *vll = 0.5 * (lo + hi);
  ims_steady_at(c, &x->s->rm, *vll, we, x->w, st, NULL);
  return st->torque_nm - x->tl;
}

int ims_ifoc_steady(imsim_t *s, double *vll_v, double *we, imsim_steady_t *st)
{
  const imsim_config_t *c = &s->c;
  if (c->ifoc_mode != IMSIM_IFOC_SPEED) return -1;
  const double np = (double)c->pole_pairs;
  const double m = s->m_h;
  const double w = s->speed_ref;
  if (!(w > 0.0)) return -1;
  /* the speed loop settles where the motor's torque meets the load and the friction */
  const ifoc_ss_ctx_t x = {s, w, s->ifoc_flux / m, c->load_nm + c->b_nms * w};
  /* the slip of the torque limit (iq_ref = te L_R / (n_p M psi_ref), w_sl = iq / (T_R id)) */
  const double iq_max = c->torque_limit_nm * c->lr_h / (np * m * s->ifoc_flux);
  double lo = -iq_max / (s->ifoc_tr * x.id), hi = -lo;
  if (np * w + lo <= 0.0) lo = 0.5 * (-np * w); /* the field keeps turning forwards */
  double v;
  if (!(ifoc_surplus(&x, lo, &v, st) < 0.0) || !(ifoc_surplus(&x, hi, &v, st) > 0.0)) return -1;
  for (int k = 0; k < 80; ++k) {
    const double mid = 0.5 * (lo + hi);
    if (ifoc_surplus(&x, mid, &v, st) < 0.0)
      lo = mid;
    else
      hi = mid;
  }
  const double w_sl = 0.5 * (lo + hi);
  (void)ifoc_surplus(&x, w_sl, vll_v, st);
  ims_steady_at(c, &s->rm, *vll_v, np * w + w_sl, w, st, s->rm.on ? s->rm.fl : NULL);
  *we = np * w + w_sl;
  /* the controller's state there: references, the speed loop's integral (its output at zero
     error), the measured speed */
  s->id_ref = x.id;
  s->iq_ref = w_sl * s->ifoc_tr * x.id;
  s->te_ref = s->iq_ref * np * m * s->ifoc_flux / c->lr_h;
  s->integ_w = s->te_ref;
  s->w_meas = w;
  /* the field angle that puts the current at (id_ref, iq_ref), and the voltage command there:
     the current loops' integrals are what the command is at zero error, less the decoupling */
  const double rho = atan2(st->i_ab[1], st->i_ab[0]) - atan2(s->iq_ref, s->id_ref);
  const cpx v_dq = cmul(cx(*vll_v, 0.0), cexpj(-rho));
  const double sl = c->sigma * c->ls_h;
  s->v_dq[0] = v_dq.re;
  s->v_dq[1] = v_dq.im;
  s->integ_d = v_dq.re + *we * sl * s->iq_ref;
  s->integ_q = v_dq.im - *we * (sl * s->id_ref + m / c->lr_h * s->ifoc_flux);
  s->rho = rho;
  s->we_ctrl = *we;
  s->t_ctrl = 0.0;
  return 0;
}
