/* SPDX-License-Identifier: Apache-2.0 */
/* The property every background solve must have, whatever the sums: shared by
 * the seeded random test (test_solve_random.cpp) and the libFuzzer target
 * (fuzz/fuzz_solve.cpp). Internal interface: include src/ privately. */
#ifndef IMEST_SOLVE_PROPERTY_H
#define IMEST_SOLVE_PROPERTY_H

#include <math.h>
#include <stddef.h>

#include "bg_solve.h" /* with bg_bounds.h: BG_SOLVE_WORK_BOUND, the one definition */

/* NULL if out (returned as rc by imest__bg_solve for cfg) has the property, else
 * what is wrong. */
static inline const char *solve_property(int rc, const bg_solve_cfg_t *cfg, const bg_solve_out_t *out)
{
  if (rc != out->status) return "return value differs from out->status";
  if (!(rc == IMEST_OK || rc == IMEST_REASON_NUMERIC || rc == IMEST_REASON_NO_ROOT ||
        rc == IMEST_ERR_CONFIG || rc == IMEST_ERR_NULL))
    return "status is not one of OK, NUMERIC, NO_ROOT, ERR_CONFIG, ERR_NULL";
  if (out->n_roots > IMEST_MAX_ROOTS) return "n_roots > IMEST_MAX_ROOTS";
  if (out->n_admissible > out->n_roots) return "n_admissible > n_roots";
  if (out->work > BG_SOLVE_WORK_BOUND) return "work beyond the documented iteration bound";
  for (unsigned int k = 0; k < out->n_roots; ++k) {
    if (!(isfinite(out->roots_k2[k]) && out->roots_k2[k] > 0.0)) return "a root is not finite and positive";
    if (k > 0 && !(out->roots_k2[k] >= out->roots_k2[k - 1])) return "roots not ascending";
  }
  if (rc != IMEST_OK) return NULL;
  if (!(isfinite(out->tr_s) && isfinite(out->rs_ohm) && isfinite(out->e_i) && isfinite(out->k1) &&
        isfinite(out->k2) && isfinite(out->e)))
    return "status OK with a non-finite T_R, R_S, K1, K2, E or E_I";
  if (!(out->tr_s >= cfg->tr_min_s && out->tr_s <= cfg->tr_max_s))
    return "status OK with T_R outside the band";
  if (!(out->k1 > 0.0 && out->k2 > 0.0)) return "status OK with K1 or K2 not positive";
  if (!(fabs(out->tr_s * out->k2 - 1.0) <= 1e-12)) return "T_R != 1/K2";
  if (!(out->e_i >= 0.0 && out->e >= 0.0)) return "negative E or E_I";
  if (!(isfinite(out->hessian[0][0]) && isfinite(out->hessian[0][1]) && isfinite(out->hessian[1][1]) &&
        isfinite(out->pe_k1) && isfinite(out->pe_k2)))
    return "status OK with a non-finite Hessian or PE index";
  if (out->n_admissible < 1u) return "status OK without an admissible root";
  return NULL;
}

#endif
