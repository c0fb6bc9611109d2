/* SPDX-License-Identifier: Apache-2.0 */
/* PWM inverter, one half carrier period at a time: reference -> modulation -> edges (dead
 * time) -> leg voltages (device drops) -> the input moments of the fast path, or the voltage
 * on each piece between edges for the piecewise and RK4 paths.
 *
 * Half bridge, phase current i > 0 into the motor (sim/README.md, Inverter):
 *   i > 0: upper switch on -> V_dc - (V_sw + r_sw i); lower diode -> -(V_d + r_d i);
 *          during the dead time the lower diode conducts.
 *   i < 0: upper diode -> V_dc + V_d + r_d |i|; lower switch on -> V_sw + r_sw |i|;
 *          during the dead time the upper diode conducts.
 *   i = 0: no drop, and the dead time does not delay the edge. */
#include "imsim_internal.h"

bool ims_inverter_has_drops(const imsim_config_t *c)
{
  return c->v_switch_v != 0.0 || c->r_switch_ohm != 0.0 || c->v_diode_v != 0.0 || c->r_diode_ohm != 0.0;
}

bool ims_inverter_is_ideal(const imsim_config_t *c)
{
  return c->dead_time_s == 0.0 && !ims_inverter_has_drops(c);
}

/* Leg voltage (against the negative bus rail) with the upper (high) or lower device pair on. */
static double leg_level(const imsim_config_t *c, bool drops, bool high, double i)
{
  if (!drops) return high ? c->vdc_v : 0.0;
  if (high) {
    if (i > 0.0) return c->vdc_v - (c->v_switch_v + c->r_switch_ohm * i);
    if (i < 0.0) return c->vdc_v + (c->v_diode_v - c->r_diode_ohm * i);
    return c->vdc_v;
  }
  if (i > 0.0) return -(c->v_diode_v + c->r_diode_ohm * i);
  if (i < 0.0) return c->v_switch_v - c->r_switch_ohm * i;
  return 0.0;
}

bool ims_pwm_modulate(imsim_t *s, cpx vref, double vdc, double m[3])
{
  const imsim_config_t *c = &s->c;
  double vabc[3];
  const double vab[2] = {vref.re, vref.im};
  imsim_ab_to_abc(vab, vabc);
  double hi = vabc[0], lo = vabc[0];
  for (int k = 1; k < 3; ++k) {
    if (vabc[k] > hi) hi = vabc[k];
    if (vabc[k] < lo) lo = vabc[k];
  }
  /* zero sequence: none (sine-triangle) or min-max (centres the three references) */
  double v0 = 0.0, need = 2.0 * (hi > -lo ? hi : -lo);
  if (c->modulation == IMSIM_MOD_SVPWM) {
    v0 = -0.5 * (hi + lo);
    need = hi - lo;
  }
  if (need > s->pwm_vdc_needed) s->pwm_vdc_needed = need;
  bool clipped = false;
  for (int k = 0; k < 3; ++k) {
    m[k] = (vabc[k] + v0) / (0.5 * vdc);
    if (m[k] > 1.0 || m[k] < -1.0) clipped = true;
    if (m[k] > 1.0) m[k] = 1.0;
    if (m[k] < -1.0) m[k] = -1.0;
  }
  return clipped;
}

/* Voltage applied on the piece of the half period around tm, with the phase currents i_abc at
   the piece's start deciding the dead time and the drops. */
cpx ims_pwm_piece_voltage(const imsim_t *s, const pwm_half_t *ph, double tm, const double i_abc[3])
{
  const imsim_config_t *c = &s->c;
  const bool drops = ims_inverter_has_drops(c);
  cpx u = cx(0.0, 0.0);
  for (int k = 0; k < 3; ++k) {
    const double e = ph->e_cmd[k];
    bool high;
    if (tm < e)
      high = ph->rising; /* before the edge: the state the half period began with */
    else if (ph->has_edge[k] && tm < e + ph->td && i_abc[k] != 0.0)
      high = i_abc[k] < 0.0; /* a diode */
    else
      high = !ph->rising;
    const double v = leg_level(c, drops, high, i_abc[k]);
    u = cadd(u, cx(IMS_AK_RE[k] * SQ23 * v, IMS_AK_IM[k] * SQ23 * v));
  }
  return u;
}

int ims_pwm_breaks(const pwm_half_t *ph, double h, double b[8])
{
  int n = 0;
  b[n++] = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double e = ph->e_cmd[k] < h ? ph->e_cmd[k] : h;
    b[n++] = e;
    if (ph->td > 0.0 && ph->has_edge[k]) b[n++] = e + ph->td < h ? e + ph->td : h;
  }
  b[n++] = h;
  for (int a = 2; a < n - 1; ++a) /* insertion sort of the inner points */
    for (int q = a; q > 1 && b[q] < b[q - 1]; --q) {
      const double t = b[q];
      b[q] = b[q - 1];
      b[q - 1] = t;
    }
  return n;
}

void ims_pwm_build(imsim_t *s, uint64_t g, const double m[3], step_input_t *in, pwm_half_t *ph)
{
  const imsim_config_t *c = &s->c;
  const double h = s->h_s;
  const double vdc = c->vdc_v;
  const bool rising = (g % 2u) == 0u; /* carrier starts at its valley at t = 0 */
  const bool drops = ims_inverter_has_drops(c);
  double iabc[3];
  const double iab[2] = {s->x[0].re, s->x[0].im};
  imsim_ab_to_abc(iab, iabc);
  double tau_cmd[3], tau_act[3], lev0[3], lev1[3];
  ph->rising = rising;
  ph->td = c->dead_time_s;
  for (int k = 0; k < 3; ++k) {
    /* rising: high on [0, e); falling: low on [0, e), high after */
    const double e = rising ? 0.5 * h * (1.0 + m[k]) : 0.5 * h * (1.0 - m[k]);
    ph->e_cmd[k] = e;
    ph->has_edge[k] = e > 0.0 && e < h;
    double ea = e;
    if (ph->has_edge[k] && c->dead_time_s > 0.0) {
      /* high->low (rising) is delayed when the current flows out of the motor (i < 0);
         low->high (falling) is delayed when it flows into the motor (i > 0). */
      if ((rising && iabc[k] < 0.0) || (!rising && iabc[k] > 0.0)) ea = e + c->dead_time_s;
      if (ea > h) ea = h;
    }
    tau_cmd[k] = h - e;
    tau_act[k] = h - ea < 1e-14 ? 0.0 : h - ea;      /* avoid denormal powers */
    lev0[k] = leg_level(c, drops, rising, iabc[k]);  /* before the (actual) edge */
    lev1[k] = leg_level(c, drops, !rising, iabc[k]); /* after it */
  }
  const int jmax = s->c.pwm_moments ? in->p : 0;
  if (!drops) {
    /* the common level 0 or V_dc of all legs drops out (sum of a_k = 0): only the high
       time after the edge (falling) or the low time (rising) counts */
    const double sg = rising ? -1.0 : 1.0;
    const double kc = sg * SQ23 * vdc;
    double p[3] = {tau_act[0], tau_act[1], tau_act[2]};
    for (int j = 0; j <= jmax; ++j) {
      const double f = kc * IMS_INV_FACT[j + 1];
      in->mom[j] = cx(f * (IMS_AK_RE[0] * p[0] + IMS_AK_RE[1] * p[1] + IMS_AK_RE[2] * p[2]),
                      f * (IMS_AK_IM[0] * p[0] + IMS_AK_IM[1] * p[1] + IMS_AK_IM[2] * p[2]));
      p[0] *= tau_act[0];
      p[1] *= tau_act[1];
      p[2] *= tau_act[2];
    }
  } else {
    /* leg k: lev0 on [0, h - tau), lev1 on [h - tau, h);
       int (h-s)^j/j! v ds = (lev0 h^(j+1) + (lev1 - lev0) tau^(j+1)) / (j+1)! */
    double p[3] = {tau_act[0], tau_act[1], tau_act[2]};
    double hp = h;
    for (int j = 0; j <= jmax; ++j) {
      double re = 0.0, im = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double v = lev0[k] * hp + (lev1[k] - lev0[k]) * p[k];
        re += IMS_AK_RE[k] * v;
        im += IMS_AK_IM[k] * v;
        p[k] *= tau_act[k];
      }
      const double f = SQ23 * IMS_INV_FACT[j + 1];
      in->mom[j] = cx(f * re, f * im);
      hp *= h;
    }
  }
  ph->act_avg[0] = in->mom[0].re / h;
  ph->act_avg[1] = in->mom[0].im / h;
  const double kc = (rising ? -1.0 : 1.0) * SQ23 * vdc;
  ph->cmd_avg[0] =
      kc / h * (IMS_AK_RE[0] * tau_cmd[0] + IMS_AK_RE[1] * tau_cmd[1] + IMS_AK_RE[2] * tau_cmd[2]);
  ph->cmd_avg[1] =
      kc / h * (IMS_AK_IM[0] * tau_cmd[0] + IMS_AK_IM[1] * tau_cmd[1] + IMS_AK_IM[2] * tau_cmd[2]);
}

/* Whether a phase current may cross zero inside the half period. The prediction: the phase
   currents piecewise linear, di/dt = f0 + u/(sigma L_S) with f0 the input-free part at the
   start and u the commanded pattern; a margin covers what it leaves out (dead time, drops,
   the change of f0). The moments path decides the dead time and the drops once per half
   period, which is exact only when no current changes sign; otherwise the half period is
   integrated piecewise. */
bool ims_pwm_may_cross_zero(const imsim_t *s, const pwm_half_t *ph)
{
  const imsim_config_t *c = &s->c;
  if (ims_inverter_is_ideal(c)) return false;
  const double h = s->h_s, sl = c->sigma * c->ls_h;
  const double nw = (double)c->pole_pairs * s->w;
  const cpx i = s->x[0], psi = s->x[1];
  const cpx f0 = cadd(cscale(i, -s->gamma), cmul(cx(s->beta / s->tr, -s->beta * nw), psi));
  double i0[3], d0[3];
  const double iab[2] = {i.re, i.im}, fab[2] = {f0.re, f0.im};
  imsim_ab_to_abc(iab, i0);
  imsim_ab_to_abc(fab, d0);
  /* the commanded pattern: breaks at the commanded edges */
  pwm_half_t cmd = *ph;
  cmd.td = 0.0;
  double b[8];
  const int nb = ims_pwm_breaks(&cmd, h, b);
  double pred[3] = {i0[0], i0[1], i0[2]}, low[3], dev = 0.0, imax = 0.0;
  for (int k = 0; k < 3; ++k) {
    low[k] = fabs(i0[k]); /* smallest |i| on i0's side; <= 0 once it crosses */
    if (fabs(i0[k]) > imax) imax = fabs(i0[k]);
  }
  for (int q = 0; q + 1 < nb; ++q) {
    const double len = b[q + 1] - b[q];
    if (len <= 0.0) continue;
    const double tm = 0.5 * (b[q] + b[q + 1]);
    double st[3];
    for (int k = 0; k < 3; ++k) st[k] = (tm < cmd.e_cmd[k]) == ph->rising ? 1.0 : 0.0;
    const double mean = (st[0] + st[1] + st[2]) / 3.0;
    for (int k = 0; k < 3; ++k) {
      pred[k] += (d0[k] + c->vdc_v * (st[k] - mean) / sl) * len;
      const double side = i0[k] > 0.0 ? pred[k] : -pred[k];
      if (side < low[k]) low[k] = side;
      if (fabs(pred[k] - i0[k]) > dev) dev = fabs(pred[k] - i0[k]);
    }
  }
  /* margin: the dead time moves at most 2 V_dc t_d of phase volt-seconds, the drops at most
     (V_sw + V_d + (r_sw + r_d) |i|) h, and f0 changes by about ||A|| h / 2 of the excursion */
  const double anorm = s->gamma + s->beta * s->m_h / s->tr + 2.0 * (1.0 / s->tr + fabs(nw));
  const double drops = c->v_switch_v + c->v_diode_v + (c->r_switch_ohm + c->r_diode_ohm) * (imax + dev);
  const double margin = (2.0 * c->vdc_v * c->dead_time_s + drops * h) / sl + 0.5 * h * anorm * dev;
  for (int k = 0; k < 3; ++k)
    if (low[k] <= margin) return true;
  return false;
}
