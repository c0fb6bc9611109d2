/* PWM inverter, one half carrier period at a time: reference -> duties -> edges (dead time)
 * -> the input moments of the fast path; the voltage on each piece between edges. */
#include "imsim_internal.h"


/* Voltage applied by the inverter at time tm inside the half period. */
cpx ims_pwm_voltage_at(const pwm_half *ph, double tm) {
  cpx u = cx(0.0, 0.0);
  for (int k = 0; k < 3; ++k) {
    const bool before = tm < ph->edge[k];
    const bool high = ph->rising ? before : !before;
    if (high) u = cadd(u, cx(IMS_AK_RE[k] * SQ23 * ph->vdc, IMS_AK_IM[k] * SQ23 * ph->vdc));
  }
  return u;
}

/* Switching instants of the half period, sorted, with 0 and h: b[0..4]. */
void ims_pwm_breaks(const pwm_half *ph, double h, double b[5]) {
  b[0] = 0.0;
  b[1] = ph->edge[0] < h ? ph->edge[0] : h;
  b[2] = ph->edge[1] < h ? ph->edge[1] : h;
  b[3] = ph->edge[2] < h ? ph->edge[2] : h;
  b[4] = h;
  for (int a = 2; a < 4; ++a)
    for (int q = a; q > 1 && b[q] < b[q - 1]; --q) {
      const double t = b[q];
      b[q] = b[q - 1];
      b[q - 1] = t;
    }
}

/* Builds one half carrier period from the reference vref (alpha-beta): the edges (dead time
   decided by the current's sign at the half-period start), the input moments in->mom, the
   commanded and the actual average voltage, and the applied voltage at the end. */
void ims_pwm_build(imsim *s, uint64_t g, cpx vref, step_input *in, pwm_half *ph, double cmd_avg[2],
                   double act_avg[2], double u_end[2]) {
  const imsim_config *c = &s->c;
  const double h = s->h_s;
  const double vdc = c->vdc_v;
  const bool rising = (g % 2u) == 0u; /* carrier starts at its valley at t = 0 */
  double vabc[3], iabc[3];
  const double vab[2] = {vref.re, vref.im};
  imsim_ab_to_abc(vab, vabc);
  const double iab[2] = {s->x[0].re, s->x[0].im};
  imsim_ab_to_abc(iab, iabc);
  double tau_cmd[3], tau_act[3];
  ph->rising = rising;
  ph->vdc = vdc;
  double end_re = 0.0, end_im = 0.0;
  bool clipped = false;
  for (int k = 0; k < 3; ++k) {
    double m = vabc[k] / (0.5 * vdc);
    const double need = 2.0 * fabs(vabc[k]); /* sine-triangle: the bus must span +-peak */
    if (need > s->pwm_vdc_needed) s->pwm_vdc_needed = need;
    if (m > 1.0 || m < -1.0) clipped = true;
    if (m > 1.0) m = 1.0;
    if (m < -1.0) m = -1.0;
    /* rising: high on [0, e); falling: low on [0, e), high after */
    const double e = rising ? 0.5 * h * (1.0 + m) : 0.5 * h * (1.0 - m);
    double ea = e;
    if (e > 0.0 && e < h && c->dead_time_s > 0.0) {
      /* high->low (rising) is delayed when the current flows out of the motor (i < 0);
         low->high (falling) is delayed when it flows into the motor (i > 0). */
      if ((rising && iabc[k] < 0.0) || (!rising && iabc[k] > 0.0)) ea = e + c->dead_time_s;
      if (ea > h) ea = h;
    }
    ph->edge[k] = ea;
    tau_cmd[k] = h - e;
    tau_act[k] = h - ea < 1e-14 ? 0.0 : h - ea; /* avoid denormal powers */
    const bool high_at_end = rising ? (ea >= h) : (ea < h);
    if (high_at_end) {
      end_re += IMS_AK_RE[k];
      end_im += IMS_AK_IM[k];
    }
  }
  s->pwm_half_periods++;
  if (clipped) s->pwm_clipped_half_periods++;
  const double sg = rising ? -1.0 : 1.0;
  const double kc = sg * SQ23 * vdc;
  double p[3] = {tau_act[0], tau_act[1], tau_act[2]};
  const int jmax = s->c.pwm_moments ? in->p : 0;
  for (int j = 0; j <= jmax; ++j) {
    const double f = kc * IMS_INV_FACT[j + 1];
    in->mom[j] = cx(f * (IMS_AK_RE[0] * p[0] + IMS_AK_RE[1] * p[1] + IMS_AK_RE[2] * p[2]),
                    f * (IMS_AK_IM[0] * p[0] + IMS_AK_IM[1] * p[1] + IMS_AK_IM[2] * p[2]));
    p[0] *= tau_act[0];
    p[1] *= tau_act[1];
    p[2] *= tau_act[2];
  }
  act_avg[0] = in->mom[0].re / h;
  act_avg[1] = in->mom[0].im / h;
  cmd_avg[0] = kc / h * (IMS_AK_RE[0] * tau_cmd[0] + IMS_AK_RE[1] * tau_cmd[1] + IMS_AK_RE[2] * tau_cmd[2]);
  cmd_avg[1] = kc / h * (IMS_AK_IM[0] * tau_cmd[0] + IMS_AK_IM[1] * tau_cmd[1] + IMS_AK_IM[2] * tau_cmd[2]);
  u_end[0] = SQ23 * vdc * end_re;
  u_end[1] = SQ23 * vdc * end_im;
  in->u_end[0] = u_end[0];
  in->u_end[1] = u_end[1];
}
