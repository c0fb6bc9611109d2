/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 1, current-sensor offsets: zero voltage (every duty 0.5, so no leg pair
 * drives a current whatever the dead time), 10 ms for any current to die, then the mean of each
 * channel over 0.25 s is its offset. A mean beyond 25 % of i_max_a, or a current that moves
 * (rms beyond 3 %), is not an offset: a sensor is broken or the rotor turns. ISR, float32. */
#include "commission_internal.h"

void imest__cm_stage_offsets(imest_comm_t *c, const float m[3], float vdc)
{
  c->d_next[0] = c->d_next[1] = c->d_next[2] = 0.5f;
  c->cnt++;
  const uint32_t n_settle = c->n_off / 25u + 1u; /* 10 ms */
  if (c->cnt <= n_settle) return;
  for (int x = 0; x < 3; ++x) {
    c->acc_m[x] += m[x];
    c->acc_m2[x] += m[x] * m[x];
  }
  c->acc_vdc += vdc;
  if (c->cnt < n_settle + c->n_off) return;

  const float inv_n = 1.0f / (float)c->n_off;
  for (int x = 0; x < 3; ++x) {
    c->off[x] = c->acc_m[x] * inv_n;
    c->res.i_offset_a[x] = c->off[x];
    /* an offset beyond a quarter of the limit is a broken sensor; a current that moves (rms
       beyond 3 % of the limit: a turning rotor, a leaking bridge) is not an offset */
    const float var = c->acc_m2[x] * inv_n - c->off[x] * c->off[x];
    const float lim = 0.03f * c->cfg.i_max_a;
    if (imest__abs(c->off[x]) > 0.25f * c->cfg.i_max_a || var > lim * lim) {
      imest__cm_fail(c, IMEST_COMM_REASON_CURRENT_AT_REST);
      return;
    }
  }
  c->vdc0 = c->acc_vdc * inv_n;
  c->res.vdc_v = c->vdc0;
  /* the axis voltage limit: what the centred pattern can reach (a leg within 5 %..95 %), or the
     user's limit */
  const float v_bus = 0.45f * c->vdc0 * IMEST_SQRT3_2_F;
  c->v_lim = (c->cfg.v_max_v > 0.0f && c->cfg.v_max_v * IMEST_SQRT3_2_F < v_bus)
                 ? c->cfg.v_max_v * IMEST_SQRT3_2_F
                 : v_bus;
  c->stage = IMEST_COMM_STAGE_WIRING;
  c->step = 0u;
  c->cnt = 0u;
  c->axis = 0u;
  c->pulse_v = 0.04f * c->vdc0;
}
