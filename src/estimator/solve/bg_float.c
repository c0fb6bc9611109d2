/* SPDX-License-Identifier: Apache-2.0 */
/* Exact power-of-two and IEEE-754 helpers of the background path: bit
 * operations on the binary64 representation, no libm (ldexp, frexp and
 * isfinite cost ~70 instructions per call on a soft-double core, a bit test a
 * few). */
#include <stdint.h>

#include "bg_float.h"

typedef union {
  double d;
  uint64_t u;
} bits64_t;

double imest__bg_pow2(int e)
{
  if (e < -1022) e = -1022;
  if (e > 1023) e = 1023;
  bits64_t b;
  b.u = (uint64_t)(e + 1023) << 52;
  return b.d;
}

int imest__bg_finite(double x)
{
  bits64_t b;
  b.d = x;
  return ((unsigned int)(b.u >> 52) & 0x7FFu) != 0x7FFu;
}

int imest__bg_round_log2(double x)
{
  bits64_t b;
  int off = 0;
  b.d = x;
  if (((b.u >> 52) & 0x7FFu) == 0u) { /* subnormal: make it normal */
    b.d = x * 18446744073709551616.0; /* 2^64 */
    off = 64;
  }
  const int ex = (int)((b.u >> 52) & 0x7FFu) - 1023;
  /* log2 x = ex + log2(1.f): round up iff 1.f >= sqrt 2 (mantissa of sqrt 2) */
  return ex - off + (((b.u & 0xFFFFFFFFFFFFFull) >= 0x6A09E667F3BCDull) ? 1 : 0);
}
