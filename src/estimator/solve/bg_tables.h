/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: power-of-two scaling, cost tables and p1/p2 coefficients
 * (docs/METHOD.md §3..§5). Internal: not part of the public API. */
#ifndef IMEST_BG_TABLES_H
#define IMEST_BG_TABLES_H

#include "bg_solve.h"
#include "bg_float.h"
#include "bg_ff.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Power-of-two scalings (docs/METHOD.md §5) and the scaled cost tables (§3) and
 * p1/p2 coefficients (§4), all float64, in the scaled unknowns (k, kappa):
 * K1 = g k, K2 = s kappa, E = c E~.
 * Weighted cost (cfg.weight_c = c_w, scaled cw = c_w/s^2, D = kappa^2 + cw):
 * E_w~ = P/D^2 with P = sum_m (e2[m] k^2 + e1[m] k + e0[m]) kappa^m
 * (E_p^2~ = P/kappa^4). dE_w/dk = 0 <=> p1 = a1 k + a0 = 0 (as the paper);
 * dE_w/dkappa = 0 <=> p2w = D P' - 4 kappa P = bw2 k^2 + bw1 k + bw0 = 0 with
 * bw_t(kappa) = kappa b_t(kappa) + cw t'(kappa), b_t[m] = (m-4) t[m] the
 * paper's. With cw = 0, p2w = kappa p2 exactly (bw_t[m+1] = b_t[m], bw_t[0] = 0). */
typedef struct {
  int sexp, gexp, cexp; /* s = 2^sexp, g = 2^gexp, c = 2^cexp */
  double s, g, c;
  double cw;                      /* weight c_w / s^2 (0: the paper's cost) */
  double e2[7], e1[8], e0[9];     /* E~ = kappa^-4 sum_m (e2[m] k^2 + e1[m] k + e0[m]) kappa^m */
  double a1[7], a0[8];            /* p1 = a1(kappa) k + a0(kappa) */
  double bw2[8], bw1[9], bw0[10]; /* p2w = bw2 k^2 + bw1 k + bw0 */
#if BG_SOFT_DOUBLE
  /* e2, e1, e0 in float-float (bg_ff.h) at ff[0], ff[7], ff[15], for the
   * value evaluations and the resultant where double is soft; ff_ok = 0 if an
   * entry is outside 2^+-32 (float64 then) */
  bg_ff_t ff[24];
  int ff_ok;
#endif
} bg_tables_t;

/* Tables for given exponents (no data-driven choice): R~ = D R D / c with
 * D = diag(g, s, s^2, g s, 1/s, g/s, g/s^2, 1/s^2), each entry scaled by one
 * power-of-two multiplication (exact unless it under/overflows). cw is set
 * from weight_c (c_w / s^2). Also fills a*, bw*. */
void imest__bg_tables_scaled(const bg_sums_t *in, int sexp, int gexp, int cexp, bg_tables_t *t);
void imest__bg_tables_weight(bg_tables_t *t, double weight_c); /* sets cw, refills bw* */

/* Choose s from tr_nominal_s, c from R_y and g from the data (docs/METHOD.md §5) and
 * build the tables (cw = 0; call imest__bg_tables_weight for c_w > 0). Returns
 * IMEST_OK, or IMEST_REASON_NUMERIC for non-finite sums, R_y <= 0 or non-finite
 * tables. */
int imest__bg_tables_build(const bg_sums_t *in, double tr_nominal_s, bg_tables_t *t);
/* The same with the weight c_w (cfg.weight_c; <= 0: the paper's cost): what
 * imest__bg_tables_build and imest__bg_tables_weight give, with bw* formed once. */
int imest__bg_tables_build_weighted(const bg_sums_t *in, double tr_nominal_s, double weight_c,
                                    bg_tables_t *t);

/* Values of e2(kappa), e1(kappa), e0(kappa) (polynomials in kappa) and their
 * first and second kappa-derivatives. */
typedef struct {
  double e2, e1, e0;
  double d2, d1, d0;    /* first derivatives */
  double dd2, dd1, dd0; /* second derivatives */
} bg_tabval_t;
void imest__bg_tables_eval(const bg_tables_t *t, double kappa, bg_tabval_t *v);
/* Values only: v[0] = e2, v[1] = e1, v[2] = e0 at kappa. Where double is soft,
 * in float-float if ff_ok and 2^-8 <= kappa < 2^8 (the range docs/METHOD.md
 * §10.4 bounds), else in float64. */
void imest__bg_tables_values(const bg_tables_t *t, double kappa, double v[3]);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_TABLES_H */
