/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: every positive root of a polynomial by Sturm sequences
 * and bisection (docs/METHOD.md §6). Internal: not part of the public API. */
#ifndef IMEST_BG_ROOTS_H
#define IMEST_BG_ROOTS_H

#include "bg_bounds.h"
#include "bg_float.h"

#ifdef __cplusplus
extern "C" {
#endif

/* All distinct positive roots of sum_k c[k] x^k (deg <= BG_POLY_MAXDEG) by
 * Sturm sequences and bisection, (0,1] on p and (1,inf) on the reversed
 * polynomial in four scaled domains, each root polished in float64 (see
 * bg_roots.c for the design).
 * The Sturm chain is float32 unless BG_ROOTS_DOUBLE is defined.
 * Returns the number of roots written to roots[] (ascending, at most max), or
 * -1 for a non-finite or all-zero polynomial or a bad deg. */
typedef struct {
  unsigned int sturm_evals;  /* evaluations of the sign-change count V(x) */
  unsigned int bisect_steps; /* sign or count bisection steps (chain precision) */
  unsigned int polish_evals; /* float64 polynomial evaluations in the polish */
  unsigned int chain_len;    /* longest Sturm chain built (number of polynomials) */
  unsigned int unresolved;   /* clusters that could not be separated (reported once) */
  unsigned int rejected;     /* isolated intervals whose float64 check failed */
  unsigned int merged;       /* duplicates merged (a root found from both sides of 1) */
  unsigned int rescues;      /* domains where the float64 parity check triggered the grid rescue */
  double max_chain_rel;      /* largest |polished - chain-precision estimate| / root, in the
                                 domain variable: what the chain precision alone would give */
} bg_roots_stats_t;

int imest__bg_roots_positive(const double *c, int deg, double *roots, int max);
int imest__bg_roots_positive_ex(const double *c, int deg, double *roots, int max, bg_roots_stats_t *st);

/* Horner evaluation of sum_k c[k] x^k (float64). */
double imest__bg_poly_eval(const double *c, int deg, double x);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_ROOTS_H */
