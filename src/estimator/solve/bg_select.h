/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: candidates and selection (docs/METHOD.md §7).
 * Internal: not part of the public API. */
#ifndef IMEST_BG_SELECT_H
#define IMEST_BG_SELECT_H

#include "bg_tables.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  double kappa, k; /* scaled root and back-substituted k = -a0/a1 */
  double k1, k2;   /* K1 = g k, K2 = s kappa */
  double e;        /* the paper's E_p^2 (unscaled; centred form if the sums have it) */
  double ew;       /* the minimised cost E_w = E_p^2 kappa^4 / (kappa^2 + cw)^2 (unscaled) */
  double tr_s, rs_ohm;
  int admissible; /* K1 > 0, T_R in band, all finite, E above -1e-4 R_y */
} bg_cand_t;

/* Evaluate every root as a candidate and pick the admissible one with least
 * E_w (first one on a tie) into *best. cand (may be NULL) receives every
 * candidate. Returns the index of the selected candidate, or -1 if none is
 * admissible. */
int imest__bg_select(const bg_tables_t *t, const double *kappa, int n, const bg_solve_cfg_t *cfg,
                     const bg_sums_t *in, bg_cand_t *best, bg_cand_t *cand, unsigned int *n_admissible);

/* E_p^2(K1, K2) from the centred sums (in->centred must be set). */
double imest__bg_e_centred(const bg_sums_t *in, double k1, double k2);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_SELECT_H */
