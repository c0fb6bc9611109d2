/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning result: the background's values with the ISR's live figures, and an estimator
 * config filled from it. Read-only calls, any context. */
#include <math.h>
#include <stddef.h>

#include "commission_internal.h"
#include "estimator/window/bg_flux.h"     /* IMEST_WITH_FLUX */
#include "estimator/window/bg_validity.h" /* IMEST_WITH_ROTOR_HF */
#include "estimator/solve/bg_float.h"     /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

int imest_comm_result(const imest_comm_t *c, imest_comm_result_t *r)
{
  if (c == NULL || r == NULL) return IMEST_ERR_NULL;
  imest__cm_copy(r, &c->res, sizeof *r);
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

/* 3 standard errors (NaN: not known, 0). */
static float std3_rel(const imest_comm_value_t *v)
{
  return isfinite(v->std_rel) ? CM_COVERAGE * v->std_rel : 0.0f;
}

/* A value's relative uncertainty from its quality: the larger of 3 standard
 * errors and the axes' spread (either NaN: not known, left out). */
static float quality_rel(const imest_comm_value_t *v)
{
  return BG_FMAXF(std3_rel(v), isfinite(v->spread_rel) ? v->spread_rel : 0.0f);
}

/* min(u, IMEST_COMM_UNCERTAINTY_MAX), the maximum for NaN (as fminf, written out) */
static float at_most_max(float u)
{
  return u < IMEST_COMM_UNCERTAINTY_MAX ? u : IMEST_COMM_UNCERTAINTY_MAX;
}

/* 1 if the result's sigma is the one at slip frequency: a single cage's square wave, or a
   deep-bar rotor's slip-frequency test (else the square wave saw its high-frequency leakage). */
static int sigma_at_slip(const imest_comm_result_t *r)
{
  return !(r->flags & IMEST_COMM_FLAG_ROTOR_HF) || (r->flags & IMEST_COMM_FLAG_SIGMA_SLIP) != 0u;
}

/* The rule imest_commission.h states for ls_uncertainty and sigma_uncertainty.
 * curve: the magnetising curve goes to the config, so the estimator takes L_S
 * (and sigma with it) at each window's flux, and their change over the curve
 * (ls_h's, sigma's spread_rel) is no longer an error of what it uses. A
 * high-frequency sigma (IMEST_COMM_FLAG_ROTOR_HF without the slip-frequency
 * test's) is not filled: the config's sigma and its stated uncertainty stay. */
static void constants_uncertainty(const imest_comm_result_t *r, int curve, imest_config_t *cfg)
{
  const int standstill = (r->flags & IMEST_COMM_FLAG_LS_STANDSTILL) != 0u;
  const float q_ls = curve ? std3_rel(&r->ls_h) : quality_rel(&r->ls_h);
  const float u_ls = BG_FMAXF(standstill ? IMEST_COMM_LS_FLOOR_STANDSTILL : IMEST_COMM_LS_FLOOR,
                              BG_FMAXF(q_ls, standstill ? quality_rel(&r->ls_standstill_h) : 0.0f));
  cfg->ls_uncertainty = at_most_max(u_ls);
  if (!sigma_at_slip(r)) return;
  const float q_sg = curve ? std3_rel(&r->sigma) : quality_rel(&r->sigma);
  const float u_sg = BG_FMAXF(standstill ? IMEST_COMM_SIGMA_FLOOR_STANDSTILL : IMEST_COMM_SIGMA_FLOOR,
                              BG_FMAXF(q_sg, quality_rel(&r->sigma_ls_h) + u_ls));
  cfg->sigma_uncertainty = at_most_max(u_sg);
}

/* A deep-bar rotor at high frequency (imest_comm_apply): the square wave's resistance and leakage
 * against the slip-frequency ones, one pole (imest_config_t.rotor_hf_rr_ratio); 1 if filled. */
static int apply_rotor_hf(const imest_comm_result_t *r, imest_config_t *cfg)
{
  if (!(IMEST_WITH_ROTOR_HF && (r->flags & IMEST_COMM_FLAG_ROTOR_HF) &&
        (r->flags & IMEST_COMM_FLAG_SIGMA_SLIP)))
    return 0;
  const float rr_ratio = r->rr_hf_ohm.value / r->rr_slip_ohm.value,
              sl_ratio = r->sigma_ls_hf_h.value / r->sigma_ls_slip_h.value;
  if (!(rr_ratio > 1.0f && sl_ratio > 0.0f)) return 0;
  cfg->rotor_hf_rr_ratio = rr_ratio;
  cfg->rotor_hf_sigma_ratio = sl_ratio < 1.0f ? sl_ratio : 1.0f;
  return 1;
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
  const int curve =
      IMEST_WITH_FLUX && r->ls_curve_points >= 2u && r->ls_curve_points <= IMEST_LS_CURVE_POINTS;
  constants_uncertainty(r, curve, cfg);
  n += 2;
  if (sigma_at_slip(r)) { /* else its sigma is the high-frequency one */
    cfg->sigma = r->sigma.value;
    n++;
  }
  if (isfinite(r->tr_s.value) && r->tr_s.value > 0.0f) {
    cfg->tr_nominal_s = r->tr_s.value;
    n++;
  }
  if (r->inverter.uncertainty >= 0.0f) {
    cfg->inverter = r->inverter;
    cfg->inverter_vdc_v = r->vdc_v; /* the bus for measured phase voltages' harmonics */
    n++;
  }
  n += apply_rotor_hf(r, cfg);
  /* the magnetising curve: the estimator follows L_S with the window's flux (bg_flux.c) */
  if (curve) {
    cfg->ls_curve_points = r->ls_curve_points;
    for (unsigned int k = 0; k < IMEST_LS_CURVE_POINTS; ++k) {
      cfg->ls_curve_i_a[k] = k < r->ls_curve_points ? r->ls_curve_i_a[k] : 0.0f;
      cfg->ls_curve_h[k] = k < r->ls_curve_points ? r->ls_curve_h[k] : 0.0f;
    }
    n++;
  }
  return n;
}
