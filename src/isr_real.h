/* Arithmetic of the ISR path: imest_real_t is float (float64 only in the
 * host-side reference build, src/CMakeLists.txt). Literals go through RL() so the
 * float build never promotes to double (-Wdouble-promotion). */
#ifndef IMEST_ISR_REAL_H
#define IMEST_ISR_REAL_H

#include "imest/imest.h"

#define RL(x)       ((imest_real_t)(x))
#define IMEST_PI_R  RL(3.14159265358979323846)
#define IMEST_2PI_R RL(6.28318530717958647692)

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
/* the float64 reference build's copy of imest.h (src/CMakeLists.txt) defines
 * IMEST_REF64_REAL_DOUBLE; the public header does not */
#ifdef IMEST_REF64_REAL_DOUBLE
static inline imest_real_t isr_abs(imest_real_t x)
{
  return __builtin_fabs(x);
}
#else
static inline imest_real_t isr_abs(imest_real_t x)
{
  return __builtin_fabsf(x);
}
#endif
#else
static inline imest_real_t isr_abs(imest_real_t x)
{
  return x < RL(0) ? -x : x;
}
#endif

/* Square root as one instruction (VSQRT.F32): the ISR file is compiled with
 * -fno-math-errno (src/CMakeLists.txt), so GCC and Clang expand the builtin
 * inline instead of calling sqrtf for a negative argument. */
#if defined(__GNUC__) || defined(__clang__)
#ifdef IMEST_REF64_REAL_DOUBLE
static inline imest_real_t isr_sqrt(imest_real_t x)
{
  return __builtin_sqrt(x);
}
#else
static inline imest_real_t isr_sqrt(imest_real_t x)
{
  return __builtin_sqrtf(x);
}
#endif
#else
#include <math.h>
static inline imest_real_t isr_sqrt(imest_real_t x)
{
  return (imest_real_t)sqrtf((float)x);
}
#endif

/* 1 if |x| <= lim (false for NaN and +-Inf). */
static inline int isr_within(imest_real_t x, imest_real_t lim)
{
  return isr_abs(x) <= lim; /* NaN compares false */
}

#endif
