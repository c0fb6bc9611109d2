/* SPDX-License-Identifier: Apache-2.0 */
/* Reference of the open-loop supplies (sine, V/f; also the PWM inverter's reference). */
#include "imsim_internal.h"

/* alpha-beta amplitude (= V_ll rms), phase and frequency at t. The phase is exact for a
   linear frequency ramp. */
void ims_vf_ref(const imsim_t *s, double t, double *amp, double *phase, double *f_hz)
{
  const imsim_config_t *c = &s->c;
  const double ramp = (c->supply == IMSIM_SUPPLY_SINE || c->start == IMSIM_START_STEADY) ? 0.0 : c->vf_ramp_s;
  if (ramp <= 0.0) {
    *amp = c->vll_v;
    *f_hz = c->freq_hz;
    *phase = 2.0 * PI * c->freq_hz * t;
    return;
  }
  const double r = t < ramp ? t / ramp : 1.0;
  *f_hz = r * c->freq_hz;
  *amp = r > 0.0 ? c->vf_boost_v + (c->vll_v - c->vf_boost_v) * r : 0.0;
  *phase = t < ramp ? PI * c->freq_hz * t * t / ramp : 2.0 * PI * c->freq_hz * (t - 0.5 * ramp);
}
