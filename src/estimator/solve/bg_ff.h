/* SPDX-License-Identifier: Apache-2.0 */
/* Float-float ("double-single") arithmetic for the hottest float64 kernels of
 * the background solve where double is soft (BG_SOFT_DOUBLE): a value is
 * hi + lo, two float32s, |lo| <= ~2^-23 |hi|, 48 significant bits. With the
 * FPU's fused multiply-add (VFMA.F32 on fpv4-sp-d16) a product is ~4 and a
 * sum ~14 float32 instructions, against ~48 and ~60 for libgcc's soft double.
 * Bounds (u = 2^-24; docs/METHOD.md §10.4):
 *  - imest__bg_ff_of: relative error <= 2^-48 (the top 24 bits exact, the
 *    other 29 rounded once to 24);
 *  - imest__bg_ff_madd, c + a b: the high parts' product exact (p +
 *    fmaf(a, b, -p)), the cross terms rounded once each, lo*lo dropped (error
 *    <= 4 u^2 |a b|); the sum's high parts exact (two_sum), its low parts
 *    rounded twice, renormalised exactly (error <= 3 u^2 (|c| + |a b|)).
 * So a sum of n products is within ~(3n + 4) u^2 sum |terms| of exact, where
 * float64's bound is n 2^-53 sum |terms|: about 30 times looser, still 1e-13
 * relative to the terms. Float32's exponent range: the callers test that
 * every operand and result stays normal (imest__bg_ff_of), and take the
 * float64 code otherwise. Exact two_sum needs round-to-nearest float32
 * without excess precision (every target: VFP, SSE); FMA contraction cannot
 * touch it (no products). Internal: not part of the public API. */
#ifndef IMEST_BG_FF_H
#define IMEST_BG_FF_H

#include "bg_float.h"

#if BG_SOFT_DOUBLE

#if defined(__GNUC__) || defined(__clang__)
#define BG_FMAF(a, b, c) __builtin_fmaf((a), (b), (c)) /* one VFMA.F32 on a Cortex-M4F */
#else
#include <math.h>
#define BG_FMAF(a, b, c) fmaf((a), (b), (c))
#endif

typedef struct {
  float hi, lo;
} bg_ff_t;

/* c + a b, bg_ff_t's one operation (out of line: one copy of ~30 instructions) */
bg_ff_t imest__bg_ff_madd(bg_ff_t c, bg_ff_t a, bg_ff_t b);

static inline double bg_ff_to_d(bg_ff_t a) /* rounded once */
{
  return (double)a.hi + (double)a.lo;
}

/* f[i] = v[i] as hi + lo; 1 if every v[i] is zero or within
 * 2^-32 <= |v[i]| < 2^32, else 0 (f then partly set) */
int imest__bg_ff_of(const double *v, int n, bg_ff_t *f);

#endif /* BG_SOFT_DOUBLE */

#endif /* IMEST_BG_FF_H */
