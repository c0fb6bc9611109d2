/* SPDX-License-Identifier: Apache-2.0 */
/* Background helpers shared by the commissioning fits (float64). Internal. */
#ifndef IMEST_COMMISSION_FIT_H
#define IMEST_COMMISSION_FIT_H

#include "commission_internal.h"

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

/* Minimum of f on [lo, hi] by golden-section search (a fixed number of iterations). */
double imest__cm_golden(double (*f)(void *, double), void *ctx, double lo, double hi, unsigned int iters);

#endif /* IMEST_COMMISSION_FIT_H */
