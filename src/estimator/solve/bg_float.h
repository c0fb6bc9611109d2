/* SPDX-License-Identifier: Apache-2.0 */
/* Exact power-of-two and IEEE-754 helpers of the background path (no libm:
 * ldexp/frexp/isfinite cost ~70 instructions per call on a soft-double core).
 * Internal: not part of the public API. */
#ifndef IMEST_BG_FLOAT_H
#define IMEST_BG_FLOAT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Helpers called from several places are kept out of line: at -O2 GCC
 * inlines them into every caller, which costs flash (the ISR flags must stay
 * -O2, so the background code says it here). */
#if defined(__GNUC__)
#define BG_NOINLINE __attribute__((noinline))
#else
#define BG_NOINLINE
#endif

double imest__bg_pow2(int e);   /* 2^e, e clamped to [-1022, 1023] */
int imest__bg_finite(double x); /* isfinite by the exponent bits */
/* round(log2(x)) for finite x > 0, exact (mantissa compared with sqrt 2). */
int imest__bg_round_log2(double x);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_FLOAT_H */
