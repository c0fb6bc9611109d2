/* SPDX-License-Identifier: Apache-2.0 */
/* Exponential decay sampled at the ISR rate, for the background fits: powers of
 * q = exp(-T / tau) by binary exponentiation with a small memo. The fits evaluate the same few
 * block lengths and spacings many times per tau; exp() in soft double (Cortex-M4) costs a few
 * thousand instructions, a multiplication under a hundred. Relative error of q^n: about
 * n eps(double), 1e-10 for a million samples. float64, bounded loops. */
#include <math.h>

#include "commission_fit.h"

void imest__cm_decay_init(cm_decay_t *d, double ts, double tau)
{
  const double x = ts / tau;
  d->q = exp(-x);
  d->one_minus_q = x < 1e-4 ? x * (1.0 - 0.5 * x * (1.0 - x / 3.0)) : 1.0 - d->q;
  d->next = 0u;
  for (unsigned int k = 0; k < CM_DECAY_MEMO; ++k) d->key[k] = 0xFFFFFFFFu;
}

double imest__cm_decay_pow(cm_decay_t *d, uint32_t n)
{
  for (unsigned int k = 0; k < CM_DECAY_MEMO; ++k)
    if (d->key[k] == n) return d->val[k];
  double r = 1.0, b = d->q;
  for (uint32_t e = n; e != 0u; e >>= 1) { /* at most 32 rounds */
    if (e & 1u) r *= b;
    b *= b;
  }
  d->key[d->next] = n;
  d->val[d->next] = r;
  d->next = (d->next + 1u) % CM_DECAY_MEMO;
  return r;
}

double imest__cm_decay_mean(cm_decay_t *d, uint32_t n)
{
  if (n <= 1u) return 1.0;
  return (1.0 - imest__cm_decay_pow(d, n)) / ((double)n * d->one_minus_q);
}
