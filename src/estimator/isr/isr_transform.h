/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage 1: rotation into the rotor frame (docs/METHOD.md §1); the 3-2
 * transform and the rotation itself are common/imest_math.h's imest__clarke()
 * and imest__rotate(). */
#ifndef IMEST_ISR_TRANSFORM_H
#define IMEST_ISR_TRANSFORM_H

#include "common/imest_math.h"

/* sin and cos by quadrant reduction to [-pi/4, pi/4] and least-maximum-error
 * polynomials of degree 5 and 6 (|error| < 1e-6, float32 rounding included:
 * an angle error far below any encoder's resolution): fixed cost, no libm, no
 * table. */
static inline void isr_sincos(imest_real_t x, imest_real_t *s_out, imest_real_t *c_out)
{
  const imest_real_t q = x * RL(IMEST_2_OVER_PI_LIT);
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

#endif
