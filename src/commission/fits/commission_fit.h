/* SPDX-License-Identifier: Apache-2.0 */
/* Background helpers shared by the commissioning fits (float64). Internal. */
#ifndef IMEST_COMMISSION_FIT_H
#define IMEST_COMMISSION_FIT_H

#include "commission_internal.h"
#include "estimator/solve/bg_float.h" /* BG_SQRT: the estimator's correctly rounded sqrt, no libm */

/* e^x to a few ulp (commission_decay.c): no libm. */
double imest__cm_exp(double x);

/* Powers of q = exp(-ts / tau) (commission_decay.c). */
#define CM_DECAY_MEMO 6u
typedef struct {
  double q, one_minus_q;
  uint32_t key[CM_DECAY_MEMO];
  double val[CM_DECAY_MEMO];
  unsigned int next;
} cm_decay_t;
void imest__cm_decay_init(cm_decay_t *d, double ts, double tau);
double imest__cm_decay_pow(cm_decay_t *d, uint32_t n);  /* q^n */
double imest__cm_decay_mean(cm_decay_t *d, uint32_t n); /* mean of q^j, j = 0 .. n - 1 */

/* Weighted least-squares line y = c0 + a x (commission_lsq.c): the sums, added to per point
   (start from all zero). */
typedef struct {
  double w, x, y, xx, xy, yy;
} cm_line_t;
void imest__cm_line_add(cm_line_t *l, double w, double x, double y);
/* The slope a and the weighted residual sum of squares. Without two distinct x (or no weight)
   a = 0 and the sum is about the mean of y. */
double imest__cm_line_fit(const cm_line_t *l, double *a);

/* Minimum of f on [lo, hi] by golden-section search (a fixed number of iterations). */
double imest__cm_golden(double (*f)(void *, double), void *ctx, double lo, double hi, unsigned int iters);
/* The second derivative of f at u (f_u = f(u)) by central differences of step h: a least-squares
   cost's curvature, whose inverse gives the searched parameter's standard error. */
double imest__cm_curvature(double (*f)(void *, double), void *ctx, double u, double f_u, double h);

#endif /* IMEST_COMMISSION_FIT_H */
