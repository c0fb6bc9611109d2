/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 6: the background solve of one window (docs/METHOD.md §3..§7), orchestrating
 * bg_tables.c -> bg_resultant.c -> bg_roots.c -> bg_select.c -> bg_quality.c.
 *
 * Bounded: every loop has a compile-time bound (bg_bounds.h): out->work, the
 * sum of Sturm evaluations, bisection steps, float64 polish evaluations and
 * quality-profile evaluations, is <= BG_SOLVE_WORK_BOUND. The counts of a
 * typical window are printed by imest-bench-solve (test/solve), the largest
 * seen by the robustness tests (test/solve, test/robustness). Plus a fixed
 * part: tables, resultant (three convolutions), selection and Hessian.
 *
 * Stack (worst case, GCC 12 -O2 -fstack-usage for Cortex-M4F, float32 chain):
 * imest__bg_solve_ex 2272 B (tables, r, 20 candidates) + imest__bg_roots_positive_ex
 * 4560 B (Sturm chain 1.8 KB, isolation stack 0.8 KB, domain polynomials and
 * found roots, helpers inlined) + polish helpers ~300 B = about 7.2 KB; the
 * quality stage (~0.6 KB) runs after the root finder has returned. No static
 * mutable data, no allocation. */
#include <math.h>

#include "bg_noise_bias.h"
#include "bg_quality.h"
#include "bg_resultant.h"
#include "bg_float.h" /* BG_FMAX...: no libm fmax on a core without VMAXNM */

static int cfg_ok(const bg_solve_cfg_t *cfg)
{
  return imest__bg_finite(cfg->sigma) && cfg->sigma > 0.0 && cfg->sigma < 1.0 &&
         imest__bg_finite(cfg->ls_h) && cfg->ls_h > 0.0 && imest__bg_finite(cfg->tr_min_s) &&
         imest__bg_finite(cfg->tr_max_s) && cfg->tr_min_s > 0.0 && cfg->tr_max_s > cfg->tr_min_s &&
         imest__bg_finite(cfg->weight_c) && cfg->weight_c >= 0.0;
}

double imest__bg_solve_weight_c(const bg_sums_t *in)
{
  if (in == 0) return 0.0;
  const double r44 = in->rw[3][3], r66 = in->rw[5][5];
  if (!(imest__bg_finite(r44) && imest__bg_finite(r66) && r44 > 0.0 && r66 >= 0.0)) return 0.0;
  const double c = BG_SQRT(BG_DIV(r66, r44));
  return imest__bg_finite(c) ? c : 0.0;
}

int imest__bg_solve_ex(const bg_sums_t *in, const bg_solve_cfg_t *cfg, bg_solve_out_t *out,
                       bg_solve_stats_t *stats)
{
  bg_solve_stats_t local;
  if (stats == 0) stats = &local;
  stats->quality_evals = 0;
  if (out == 0) return IMEST_ERR_NULL;
  const double nan = (double)NAN;
  out->n_roots = out->n_admissible = 0;
  for (int i = 0; i < IMEST_MAX_ROOTS; ++i) out->roots_k2[i] = 0.0;
  out->k1 = out->k2 = out->tr_s = out->rs_ohm = nan;
  out->e = out->e_i = out->e_w = nan;
  out->hessian[0][0] = out->hessian[0][1] = out->hessian[1][0] = out->hessian[1][1] = nan;
  out->hessian_pd = 0;
  out->pe_k1 = out->pe_k2 = nan;
  out->pe_quad[0] = out->pe_quad[1] = nan;
  out->noise_e_k = 0.0;
  out->scale_s = out->scale_g = out->scale_c = nan;
  out->pe_flags = 0;
  out->work = 0;
  if (in == 0 || cfg == 0) return out->status = IMEST_ERR_NULL;
  if (!cfg_ok(cfg)) return out->status = IMEST_ERR_CONFIG;

  bg_tables_t t;
  if (imest__bg_tables_build_weighted(in, cfg->tr_nominal_s, cfg->weight_c, &t) != IMEST_OK) {
    stats->roots.sturm_evals = stats->roots.bisect_steps = stats->roots.polish_evals = 0;
    return out->status = IMEST_REASON_NUMERIC;
  }
  out->scale_s = t.s;
  out->scale_g = t.g;
  out->scale_c = t.c;

  double r[22];
  imest__bg_resultant(&t, r, 0);
  double kappa[IMEST_MAX_ROOTS];
  const int nr = imest__bg_roots_positive_ex(r, BG_RES_DEG, kappa, IMEST_MAX_ROOTS, &stats->roots);
  out->work = stats->roots.sturm_evals + stats->roots.bisect_steps + stats->roots.polish_evals;
  if (nr < 0) return out->status = IMEST_REASON_NUMERIC; /* non-finite or all-zero resultant */
  out->n_roots = (unsigned int)nr;
  for (int i = 0; i < nr; ++i) out->roots_k2[i] = kappa[i] * t.s;

  bg_cand_t best;
  unsigned int nad = 0;
  const int b = imest__bg_select(&t, kappa, nr, cfg, in, &best, 0, &nad);
  out->n_admissible = nad;
  if (b < 0) return out->status = IMEST_REASON_NO_ROOT;

  const bg_cand_t *c = &best;
  out->k1 = c->k1;
  out->k2 = c->k2;
  out->tr_s = c->tr_s;
  out->rs_ohm = c->rs_ohm;
  /* E below zero is the cancellation floor of float32-accumulated sums */
  out->e = (c->e > 0.0) ? c->e : 0.0;
  out->e_w = (c->ew > 0.0) ? c->ew : 0.0;
  out->e_i = BG_SQRT(BG_DIV(out->e, in->ry));
  /* The error indices take the residual as measured: the noise's share at
   * the selected K, not at the centring (far from the solution the latter
   * can be much smaller, and a negative compensated E then reads as an
   * exact fit: pe 0). */
  if (in->noise) out->noise_e_k = imest__bg_noise_e_at(in->noise, c->k1, c->k2, in->noise_m);
  bg_solve_cfg_t qcfg = *cfg;
  if (in->noise && in->noise_f > 0.0) qcfg.e_noise = BG_FMAX(cfg->e_noise, in->noise_f * out->noise_e_k);
  stats->quality_evals = imest__bg_quality(&t, &qcfg, c, out);
  out->work += stats->quality_evals;

  const int finite = imest__bg_finite(out->e_i) && imest__bg_finite(out->hessian[0][0]) &&
                     imest__bg_finite(out->hessian[0][1]) && imest__bg_finite(out->hessian[1][1]) &&
                     imest__bg_finite(out->pe_k1) && imest__bg_finite(out->pe_k2) &&
                     imest__bg_finite(out->pe_quad[0]) && imest__bg_finite(out->pe_quad[1]);
  if (!finite) {
    out->hessian_pd = 0;
    return out->status = IMEST_REASON_NUMERIC;
  }
  return out->status = IMEST_OK;
}

int imest__bg_solve(const bg_sums_t *in, const bg_solve_cfg_t *cfg, bg_solve_out_t *out)
{
  return imest__bg_solve_ex(in, cfg, out, 0);
}
