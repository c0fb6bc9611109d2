/* Background solve: from one window's sums to T_R, R_S and their quality.
 * Internal interface between the window bookkeeping (bg_task.c) and the solve
 * stages (bg_tables.c, bg_resultant.c, bg_roots.c, bg_select.c, bg_quality.c).
 * MATH.md §3..§7. */
#ifndef IMEST_BG_SOLVE_H
#define IMEST_BG_SOLVE_H

#include "imest/imest.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One window's sums, full 8x8 (structure already fixed: row/column 3 = -m x
 * row/column 4, (R_Wy)_3 = -m (R_Wy)_4), float64, not scaled. */
typedef struct {
  double rw[8][8];
  double rwy[8];
  double ry;
} imest_sums_t;

typedef struct {
  double sigma;        /* total leakage factor */
  double ls_h;         /* L_S [H] */
  double tr_nominal_s; /* for the power-of-two scaling s of K2 */
  double tr_min_s;     /* admissible T_R band for the selection */
  double tr_max_s;
} imest_solve_cfg_t;

typedef struct {
  int status;                 /* IMEST_OK, IMEST_ST_NUMERIC or IMEST_ST_NO_ROOT */
  unsigned int n_roots;       /* positive roots of the resultant */
  unsigned int n_admissible;  /* of which K1 > 0 and T_R in band */
  double roots_k2[IMEST_MAX_ROOTS];
  double k1, k2;              /* selected minimiser */
  double tr_s, rs_ohm;
  double e;                   /* E_p^2 at the minimiser (unscaled) */
  double e_i;                 /* sqrt(E / R_y) */
  double hessian[2][2];       /* unscaled, in (K1, K2) */
  int hessian_pd;
  double pe_k1, pe_k2;        /* parametric error indices (absolute), MATH.md §7 */
  double pe_quad[2];          /* quadratic approximations sqrt(0.5 E (H^-1)_ii) */
  double scale_s, scale_g, scale_c; /* the power-of-two scalings used */
  unsigned int pe_flags;      /* IMEST_PE_FLAG_* (bg_poly.h): how the PE indices were obtained */
  unsigned int work;          /* iterations used (Sturm evaluations + bisection + polish +
                                 quality evaluations); bounded, see bg_solve.c */
} imest_solve_out_t;

/* Solve one window. Always terminates within fixed iteration bounds; never
 * returns a non-finite value with status IMEST_OK. */
int imest_solve(const imest_sums_t *in, const imest_solve_cfg_t *cfg, imest_solve_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_SOLVE_H */
