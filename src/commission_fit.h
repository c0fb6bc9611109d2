/* Background helpers shared by the commissioning fits (float64). Internal. */
#ifndef IMEST_COMMISSION_FIT_H
#define IMEST_COMMISSION_FIT_H

#include "commission_internal.h"

/* Mean of exp(-(k - k_ref) ts / tau) over the samples k0 .. k0 + n - 1. */
double cm_block_exp(uint32_t k0, uint32_t n, uint32_t k_ref, double ts, double tau);

/* Minimum of f on [lo, hi] by golden-section search (a fixed number of iterations). */
double cm_golden(double (*f)(void *, double), void *ctx, double lo, double hi, unsigned int iters);

#endif /* IMEST_COMMISSION_FIT_H */
