/* SPDX-License-Identifier: Apache-2.0 */
/* Random numbers for the sensor noise: xoshiro256** seeded by splitmix64, Gaussian by the
 * polar method. Reproducible for a given seed. */
#include "imsim_internal.h"

static uint64_t splitmix64(uint64_t *x)
{
  uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
static inline uint64_t rotl(uint64_t x, int k)
{
  return (x << k) | (x >> (64 - k));
}
static uint64_t rng_next(uint64_t s[4])
{
  const uint64_t result = rotl(s[1] * 5, 7) * 9;
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return result;
}
static double rng_uniform(uint64_t s[4])
{ /* (-1, 1) */
  return (double)(rng_next(s) >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

/* Seeds r from the splitmix64 sequence at *sm (which advances), so that successive calls
   give independent streams from one seed. */
void ims_rng_seed(imsim_rng_t *r, uint64_t *sm)
{
  for (int k = 0; k < 4; ++k) r->s[k] = splitmix64(sm);
  r->has_spare = false;
  r->spare = 0.0;
}

double ims_rng_gauss(imsim_rng_t *r)
{
  if (r->has_spare) {
    r->has_spare = false;
    return r->spare;
  }
  double u, v, q;
  do {
    u = rng_uniform(r->s);
    v = rng_uniform(r->s);
    q = u * u + v * v;
  } while (q >= 1.0 || q == 0.0);
  const double f = sqrt(-2.0 * log(q) / q);
  r->spare = v * f;
  r->has_spare = true;
  return u * f;
}
