/* SPDX-License-Identifier: Apache-2.0 */
/* Load torque: 0 before load_on_s, linear ramp over load_ramp_s, then load_nm (opposing
 * positive rotation); imsim_set_load() overrides it. */
#include "imsim_internal.h"

double ims_load_at(const imsim_t *s, double t)
{
  if (s->load_overridden) return s->load_override;
  const imsim_config_t *c = &s->c;
  if (t < c->load_on_s) return 0.0;
  if (c->load_ramp_s > 0.0 && t < c->load_on_s + c->load_ramp_s)
    return c->load_nm * (t - c->load_on_s) / c->load_ramp_s;
  return c->load_nm;
}

void imsim_set_load(imsim_t *s, double load_nm)
{
  s->load_override = load_nm;
  s->load_overridden = true;
}
