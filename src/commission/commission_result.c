/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning result: the background's values with the ISR's live figures, and an estimator
 * config filled from it. Read-only calls, any context. */
#include <math.h>
#include <stddef.h>

#include "commission_internal.h"

int imest_comm_result(const imest_comm_t *c, imest_comm_result_t *r)
{
  if (c == NULL || r == NULL) return IMEST_ERR_NULL;
  *r = c->res;
  r->state = c->state;
  r->reason = c->reason;
  if (c->state == IMEST_COMM_RUNNING || c->state == IMEST_COMM_IDLE) r->stage = (int)c->stage;
  r->time_s = (float)c->k * c->ts_s;
  r->i_peak_a = c->i_peak;
  r->rotor_moved_rad = c->th_dev;
  if (c->th_dev > 0.01f) r->flags |= IMEST_COMM_FLAG_ROTOR_CREPT;
  const int plausible = isfinite(r->rs_ohm.value) && isfinite(r->sigma_ls_h.value) &&
                        isfinite(r->ls_h.value) && isfinite(r->sigma.value) && r->sigma.value > 0.0f &&
                        r->sigma.value < 1.0f;
  r->valid = c->state == IMEST_COMM_DONE && plausible;
  return IMEST_OK;
}

int imest_comm_apply(const imest_comm_result_t *r, imest_config_t *cfg)
{
  if (r == NULL || cfg == NULL) return IMEST_ERR_NULL;
  if (!r->valid) return IMEST_ERR_ARG;
  int n = 0;
  if (r->pole_pairs > 0u) {
    cfg->pole_pairs = r->pole_pairs;
    n++;
  }
  cfg->ls_h = r->ls_h.value;
  cfg->rs_nominal_ohm = r->rs_ohm.value;
  n += 2;
  if (!(r->flags & IMEST_COMM_FLAG_ROTOR_HF)) { /* else its sigma is the high-frequency one */
    cfg->sigma = r->sigma.value;
    n++;
  }
  if (isfinite(r->tr_s.value) && r->tr_s.value > 0.0f) {
    cfg->tr_nominal_s = r->tr_s.value;
    n++;
  }
  if (r->inverter.uncertainty >= 0.0f) {
    cfg->inverter = r->inverter;
    n++;
  }
  /* The magnetising curve (r->ls_curve_points, ls_curve_i_a, ls_curve_h) is for the estimator's
     config fields of the same names (L_S followed with the flux); imest_config_t does not have
     them yet. When it does: copy the three here when r->ls_curve_points > 0 and count one field
     (the header's "filled" list and count with it). */
  return n;
}
