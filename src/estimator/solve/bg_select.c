/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 4 of the background solve: candidates and selection (docs/METHOD.md §7).
 * For every positive root kappa of the resultant: k = -a0/a1 (a1 > 0 for
 * K2 > 0 with a positive semi-definite R_W), K1 = g k, K2 = s kappa,
 * T_R = 1/K2, R_S = sigma L_S K1 - (1 - sigma) L_S K2, the paper's E_p^2 and
 * the minimised cost E_w = E_p^2 kappa^4 / (kappa^2 + cw)^2 (= E_p^2 if cw = 0).
 * E_p^2 is formed by cancellation. From the tables (R_y - 2 R_Wy'K + K'R_W K)
 * its floor is about 1e-5 R_y with float32-accumulated sums (measured: noise-
 * free data gave -1.2e-5 R_y at the true root). When the sums carry their
 * centred form (bg_sums_t.centred), E_p^2 of every candidate that passes
 * the other checks is recomputed as R_ee - 2 R_We'd + d'R_W d, d = K - c0,
 * which is small near the centring and has no such floor.
 * Admissible: everything finite, a1(kappa) > 0, K1 > 0, T_R in
* [tr_min, tr_max], and E_p^2 >= -1e-4 R_y (a clearly negative E is garbage),
 * or, where the noise's bias was subtracted from the sums, E_p^2 no further
 * below zero than that bias at the candidate's own K (with the centring far
 * from the solution, e.g. on the nominal T_R, the bias at the centring says
 * nothing about it: 11 kW at 80 % speed, every window refused).
 * The admissible candidate with the least E_w is selected (first one on a tie). */
#include "bg_select.h"
#include "bg_noise_bias.h"

#include <math.h>
#include "bg_float.h" /* BG_FMAX...: no libm fmax on a core without VMAXNM */

static int centred_ok(const bg_sums_t *in)
{
  if (!in->centred || !imest__bg_finite(in->ree)) return 0;
  for (int i = 0; i < 8; ++i)
    if (!imest__bg_finite(in->c0[i]) || !imest__bg_finite(in->rwe[i])) return 0;
  return 1;
}

double imest__bg_e_centred(const bg_sums_t *in, double k1, double k2)
{
  const double ik = BG_DIV(1.0, k2), ik2 = ik * ik;
  const double K[8] = {k1, k2, k2 * k2, k1 * k2, ik, k1 * ik, k1 * ik2, ik2};
  double d[8];
  for (int i = 0; i < 8; ++i) d[i] = K[i] - in->c0[i];
  /* R_ee - 2 R_We'd + d'R_W d, R_W symmetric: upper triangle twice */
  double e = in->ree;
  for (int i = 0; i < 8; ++i) {
    double off = 0.0;
    for (int j = i + 1; j < 8; ++j) off += in->rw[i][j] * d[j];
    e += d[i] * (in->rw[i][i] * d[i] + 2.0 * (off - in->rwe[i]));
  }
  return e;
}

int imest__bg_select(const bg_tables_t *t, const double *kappa, int n, const bg_solve_cfg_t *cfg,
                     const bg_sums_t *in, bg_cand_t *best, bg_cand_t *cand, unsigned int *n_admissible)
{
  int ib = -1;
  unsigned int nad = 0;
  const int centred = centred_ok(in);
  const double floor_e = -1e-4 * in->ry - in->e_slack;
  for (int i = 0; i < n; ++i) {
    bg_cand_t cv;
    bg_cand_t *c = &cv;
    double v[3];
    const double x = kappa[i];
    imest__bg_tables_values(t, x, v);
    const double a1 = 2.0 * v[0], a0 = v[1];
    c->kappa = x;
    c->k = BG_DIV(-a0, a1);
    const double x2 = x * x, x4 = x2 * x2;
    const double p = (v[0] * c->k + v[1]) * c->k + v[2];
    c->e = BG_DIV(p, x4) * t->c;
    double w = 1.0; /* kappa^4 / (kappa^2 + cw)^2 */
    if (t->cw != 0.0) {
      const double dd = x2 + t->cw;
      w = BG_DIV(x4, dd * dd);
    }
    c->k1 = c->k * t->g;
    c->k2 = x * t->s;
    c->tr_s = BG_DIV(1.0, c->k2);
    c->rs_ohm = cfg->sigma * cfg->ls_h * c->k1 - (1.0 - cfg->sigma) * cfg->ls_h * c->k2;
    c->admissible = imest__bg_finite(c->k1) && imest__bg_finite(c->k2) && imest__bg_finite(c->tr_s) &&
                    imest__bg_finite(c->rs_ohm) && a1 > 0.0 && c->k1 > 0.0 && c->k2 > 0.0 &&
                    c->tr_s >= cfg->tr_min_s && c->tr_s <= cfg->tr_max_s;
    if (c->admissible && centred) c->e = imest__bg_e_centred(in, c->k1, c->k2);
    c->ew = c->e * w;
    double floor_c = floor_e;
    if (c->admissible && c->e < floor_e && in->noise && in->noise_f > 0.0) {
      floor_c = -1e-4 * in->ry -
                in->noise_f * BG_FMAX(0.0, imest__bg_noise_e_at(in->noise, c->k1, c->k2, in->noise_m));
    }
    c->admissible = c->admissible && imest__bg_finite(c->e) && imest__bg_finite(c->ew) && c->e >= floor_c;
    if (c->admissible) {
      ++nad;
      if (ib < 0 || c->ew < best->ew) {
        ib = i;
        *best = *c;
      }
    }
    if (cand) cand[i] = *c;
  }
  *n_admissible = nad;
  return ib;
}
