/* ISR stage 1: 3-2 transform and rotation into the rotor frame (docs/METHOD.md §1). */
#ifndef IMEST_ISR_TRANSFORM_H
#define IMEST_ISR_TRANSFORM_H

#include "isr_real.h"

/* Power-invariant 3-2 transform: amplitude of alpha/beta = line-to-line rms. */
static inline void isr_clarke(const imest_real_t x[3], imest_real_t *xa, imest_real_t *xb)
{
  const imest_real_t k_a = RL(0.81649658092772603273); /* sqrt(2/3) */
  const imest_real_t k_b = RL(0.70710678118654752440); /* sqrt(2/3)*sqrt(3)/2 */
  *xa = k_a * (x[0] - RL(0.5) * (x[1] + x[2]));
  *xb = k_b * (x[1] - x[2]);
}

/* x - 2*pi*round(x / 2*pi): wraps into [-pi, pi]. |x| must be < 2^31 * 2pi
 * (guaranteed by the input plausibility check). */
static inline imest_real_t isr_wrap_pi(imest_real_t x)
{
  const imest_real_t q = x * RL(0.15915494309189533577);
  const int32_t k = (int32_t)(q + (q >= RL(0) ? RL(0.5) : RL(-0.5)));
  return x - (imest_real_t)k * IMEST_2PI_R;
}

/* sin and cos by quadrant reduction to [-pi/4, pi/4] and least-maximum-error
 * polynomials of degree 5 and 6 (|error| < 1e-6, float32 rounding included:
 * an angle error far below any encoder's resolution): fixed cost, no libm, no
 * table. */
static inline void isr_sincos(imest_real_t x, imest_real_t *s_out, imest_real_t *c_out)
{
  const imest_real_t q = x * RL(0.63661977236758134308); /* 2/pi */
  const int32_t k = (int32_t)(q + (q >= RL(0) ? RL(0.5) : RL(-0.5)));
  /* two-step Cody-Waite reduction keeps r accurate for |x| up to a few 100 rad */
  const imest_real_t r = (x - (imest_real_t)k * RL(1.5703125)) - (imest_real_t)k * RL(4.83826794896619231e-4);
  const imest_real_t r2 = r * r;
  const imest_real_t sp = r * (RL(1) + r2 * (RL(-0.16662837) + r2 * RL(0.00815306)));
  const imest_real_t cp = RL(1) + r2 * (RL(-0.49999895) + r2 * (RL(0.0416563) + r2 * RL(-0.00135979)));
  const uint32_t quad = (uint32_t)k & 3u;
  const imest_real_t s0 = (quad & 1u) ? cp : sp;
  const imest_real_t c0 = (quad & 1u) ? sp : cp;
  *s_out = (quad & 2u) ? -s0 : s0;
  *c_out = ((quad + 1u) & 2u) ? -c0 : c0;
}

/* Rotation by the electrical angle phi (eq. 2): x = c*a + s*b, y = -s*a + c*b. */
static inline void isr_rotate(imest_real_t s, imest_real_t c, imest_real_t a, imest_real_t b, imest_real_t *x,
                              imest_real_t *y)
{
  *x = c * a + s * b;
  *y = c * b - s * a;
}

#endif
