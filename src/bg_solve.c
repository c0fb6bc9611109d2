/* Stage 6: the background solve of one window (docs/METHOD.md §3..§7), orchestrating
 * bg_tables.c -> bg_resultant.c -> bg_roots.c -> bg_select.c -> bg_quality.c.
 *
 * Bounded: every loop has a compile-time bound (bg_poly.h): out->work, the sum
 * of Sturm evaluations, bisection steps, float64 polish evaluations and
 * quality-profile evaluations, is <= IMEST_SOLVE_WORK_BOUND (24466). Typical
 * (testvector): 12 Sturm evaluations, 63 float32 bisection steps, 20 float64
 * polish evaluations, 34 profile evaluations (work 129; at most 422 seen in
 * test/solve over 3000 garbage and 320 realistic windows).
 * Plus a fixed part: tables (~150 float64 ops), resultant (~700 float64
 * multiply-adds), selection (~80 per root), Hessian (~80).
 *
 * Stack (worst case, GCC 12 -O2 -fstack-usage for Cortex-M4F, float32 chain):
 * imest_solve_ex 2272 B (tables, r, 20 candidates) + imest_poly_positive_roots_ex
 * 4560 B (Sturm chain 1.8 KB, isolation stack 0.8 KB, domain polynomials and
 * found roots, helpers inlined) + polish helpers ~300 B = about 7.2 KB; the
 * quality stage (~0.6 KB) runs after the root finder has returned. No static
 * mutable data, no allocation. */
#include <math.h>

#include "bg_poly.h"

static int cfg_ok(const imest_solve_cfg_t *cfg) {
  return imest_finite(cfg->sigma) && cfg->sigma > 0.0 && cfg->sigma < 1.0 && imest_finite(cfg->ls_h) &&
         cfg->ls_h > 0.0 && imest_finite(cfg->tr_min_s) && imest_finite(cfg->tr_max_s) && cfg->tr_min_s > 0.0 &&
         cfg->tr_max_s > cfg->tr_min_s && imest_finite(cfg->weight_c) && cfg->weight_c >= 0.0;
}

double imest_solve_weight_c(const imest_sums_t *in) {
  if (in == 0) return 0.0;
  const double r44 = in->rw[3][3], r66 = in->rw[5][5];
  if (!(imest_finite(r44) && imest_finite(r66) && r44 > 0.0 && r66 >= 0.0)) return 0.0;
  const double c = sqrt(r66 / r44);
  return imest_finite(c) ? c : 0.0;
}

int imest_solve_ex(const imest_sums_t *in, const imest_solve_cfg_t *cfg, imest_solve_out_t *out,
                   imest_solve_stats_t *stats) {
  imest_solve_stats_t local;
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
  out->scale_s = out->scale_g = out->scale_c = nan;
  out->pe_flags = 0;
  out->work = 0;
  if (in == 0 || cfg == 0) return out->status = IMEST_ERR_NULL;
  if (!cfg_ok(cfg)) return out->status = IMEST_ERR_CONFIG;

  imest_tables_t t;
  if (imest_tables_build(in, cfg->tr_nominal_s, &t) != IMEST_OK) {
    stats->roots.sturm_evals = stats->roots.bisect_steps = stats->roots.polish_evals = 0;
    return out->status = IMEST_REASON_NUMERIC;
  }
  if (cfg->weight_c > 0.0) imest_tables_weight(&t, cfg->weight_c);
  out->scale_s = t.s;
  out->scale_g = t.g;
  out->scale_c = t.c;

  double r[22];
  imest_resultant(&t, r, 0);
  double kappa[IMEST_MAX_ROOTS];
  const int nr = imest_poly_positive_roots_ex(r, IMEST_RES_DEG, kappa, IMEST_MAX_ROOTS, &stats->roots);
  out->work = stats->roots.sturm_evals + stats->roots.bisect_steps + stats->roots.polish_evals;
  if (nr < 0) return out->status = IMEST_REASON_NUMERIC; /* non-finite or all-zero resultant */
  out->n_roots = (unsigned int)nr;
  for (int i = 0; i < nr; ++i) out->roots_k2[i] = kappa[i] * t.s;

  imest_cand_t best;
  unsigned int nad = 0;
  const int b = imest_select(&t, kappa, nr, cfg, in, &best, 0, &nad);
  out->n_admissible = nad;
  if (b < 0) return out->status = IMEST_REASON_NO_ROOT;

  const imest_cand_t *c = &best;
  out->k1 = c->k1;
  out->k2 = c->k2;
  out->tr_s = c->tr_s;
  out->rs_ohm = c->rs_ohm;
  /* E below zero is the cancellation floor of float32-accumulated sums */
  out->e = (c->e > 0.0) ? c->e : 0.0;
  out->e_w = (c->ew > 0.0) ? c->ew : 0.0;
  out->e_i = sqrt(out->e / in->ry);
  stats->quality_evals = imest_quality(&t, cfg, c, out);
  out->work += stats->quality_evals;

  const int finite = imest_finite(out->e_i) && imest_finite(out->hessian[0][0]) &&
                     imest_finite(out->hessian[0][1]) && imest_finite(out->hessian[1][1]) &&
                     imest_finite(out->pe_k1) && imest_finite(out->pe_k2) && imest_finite(out->pe_quad[0]) &&
                     imest_finite(out->pe_quad[1]);
  if (!finite) {
    out->hessian_pd = 0;
    return out->status = IMEST_REASON_NUMERIC;
  }
  return out->status = IMEST_OK;
}

int imest_solve(const imest_sums_t *in, const imest_solve_cfg_t *cfg, imest_solve_out_t *out) {
  return imest_solve_ex(in, cfg, out, 0);
}
