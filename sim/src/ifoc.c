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
