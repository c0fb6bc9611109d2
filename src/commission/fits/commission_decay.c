/* SPDX-License-Identifier: Apache-2.0 */
/* Exponential decay sampled at the ISR rate, for the background fits: powers of
 * q = exp(-T / tau) by binary exponentiation with a small memo. The fits evaluate the same few
 * block lengths and spacings many times per tau; exp() in soft double (Cortex-M4) costs a few
 * thousand instructions, a multiplication under a hundred. Relative error of q^n: about
 * n eps(double), 1e-10 for a million samples. And exp itself (imest__cm_exp), the fits' only
 * transcendental function: libm's is 1.1 KB of flash on a Cortex-M4F that nothing else in the
 * library links. float64, bounded loops. */
#include "commission_fit.h"

/* ln 2 in two parts (Cody-Waite): the high one has 32 significant bits, so k ln2_hi is exact
   for |k| < 2^20 and r = x - k ln 2 keeps its precision. */
#define CM_LN2_HI_LIT 6.93147180369123816490e-01
#define CM_LN2_LO_LIT 1.90821492927058770002e-10
#define CM_LOG2E_LIT  1.44269504088896338700e+00
/* terms of the series of e^r, |r| <= ln2 / 2: the next one, r^14 / 14!, is 1.2e-18 */
#define CM_EXP_TERMS  13

double imest__cm_exp(double x)
{
  if (!(x > -700.0)) return x < 0.0 ? 0.0 : x; /* e^-700 = 1e-304; NaN stays NaN */
  if (x > 700.0) x = 700.0;                    /* 1e304: far beyond any value the fits take */
  const double kd = x * CM_LOG2E_LIT;
  const int k = (int)(kd + (kd >= 0.0 ? 0.5 : -0.5)); /* |k| <= 1010: an int even where it is 16 bits */
  const double r = (x - (double)k * CM_LN2_HI_LIT) - (double)k * CM_LN2_LO_LIT;
  /* e^r = 1 + r (1 + r/2 (1 + r/3 (...))) */
  double p = 1.0, n = (double)CM_EXP_TERMS;
  for (int j = 0; j < CM_EXP_TERMS; ++j) {
    p = 1.0 + p * r / n;
    n -= 1.0;
  }
  /* times 2^k, exact (|k| <= 1010 keeps p 2^k normal): as the estimator scales, by the exponent
     where double is soft, by a multiplication where the FPU has double */
  return BG_SCALE2(p, k, imest__bg_pow2(k));
}

void imest__cm_decay_init(cm_decay_t *d, double ts, double tau)
{
  const double x = ts / tau;
  d->q = imest__cm_exp(-x);
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
