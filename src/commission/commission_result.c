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

/* A value's relative uncertainty from its quality: the larger of 3 standard
 * errors and the axes' spread (either NaN: not known, left out). */
static float quality_rel(const imest_comm_value_t *v)
{
  const float s = isfinite(v->std_rel) ? 3.0f * v->std_rel : 0.0f;
  const float p = isfinite(v->spread_rel) ? v->spread_rel : 0.0f;
  return fmaxf(s, p);
}

/* The rule imest_commission.h states for ls_uncertainty and sigma_uncertainty. */
static void constants_uncertainty(const imest_comm_result_t *r, imest_config_t *cfg)
{
  const int standstill = (r->flags & IMEST_COMM_FLAG_LS_STANDSTILL) != 0u;
  const float u_ls =
      fmaxf(standstill ? IMEST_COMM_LS_FLOOR_STANDSTILL : IMEST_COMM_LS_FLOOR,
            fmaxf(quality_rel(&r->ls_h), standstill ? quality_rel(&r->ls_standstill_h) : 0.0f));
  const float u_sg = fmaxf(standstill ? IMEST_COMM_SIGMA_FLOOR_STANDSTILL : IMEST_COMM_SIGMA_FLOOR,
                           fmaxf(quality_rel(&r->sigma), quality_rel(&r->sigma_ls_h) + u_ls));
  cfg->ls_uncertainty = fminf(u_ls, IMEST_COMM_UNCERTAINTY_MAX);
  cfg->sigma_uncertainty = fminf(u_sg, IMEST_COMM_UNCERTAINTY_MAX);
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
  cfg->sigma = r->sigma.value;
  cfg->rs_nominal_ohm = r->rs_ohm.value;
  constants_uncertainty(r, cfg);
  n += 3;
  if (isfinite(r->tr_s.value) && r->tr_s.value > 0.0f) {
    cfg->tr_nominal_s = r->tr_s.value;
    n++;
  }
  if (r->inverter.uncertainty >= 0.0f) {
    cfg->inverter = r->inverter;
    n++;
  }
  return n;
}
