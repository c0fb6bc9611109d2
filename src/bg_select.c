/* Stage 4 of the background solve: candidates and selection (MATH.md §7).
 * For every positive root kappa of the resultant: k = -a0/a1 (a1 > 0 for
 * K2 > 0 with a positive semi-definite R_W), E in float64, K1 = g k,
 * K2 = s kappa, T_R = 1/K2, R_S = sigma L_S K1 - (1 - sigma) L_S K2.
 * Admissible: everything finite, a1(kappa) > 0, K1 > 0, T_R in
 * [tr_min, tr_max], and E >= -1e-4 R_y (E is formed by cancellation: with
 * float32-accumulated sums its resolution is about 1e-5 R_y, measured, and
 * noise-free data put the true minimum right at that floor; a clearly
 * negative E is garbage). The
 * admissible candidate with the least E is selected (first one on a tie). */
#include <math.h>

#include "bg_poly.h"

int imest_select(const imest_tables_t *t, const double *kappa, int n, const imest_solve_cfg_t *cfg,
                 double ry, imest_cand_t *cand, unsigned int *n_admissible) {
  int best = -1;
  unsigned int nad = 0;
  for (int i = 0; i < n; ++i) {
    imest_cand_t *c = &cand[i];
    imest_tabval_t v;
    const double x = kappa[i];
    imest_tables_eval(t, x, &v);
    const double a1 = 2.0 * v.e2, a0 = v.e1;
    c->kappa = x;
    c->k = -a0 / a1;
    const double x2 = x * x;
    const double es = (v.e2 * c->k * c->k + v.e1 * c->k + v.e0) / (x2 * x2);
    c->e = ldexp(es, t->cexp);
    c->k1 = ldexp(c->k, t->gexp);
    c->k2 = ldexp(x, t->sexp);
    c->tr_s = 1.0 / c->k2;
    c->rs_ohm = cfg->sigma * cfg->ls_h * c->k1 - (1.0 - cfg->sigma) * cfg->ls_h * c->k2;
    c->admissible = isfinite(c->k1) && isfinite(c->k2) && isfinite(c->e) && isfinite(c->tr_s) &&
                    isfinite(c->rs_ohm) && a1 > 0.0 && c->k1 > 0.0 && c->k2 > 0.0 &&
                    c->tr_s >= cfg->tr_min_s && c->tr_s <= cfg->tr_max_s && c->e >= -1e-4 * ry;
    if (c->admissible) {
      ++nad;
      if (best < 0 || c->e < cand[best].e) best = i;
    }
  }
  *n_admissible = nad;
  return best;
}
