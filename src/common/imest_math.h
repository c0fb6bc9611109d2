/* SPDX-License-Identifier: Apache-2.0 */
/* The library's one math header: its constants (each number written once),
 * the arithmetic type of the per-sample paths and the helpers they share
 * (absolute value, square root, the 3-2 transform, rotation, angle wrapping) without
 * libm. imest_real_t is float (float64 only in the host-side reference build,
 * IMEST_REAL_DOUBLE, src/CMakeLists.txt). Literals go through RL() so the
 * float build never promotes to double (-Wdouble-promotion). Internal: not
 * part of the public API. */
#ifndef IMEST_COMMON_MATH_H
#define IMEST_COMMON_MATH_H

#include "imest/imest.h"

/* The numbers, as exact decimal literals: use them through the typed forms. */
#define IMEST_PI_LIT         3.14159265358979323846
#define IMEST_2PI_LIT        6.28318530717958647692
#define IMEST_INV_2PI_LIT    0.15915494309189533577 /* 1 / (2 pi) */
#define IMEST_2_OVER_PI_LIT  0.63661977236758134308 /* 2 / pi */
#define IMEST_SQRT2_3_LIT    0.81649658092772603273 /* sqrt(2/3): power-invariant 3-2 transform */
#define IMEST_SQRT1_2_LIT    0.70710678118654752440 /* sqrt(2/3) sqrt(3)/2 */
#define IMEST_SQRT3_2_LIT    1.22474487139158904910 /* sqrt(3/2) */
#define IMEST_HALF_SQRT3_LIT 0.86602540378443864676 /* sqrt(3)/2 */
#define IMEST_SQRT2_LIT      1.41421356237309504880
#define IMEST_ONE_THIRD_LIT  0.33333333333333333333
#define IMEST_ONE_SIXTH_LIT  0.16666666666666666667

/* A window's speed is steady when its mean is within this share of the
 * previous window's, plus this many rad/s: the angle observer (ISR) and the
 * noise model (background) are models of steady operation. */
#define IMEST_STEADY_REL_LIT       0.02
#define IMEST_STEADY_ABS_RAD_S_LIT 1.0

#define RL(x)              ((imest_real_t)(x))
#define IMEST_PI_R         RL(IMEST_PI_LIT)
#define IMEST_2PI_R        RL(IMEST_2PI_LIT)
#define IMEST_PI_F         ((float)IMEST_PI_LIT)
#define IMEST_2PI_F        ((float)IMEST_2PI_LIT)
#define IMEST_PI_D         IMEST_PI_LIT
#define IMEST_SQRT2_D      IMEST_SQRT2_LIT
#define IMEST_SQRT2_3_F    ((float)IMEST_SQRT2_3_LIT)
#define IMEST_SQRT3_2_F    ((float)IMEST_SQRT3_2_LIT)
#define IMEST_HALF_SQRT3_F ((float)IMEST_HALF_SQRT3_LIT)

/* Compiler barrier for the ISR/background hand-off. Override on multi-core or
 * cached systems with a real memory barrier (e.g. -DIMEST_BARRIER=__DMB()). */
#ifndef IMEST_BARRIER
#if defined(__GNUC__) || defined(__clang__)
#define IMEST_BARRIER() __asm__ volatile("" ::: "memory")
#else
#define IMEST_BARRIER()                                                                                      \
  do {                                                                                                       \
  } while (0)
#endif
#endif

/* Absolute value without libm (the ISR calls no library function). GCC and
 * Clang expand the builtin to one instruction (VABS.F32 on Cortex-M4F: the
 * comparison form costs four, six times per sample). */
#if defined(__GNUC__) || defined(__clang__)
/* the float64 reference build defines IMEST_REAL_DOUBLE (src/CMakeLists.txt) */
#ifdef IMEST_REAL_DOUBLE
static inline imest_real_t imest__abs(imest_real_t x)
{
  return __builtin_fabs(x);
}
#else
static inline imest_real_t imest__abs(imest_real_t x)
{
  return __builtin_fabsf(x);
}
#endif
#else
static inline imest_real_t imest__abs(imest_real_t x)
{
  return x < RL(0) ? -x : x;
}
#endif

/* Square root as one instruction (VSQRT.F32 on Cortex-M4F/M7), whatever the
 * flags: the ISR calls no library function. With -fno-math-errno (what
 * src/CMakeLists.txt gives the per-sample folders; GCC and Clang then define
 * __NO_MATH_ERRNO__) the builtin is that one instruction. Without it (an IDE
 * project, docs/integrating.md) GCC and Clang expand the builtin to VSQRT, a
 * compare and a call to sqrtf for a negative or NaN argument (to set errno),
 * so on 32-bit ARM with a single-precision FPU (__ARM_FP bit 2) the
 * instruction is written out: the same VSQRT.F32, IEEE-754 correctly rounded
 * as sqrtf, the default NaN for a negative argument as the builtin's
 * instruction gives. The builtin is kept where the flag is given (the
 * compiler schedules it, the code the firmware budgets measure) and off ARM
 * (the host build). */
#if defined(__GNUC__) || defined(__clang__)
#ifdef IMEST_REAL_DOUBLE
static inline imest_real_t imest__sqrt(imest_real_t x)
{
  return __builtin_sqrt(x);
}
#elif defined(__arm__) && defined(__ARM_FP) && (__ARM_FP & 4) && !defined(__NO_MATH_ERRNO__)
static inline imest_real_t imest__sqrt(imest_real_t x)
{
  imest_real_t r;
  __asm__("vsqrt.f32 %0, %1" : "=t"(r) : "t"(x)); /* "t": a single-precision VFP register */
  return r;
}
#else
static inline imest_real_t imest__sqrt(imest_real_t x)
{
  return __builtin_sqrtf(x);
}
#endif
#else
#include <math.h>
static inline imest_real_t imest__sqrt(imest_real_t x)
{
  return (imest_real_t)sqrtf((float)x);
}
#endif

/* 1 if |x| <= lim (false for NaN and +-Inf). */
static inline int imest__within(imest_real_t x, imest_real_t lim)
{
  return imest__abs(x) <= lim; /* NaN compares false */
}

/* Power-invariant 3-2 transform: amplitude of alpha/beta = line-to-line rms. */
static inline void imest__clarke(const imest_real_t x[3], imest_real_t *xa, imest_real_t *xb)
{
  const imest_real_t k_a = RL(IMEST_SQRT2_3_LIT);
  const imest_real_t k_b = RL(IMEST_SQRT1_2_LIT);
  *xa = k_a * (x[0] - RL(0.5) * (x[1] + x[2]));
  *xb = k_b * (x[1] - x[2]);
}

/* Rotation by the angle phi (s = sin phi, c = cos phi) into the frame turned by phi
 * (docs/METHOD.md eq. 2, into the rotor frame): x = c*a + s*b, y = -s*a + c*b.
 * With -s it turns the other way (a phasor advanced by phi). */
static inline void imest__rotate(imest_real_t s, imest_real_t c, imest_real_t a, imest_real_t b,
                                 imest_real_t *x, imest_real_t *y)
{
  *x = c * a + s * b;
  *y = c * b - s * a;
}

/* x - 2*pi*round(x / 2*pi): wraps into [-pi, pi]. |x| must be < 2^31 * 2pi
 * (guaranteed by the input plausibility check). */
static inline imest_real_t imest__wrap_pi(imest_real_t x)
{
  const imest_real_t q = x * RL(IMEST_INV_2PI_LIT);
  const int32_t k = (int32_t)(q + (q >= RL(0) ? RL(0.5) : RL(-0.5)));
  return x - (imest_real_t)k * IMEST_2PI_R;
}

/* Clear n values. Through a volatile pointer: a plain loop of zero stores is
 * what compilers turn into a call of memset (GCC's loop-distribution at -O2,
 * clang's loop-idiom pass, whatever the flags), and the ISR path calls no
 * library function. The stores are the loop's own: one per value. */
static inline void imest__zero_real(imest_real_t *p, uint32_t n)
{
  imest_real_t volatile *const v = p;
  for (uint32_t k = 0u; k < n; ++k) v[k] = RL(0);
}
static inline void imest__zero_f32(float *p, uint32_t n)
{
  float volatile *const v = p;
  for (uint32_t k = 0u; k < n; ++k) v[k] = 0.0f;
}

#endif /* IMEST_COMMON_MATH_H */
