/* SPDX-License-Identifier: Apache-2.0 */
/* Background solve: from one window's sums to T_R, R_S and their quality.
 * Internal interface between the window bookkeeping (bg_task.c) and the solve
 * stages (bg_tables.c, bg_resultant.c, bg_roots.c, bg_select.c, bg_quality.c).
 * docs/METHOD.md §3..§7. */
#ifndef IMEST_BG_SOLVE_H
#define IMEST_BG_SOLVE_H

#include "imest/imest.h"
#include "bg_bounds.h"
#include "bg_roots.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One window's sums, full 8x8 (structure already fixed: row/column 3 = -m x
 * row/column 4, (R_Wy)_3 = -m (R_Wy)_4), float64, not scaled. */
typedef struct {
  double rw[8][8];
  double rwy[8];
  double ry;
  /* Optional centred form (centred != 0): the ISR accumulated e = y - W c0,
   * so E(K) = R_ee - 2 R_We'd + d'R_W d with d = K - c0 is formed without the
   * cancellation of R_y - 2 R_Wy'K + K'R_W K (whose floor is ~1e-5 R_y with
   * float32-accumulated sums). 8-column form: c0[2] = 0, rwe[2] = -m rwe[3].
   * centred = 0 (e.g. a zero-initialised struct): E from the tables. */
  int centred;
  /* How far below zero E_p^2 of a candidate may come out before it counts as
   * garbage, beyond the cancellation floor: the noise's share taken out of the
   * sums leaves E_p^2 ~ 0 at the solution, plus or minus its fluctuation
   * (bg_noise.c). 0: none. */
  double e_slack;
  /* Optional (NULL: none): the noise's bias, of which noise_f was taken out
   * of the sums; a candidate far from c0 may then come out as far below zero
   * as the bias at its own K (imest__bg_noise_e), which e_slack (the bias at c0) does
   * not bound. */
  const struct bg_noise *noise;
  double noise_f, noise_m;
  double c0[8];
  double rwe[8];
  double ree;
} bg_sums_t;

/* 7-column index of the ISR's sums (W1 W2 W4 ...) -> 8-entry K index (column 3
 * rebuilt): 0, 1, 3, 4, 5, 6, 7 (bg_noise_bias.c; the window's stage uses it too). */
extern const unsigned int imest__bg_k_of_col[7];

typedef struct {
  double sigma;        /* total leakage factor */
  double ls_h;         /* L_S [H] */
  double tr_nominal_s; /* for the power-of-two scaling s of K2 */
  double tr_min_s;     /* admissible T_R band for the selection */
  double tr_max_s;
  /* Speed normalisation of the cost, c [(1/s)^2]: the solve minimises
   * E_w = E_p^2 K2^4 / (K2^2 + c)^2 instead of the paper's E_p^2. The
   * eliminated equation was multiplied by (1 + n_p^2 w^2 T_R^2) (docs/METHOD.md §2),
   * which weights the residual ~(1 + n_p^2 w^2 T_R^2)^2 and lets any noise
   * floor pull the minimum to the spurious K2 ~ n_p w; with c = n_p^2 w^2
   * that weight is divided out. Use imest__bg_solve_weight_c() (current-weighted
   * n_p^2 w^2 of the window). 0 = the paper's cost (exactly); negative or
   * non-finite: IMEST_ERR_CONFIG. */
  double weight_c;
  /* E_p^2 the sensors' noise explains (bg_noise.c), taken out of the sums:
   * the parametric error indices are those of the residual as measured
   * (L = E* + 0.25 (E* + e_noise)), not of the compensated one, which is ~0.
   * 0: none. */
  double e_noise;
} bg_solve_cfg_t;

typedef struct {
  int status;                /* IMEST_OK, IMEST_REASON_NUMERIC or IMEST_REASON_NO_ROOT */
  unsigned int n_roots;      /* positive roots of the resultant */
  unsigned int n_admissible; /* of which K1 > 0 and T_R in band */
  double roots_k2[IMEST_MAX_ROOTS];
  double k1, k2; /* selected minimiser */
  double tr_s, rs_ohm;
  double e;             /* the paper's E_p^2 at the minimiser (unscaled) */
  double e_i;           /* sqrt(E_p^2 / R_y) */
  double e_w;           /* the minimised cost E_w at the minimiser (= e if weight_c = 0) */
  double hessian[2][2]; /* of E_w (the minimised cost), unscaled, in (K1, K2) */
  int hessian_pd;
  double pe_k1, pe_k2; /* parametric error indices (absolute), docs/METHOD.md §7, of E_w */
  double pe_quad[2];   /* quadratic approximations sqrt(0.5 E (H^-1)_ii) */
  double noise_e_k;    /* the noise's E_p^2 at the minimiser, imest__bg_noise_e (0: no in->noise) */
  double scale_s, scale_g, scale_c; /* the power-of-two scalings used */
  unsigned int pe_flags;            /* BG_PE_FLAG_* (bg_quality.h): how the PE indices were obtained */
  unsigned int work;                /* iterations used (Sturm evaluations + bisection + polish +
                                 quality evaluations); bounded, see bg_solve.c */
} bg_solve_out_t;

/* Solve one window. Always terminates within fixed iteration bounds; never
 * returns a non-finite value with status IMEST_OK. */
int imest__bg_solve(const bg_sums_t *in, const bg_solve_cfg_t *cfg, bg_solve_out_t *out);

/* The cost weight c = sqrt(R66/R44) (1-based: |W6|^2 ~ (n_p w)^4 |i|^2 per
 * |i|^2 = |W4|^2), i.e. the current-weighted n_p^2 w^2 of the window; 0 if
 * undefined (no current, non-finite sums). */
double imest__bg_solve_weight_c(const bg_sums_t *in);

typedef struct {
  bg_roots_stats_t roots;
  unsigned int quality_evals;
} bg_solve_stats_t;

/* imest__bg_solve with optional instrumentation (stats may be NULL). */
int imest__bg_solve_ex(const bg_sums_t *in, const bg_solve_cfg_t *cfg, bg_solve_out_t *out,
                       bg_solve_stats_t *stats);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_SOLVE_H */
