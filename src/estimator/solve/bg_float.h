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
#define BG_CONST    __attribute__((const)) /* a result that is not used needs no call */
#else
#define BG_NOINLINE
#define BG_CONST
#endif

BG_CONST double imest__bg_pow2(int e); /* 2^e, e clamped to [-1022, 1023] */
/* x * imest__bg_pow2(e), bit for bit, by an exponent addition where x and the
 * result are normal (a soft-double multiplication costs ~45 instructions). */
double imest__bg_scale2(double x, int e);
/* BG_SOFT_DOUBLE: 0 where the FPU has double (Cortex-M7 fpv5-d16), whose one
 * instruction per operation the integer and float32 shortcuts below would
 * only slow down; 1 elsewhere, the host included, so that the tests run the
 * code of a single-precision FPU. */
#if defined(__ARM_FP) && ((__ARM_FP)&8)
#define BG_SOFT_DOUBLE 0
#else
#define BG_SOFT_DOUBLE 1
#endif

/* x * p2, where p2 = imest__bg_pow2(e): by the exponent where double is soft
 * (p2 is then not evaluated), by the multiplication where the FPU has double. */
#if !BG_SOFT_DOUBLE
#define BG_SCALE2(x, e, p2) ((x) * (p2))
#else
#define BG_SCALE2(x, e, p2) ((void)(p2), imest__bg_scale2((x), (e)))
#endif
int imest__bg_finite(double x); /* isfinite by the exponent bits */
/* sqrt(x), correctly rounded like IEEE-754 sqrt (bit for bit; a NaN for x < 0):
 * a float32 seed and two corrections in integers, ~100 instructions where
 * libm's bit-by-bit soft-double sqrt takes ~800. Where the FPU has double,
 * its one instruction. */
#if !BG_SOFT_DOUBLE
#define BG_SQRT(x) sqrt(x)
#else
double imest__bg_sqrt(double x);
#define BG_SQRT(x) imest__bg_sqrt(x)
#endif
/* x / y, correctly rounded like IEEE-754 division (bit for bit): three
 * float32 quotient chunks and an exact remainder in integers, ~130
 * instructions where libgcc's soft-double division takes ~560. Where the FPU
 * has double, its one instruction. */
#if !BG_SOFT_DOUBLE
#define BG_DIV(x, y) ((x) / (y))
#else
/* On a hard-float ABI, the operands in core registers like libgcc's
 * __aeabi_ddiv's: the callers then move nothing to the FPU and back. */
#if defined(__arm__) && defined(__ARM_PCS_VFP) && defined(__GNUC__)
#define BG_CORE_PCS __attribute__((pcs("aapcs")))
#else
#define BG_CORE_PCS
#endif
BG_CORE_PCS double imest__bg_div(double x, double y);
#define BG_DIV(x, y) imest__bg_div((x), (y))
#endif
/* fmax, fmaxf, fminf as C99 and newlib define them: the other operand where
 * one is a NaN, else x > y ? x : y (y where equal, as newlib's and glibc's),
 * bit for bit. Where the FPU has no VMAXNM (Cortex-M4F), libm's call
 * __fpclassify for each operand: with them 334 B of flash. Where it has
 * (Cortex-M7 fpv5-d16), GCC's builtins are one instruction. Background only. */
#if !BG_SOFT_DOUBLE
#define BG_FMAX(x, y)  fmax((x), (y))
#define BG_FMAXF(x, y) fmaxf((x), (y))
#define BG_FMINF(x, y) fminf((x), (y))
#else
double imest__bg_fmax(double x, double y);
float imest__bg_fmaxf(float x, float y);
float imest__bg_fminf(float x, float y);
#define BG_FMAX(x, y)  imest__bg_fmax((x), (y))
#define BG_FMAXF(x, y) imest__bg_fmaxf((x), (y))
#define BG_FMINF(x, y) imest__bg_fminf((x), (y))
#endif
/* round(log2(x)) for finite x > 0, exact (mantissa compared with sqrt 2). */
int imest__bg_round_log2(double x);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_FLOAT_H */
