/* SPDX-License-Identifier: Apache-2.0 */
/* The stator's and the rotor's temperatures from the estimator's results, by the resistance method
 * (include/imest/imest_temperature.h: the relation, its assumptions and the defaults). Runs once
 * per window in the background task: -Os like the rest of the once-per-window code
 * (src/CMakeLists.txt). float32 arithmetic, no libm. */
#include "imest/imest_temperature.h"

#include <math.h>
#include <stddef.h>

#include "common/imest_range.h"

void imest_temperature_config_default(imest_temperature_config_t *cfg, float t_ref_c, float rs_ref_ohm,
                                      float tr_ref_s, float ls_h)
{
  if (cfg == NULL) return;
  cfg->t_ref_c = t_ref_c;
  cfg->t_ref_uncert_k = 1.0f;
  cfg->rs_ref_ohm = rs_ref_ohm;
  cfg->rs_ref_bound_rel = 0.003f;
  cfg->tr_ref_s = tr_ref_s;
  cfg->tr_ref_bound_rel = 0.005f;
  cfg->lr_h = ls_h;
  cfg->stator_k_c = 234.5f;
  cfg->rotor_k_c = 225.0f;
  cfg->stator_tol_k = 3.0f;
  cfg->rotor_tol_k = 5.0f;
}

int imest_temperature_config_check(const imest_temperature_config_t *cfg, const char **field)
{
  const char *bad = NULL;
  if (cfg == NULL) {
    if (field) *field = "cfg";
    return IMEST_ERR_NULL;
  }
  if (!imest__in_range(cfg->t_ref_c, -60.0f, 0, 200.0f))
    bad = "t_ref_c";
  else if (!imest__in_range(cfg->t_ref_uncert_k, 0.0f, 0, 50.0f))
    bad = "t_ref_uncert_k";
  else if (!imest__in_range(cfg->rs_ref_ohm, 0.0f, 1, 3.0e38f))
    bad = "rs_ref_ohm";
  else if (!imest__in_range(cfg->rs_ref_bound_rel, 0.0f, 0, 0.5f))
    bad = "rs_ref_bound_rel";
  else if (!imest__in_range(cfg->tr_ref_s, 0.0f, 1, 3.0e38f))
    bad = "tr_ref_s";
  else if (!imest__in_range(cfg->tr_ref_bound_rel, 0.0f, 0, 0.5f))
    bad = "tr_ref_bound_rel";
  else if (!imest__in_range(cfg->lr_h, 0.0f, 1, 3.0e38f))
    bad = "lr_h";
  else if (!imest__in_range(cfg->stator_k_c, 100.0f, 0, 1000.0f))
    bad = "stator_k_c";
  else if (!imest__in_range(cfg->rotor_k_c, 100.0f, 0, 1000.0f))
    bad = "rotor_k_c";
  else if (!imest__in_range(cfg->stator_tol_k, 0.0f, 1, 1000.0f))
    bad = "stator_tol_k";
  else if (!imest__in_range(cfg->rotor_tol_k, 0.0f, 1, 1000.0f))
    bad = "rotor_tol_k";
  if (field) *field = bad;
  return bad == NULL ? IMEST_OK : IMEST_ERR_CONFIG;
}

int imest_temperature_init(imest_temperature_t *t, const imest_temperature_config_t *cfg)
{
  if (t == NULL || cfg == NULL) return IMEST_ERR_NULL;
  if (imest_temperature_config_check(cfg, NULL) != IMEST_OK) return IMEST_ERR_CONFIG;
  t->cfg = *cfg;
  t->stator_c = NAN;
  t->stator_uncert_k = NAN;
  t->stator_valid = 0;
  t->rr_ohm = NAN;
  t->rotor_c = NAN;
  t->rotor_uncert_k = NAN;
  t->rotor_valid = 0;
  t->t_end_s = 0.0;
  t->updates = 0u;
  return IMEST_OK;
}

/* T = ratio (k + T_ref) - k and its uncertainty (T + k) ratio_bound + ratio u_ref: the resistance
   method (the header), for a resistance ratio R / R_ref with relative bound ratio_bound. */
static float resistance_method(const imest_temperature_config_t *c, float ratio, float k, float ratio_bound,
                               float *uncert_k)
{
  const float temp_c = ratio * (k + c->t_ref_c) - k;
  *uncert_k = (temp_c + k) * ratio_bound + ratio * c->t_ref_uncert_k;
  return temp_c;
}

int imest_temperature_update(imest_temperature_t *t, const imest_result_t *r)
{
  if (t == NULL || r == NULL) return IMEST_ERR_NULL;
  const imest_temperature_config_t *c = &t->cfg;
  int valid = 0;

  const float rs = (float)r->rs_ohm;
  const float rs_b = (float)r->rs_bound_rel;
  t->stator_c = NAN;
  t->stator_uncert_k = NAN;
  t->stator_valid = 0;
  if (isfinite(rs) && rs > 0.0f && isfinite(rs_b) && rs_b >= 0.0f) {
    t->stator_c = resistance_method(c, rs / c->rs_ref_ohm, c->stator_k_c, rs_b + c->rs_ref_bound_rel,
                                    &t->stator_uncert_k);
    t->stator_valid = (r->rs_valid && t->stator_uncert_k <= c->stator_tol_k) ? 1 : 0;
  }

  const float tr = (float)r->tr_s;
  const float tr_b = (float)r->tr_bound_rel;
  t->rr_ohm = NAN;
  t->rotor_c = NAN;
  t->rotor_uncert_k = NAN;
  t->rotor_valid = 0;
  if (isfinite(tr) && tr > 0.0f && isfinite(tr_b) && tr_b >= 0.0f && tr_b < 1.0f) {
    t->rr_ohm = c->lr_h / tr;
    /* R_R / R_R,ref = T_R,ref / T_R (L_R cancels); a bound b on T_R is b / (1 - b) on 1 / T_R */
    t->rotor_c = resistance_method(c, c->tr_ref_s / tr, c->rotor_k_c,
                                   tr_b / (1.0f - tr_b) + c->tr_ref_bound_rel, &t->rotor_uncert_k);
    t->rotor_valid = (r->tr_valid && t->rotor_uncert_k <= c->rotor_tol_k) ? 1 : 0;
  }

  if (t->stator_valid) valid |= 1;
  if (t->rotor_valid) valid |= 2;
  t->t_end_s = r->t_end_s;
  t->updates++;
  return valid;
}
