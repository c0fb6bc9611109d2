/* SPDX-License-Identifier: Apache-2.0 */
/* Thermal drift of R_S and R_R: R(T) = R_cold (1 + alpha (T - T_amb)), each body a first-order
 * model driven by its own copper loss (see sim/README.md, Thermal drift). */
#include "imsim_internal.h"

void ims_update_params(imsim_t *s)
{
  const imsim_config_t *c = &s->c;
  s->rs = c->rs_ohm * (1.0 + c->alpha_per_k * (s->temp_s - c->t_amb_c));
  s->rr = s->rr0_ohm * (1.0 + c->alpha_per_k * (s->temp_r - c->t_amb_c));
  s->tr = c->lr_h / s->rr;
  s->gamma = s->rs / (c->sigma * c->ls_h) + (1.0 - c->sigma) / (c->sigma * s->tr);
  s->beta = s->m_h / (c->sigma * c->ls_h * c->lr_h);
}

/* Copper losses at t_n drive both first-order models (exact exponential step over 1/fs). */
void ims_thermal_step(imsim_t *s)
{
  const imsim_config_t *c = &s->c;
  const double ts = s->ts_s;
  const cpx ir = cscale(cadd(s->x[1], cscale(s->x[0], -s->m_h)), 1.0 / c->lr_h);
  const double ps = s->rs * cabs2(s->x[0]);
  const double pr = s->rm.on ? ims_rm_p_rotor(s) : s->rr * cabs2(ir);
  const double ks = 1.0 - exp(-ts * c->thermal_speedup / c->tau_stator_s);
  const double kr = 1.0 - exp(-ts * c->thermal_speedup / c->tau_rotor_s);
  s->temp_s += ks * (c->t_amb_c + c->rth_stator_k_per_w * ps - s->temp_s);
  s->temp_r += kr * (c->t_amb_c + c->rth_rotor_k_per_w * pr - s->temp_r);
  ims_update_params(s);
}
