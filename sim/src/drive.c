/* SPDX-License-Identifier: Apache-2.0 */
/* Firmware timing (sim/README.md, Firmware timing): the drive samples once every N carrier
 * periods, at a carrier valley t_k; from that sample it computes the duties that the PWM unit
 * loads at the next valley, t_k+1, and applies during [t_k+1, t_k+2). The duties come from
 * the V/f reference, the IFOC, or the caller (supply ext: imsim_set_duty/imsim_set_voltage).
 * They are converted with the bus voltage the drive measured at t_k. */
#include "imsim_internal.h"

/* Duties from an alpha-beta voltage command, as firmware computes them: the configured
   modulation with the measured bus, clipped to [0, 1]. Returns true if it clipped. */
static bool duties_from(imsim_t *s, cpx v, double d[3])
{
  double m[3];
  const double vdc = s->vdc_meas > 0.0 ? s->vdc_meas : s->c.vdc_v;
  const bool clipped = ims_pwm_modulate(s, v, vdc, m);
  for (int k = 0; k < 3; ++k) d[k] = 0.5 + 0.5 * m[k];
  return clipped;
}

/* The reference a V/f drive computes at t for the sample period after the next one: taken at
   that period's centre, t + 1.5/fs, so that the applied fundamental is not delayed. */
static cpx vf_command(const imsim_t *s, double t)
{
  double amp, phs, f;
  ims_vf_ref(s, t + 1.5 * s->ts_s, &amp, &phs, &f);
  return cscale(cexpj(phs), amp);
}

void ims_drive_init(imsim_t *s)
{
  for (int k = 0; k < 3; ++k) s->duty[k] = s->duty_next[k] = 0.5; /* zero voltage */
  if (!ims_firmware_timing(&s->c)) return;
  if (s->c.supply == IMSIM_SUPPLY_PWM) {
    /* what the drive computed at t_-1 for [t_0, t_1) (continuity for a steady start) */
    duties_from(s, vf_command(s, -s->ts_s), s->duty);
    for (int k = 0; k < 3; ++k) s->duty_next[k] = s->duty[k];
  } else if (s->c.supply == IMSIM_SUPPLY_IFOC && s->c.start == IMSIM_START_STEADY) {
    /* the steady controller's command for [t_0, t_1) (ims_ifoc_steady), at its centre */
    duties_from(s, ims_ifoc_vref(s, 0.5 * s->ts_s), s->duty);
    for (int k = 0; k < 3; ++k) s->duty_next[k] = s->duty[k];
  }
}

void ims_drive_update(imsim_t *s)
{
  cpx v;
  switch (s->c.supply) {
  case IMSIM_SUPPLY_PWM: v = vf_command(s, s->t); break;
  case IMSIM_SUPPLY_IFOC:
    /* the controller's synchronous-frame command rotated to the centre of its period */
    v = ims_ifoc_vref(s, s->t + 1.5 * s->ts_s);
    break;
  case IMSIM_SUPPLY_EXT:
  case IMSIM_SUPPLY_SINE:
  case IMSIM_SUPPLY_VF:
  default: return; /* ext: set by the caller since the last step */
  }
  if (duties_from(s, v, s->duty_next)) s->pwm_clipped_half_periods += (uint64_t)s->k_steps;
}

void ims_drive_advance(imsim_t *s)
{
  for (int k = 0; k < 3; ++k) s->duty[k] = s->duty_next[k];
}

int imsim_set_duty(imsim_t *s, const double duty[3])
{
  if (s->c.supply != IMSIM_SUPPLY_EXT) return -1;
  if (!isfinite(duty[0]) || !isfinite(duty[1]) || !isfinite(duty[2])) return -1;
  bool clipped = false;
  for (int k = 0; k < 3; ++k) {
    double d = duty[k];
    if (d < 0.0 || d > 1.0) clipped = true;
    if (d < 0.0) d = 0.0;
    if (d > 1.0) d = 1.0;
    s->duty_next[k] = d;
  }
  if (clipped) s->pwm_clipped_half_periods += (uint64_t)s->k_steps;
  return 0;
}

int imsim_set_voltage(imsim_t *s, const double u_abc[3])
{
  if (s->c.supply != IMSIM_SUPPLY_EXT) return -1;
  if (!isfinite(u_abc[0]) || !isfinite(u_abc[1]) || !isfinite(u_abc[2])) return -1;
  double ab[2];
  imsim_abc_to_ab(u_abc, ab);
  if (duties_from(s, cx(ab[0], ab[1]), s->duty_next)) s->pwm_clipped_half_periods += (uint64_t)s->k_steps;
  return 0;
}
