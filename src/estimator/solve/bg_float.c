/* SPDX-License-Identifier: Apache-2.0 */
/* Exact power-of-two and IEEE-754 helpers of the background path: bit
 * operations on the binary64 representation, no libm (ldexp, frexp and
 * isfinite cost ~70 instructions per call on a soft-double core, a bit test a
 * few). */
#include <stdint.h>

#include "bg_float.h"
#include "common/imest_math.h" /* imest__sqrt: VSQRT.F32, no library call */

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

double imest__bg_scale2(double x, int e)
{
  bits64_t b;
  b.d = x;
  const int ex = (int)((b.u >> 52) & 0x7FFu), r = ex + e;
  if (ex != 0 && ex != 0x7FF && r > 0 && r < 0x7FF && e >= -1022 && e <= 1023) {
    b.u += (uint64_t)(int64_t)e << 52; /* the exponent field stays in range: the sign is kept */
    return b.d;
  }
  return x * imest__bg_pow2(e); /* zero, subnormal, non-finite, or a result out of the normal range */
}

int imest__bg_finite(double x)
{
  bits64_t b;
  b.d = x;
  return ((unsigned int)(b.u >> 52) & 0x7FFu) != 0x7FFu;
}

#if BG_SOFT_DOUBLE
double imest__bg_fmax(double x, double y)
{
  bits64_t a, b;
  a.d = x;
  b.d = y;
  /* a NaN by the bits: a soft-double comparison costs ~20 instructions */
  if ((a.u << 1) > 0xFFE0000000000000ull) return y;
  if ((b.u << 1) > 0xFFE0000000000000ull) return x;
  return x > y ? x : y;
}

float imest__bg_fmaxf(float x, float y)
{
  if (x != x) return y;
  if (y != y) return x;
  return x > y ? x : y;
}

float imest__bg_fminf(float x, float y)
{
  if (x != x) return y;
  if (y != y) return x;
  return x < y ? x : y;
}
#endif

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

#if BG_SOFT_DOUBLE
/* x = m 2^(e - 52), e even, m in [2^52, 2^54): sqrt(x) = y 2^(e/2 - 52) with
 * y = round(sqrt(m 2^52)) in [2^52, 2^53]. s0 = sqrtf(m 2^-52) is within
 * 2^-23.4 relative; one Newton step from y0 = s0 2^52, its correction
 * formed in float32, leaves |y - sqrt(m 2^52)| < 2^8, so the residual
 * m 2^52 - y^2 (< 2^62) is exact in int64 modulo 2^64; a second step leaves
 * |y - sqrt| < 1.01, and at most two unit steps make y the floor (0 <= r <=
 * 2y); y rounds up iff r > y (a tie cannot occur). */
double imest__bg_sqrt(double x)
{
  bits64_t b;
  b.d = x;
  int ex = (int)((b.u >> 52) & 0x7FFu), off = 0;
  if ((b.u >> 63) != 0u || ex == 0x7FF || ex == 0) {
    if ((b.u << 1) == 0u || (ex == 0x7FF && (b.u >> 63) == 0u) || (ex == 0x7FF && (b.u << 12) != 0u))
      return x; /* +-0, +inf, NaN */
    if ((b.u >> 63) != 0u) {
      b.u = 0x7FF8000000000000ull; /* x < 0: the default NaN */
      return b.d;
    }
    b.d = x * 18014398509481984.0; /* subnormal: 2^54 x is normal */
    ex = (int)((b.u >> 52) & 0x7FFu);
    off = 54;
  }
  uint64_t m = (b.u & 0xFFFFFFFFFFFFFull) | 0x10000000000000ull;
  int e = ex - 1023 - off;
  if (((unsigned int)e & 1u) != 0u) {
    m <<= 1;
    e -= 1;
  }
  const uint64_t mlo = m << 52; /* m 2^52 modulo 2^64 */
  const float s0 =
      (float)imest__sqrt((imest_real_t)((float)(uint32_t)(m >> 22) * 9.31322574615478515625e-10f));
  const uint32_t y0 = (uint32_t)(s0 * 8388608.0f); /* s0 2^23: an integer (24 bits) */
  const int64_t d = (int64_t)(m - ((uint64_t)y0 * y0 << 6));
  const float step1 = (float)(int32_t)(d / 4) * (16777216.0f / (float)y0); /* (m 2^52 - y0^2) / 2 y0 */
  uint64_t y = ((uint64_t)y0 << 29) + (uint64_t)(int64_t)(int32_t)step1;
  const int64_t r1 = (int64_t)(mlo - y * y);
  const float step2 = (float)(int32_t)(r1 / 4294967296LL) * 512.0f / (float)(uint32_t)(y >> 22);
  y += (uint64_t)(int64_t)(int32_t)step2;
  int64_t r = (int64_t)(mlo - y * y);
  for (int i = 0; i < 3; ++i) {
    if (r < 0) {
      r += (int64_t)(2u * y) - 1;
      --y;
    } else if (r > (int64_t)(2u * y)) {
      r -= (int64_t)(2u * y) + 1;
      ++y;
    }
  }
  if (r > (int64_t)y) ++y; /* y = 2^53 carries into the exponent */
  b.u = ((uint64_t)(int64_t)(e / 2 + 1022) << 52) + y;
  return b.d;
}
#endif

#if BG_SOFT_DOUBLE
/* x = mx 2^(ex-52), y = my 2^(ey-52), mx, my in [2^52, 2^53); with mx < my
 * doubled, x / y = (mx / my) 2^e with mx / my in [1, 2), so the result's
 * mantissa is q = round(mx 2^52 / my) in [2^52, 2^53]. q is built in three
 * chunks of 20, 22 and 10 bits, each estimated in float32 from the exact
 * remainder rem = mx 2^n - Q my: |rem / my| <= 3 after each chunk (the
 * float32 quotient is within 2^-22 relative, plus one for the truncation),
 * so rem stays below 2^55 and is exact in int64 modulo 2^64, and the
 * chunks fit int32. Then at most two unit steps make 0 <= rem < my (Q the
 * floor), and Q rounds up iff 2 rem > my (no tie: mx 2^53 / my would be an
 * odd integer, but my < 2^53 leaves a factor 2 in it). Zero, subnormal or
 * non-finite operands and results outside the normal range: the library's
 * division. */
static int64_t div_chunk(int64_t rem, float rinv, float scale)
{
  return (int64_t)(int32_t)((float)(int32_t)(rem / 16777216) * rinv * scale); /* rem / 2^24 < 2^31 */
}

BG_CORE_PCS double imest__bg_div(double x, double y)
{
  bits64_t a, b;
  a.d = x;
  b.d = y;
  const int ea = (int)((a.u >> 52) & 0x7FFu), eb = (int)((b.u >> 52) & 0x7FFu);
  uint64_t mx = (a.u & 0xFFFFFFFFFFFFFull) | 0x10000000000000ull;
  const uint64_t my = (b.u & 0xFFFFFFFFFFFFFull) | 0x10000000000000ull;
  int e = ea - eb + 1023;
  if (mx < my) {
    mx <<= 1;
    --e;
  }
  if (ea == 0 || ea == 0x7FF || eb == 0 || eb == 0x7FF || e < 1 || e > 2046) return x / y;
  const float rinv = 1.0f / (float)(uint32_t)(my >> 21); /* 2^21 / my, within 2^-23 */
  /* q1 = mx 2^20 / my: (mx / 2^22) (2^21 / my) 2^21 */
  uint64_t q = (uint64_t)(uint32_t)((float)(uint32_t)(mx >> 22) * rinv * 2097152.0f);
  int64_t rem = (int64_t)((mx << 20) - q * my);
  /* next chunk: rem 2^22 / my = (rem / 2^24) (2^21 / my) 2^25 */
  int64_t c = div_chunk(rem, rinv, 33554432.0f);
  q = (q << 22) + (uint64_t)c;
  rem = (int64_t)(((uint64_t)rem << 22) - (uint64_t)c * my);
  c = div_chunk(rem, rinv, 8192.0f); /* rem 2^10 / my = (rem / 2^24) (2^21 / my) 2^13 */
  q = (q << 10) + (uint64_t)c;
  rem = (int64_t)(((uint64_t)rem << 10) - (uint64_t)c * my);
  for (int i = 0; i < 3; ++i) {
    if (rem < 0) {
      rem += (int64_t)my;
      --q;
    } else if (rem >= (int64_t)my) {
      rem -= (int64_t)my;
      ++q;
    }
  }
  if ((uint64_t)rem > my - (uint64_t)rem) ++q; /* q = 2^53 carries into the exponent */
  b.u = ((a.u ^ b.u) & 0x8000000000000000ull) + ((uint64_t)(e - 1) << 52) + q;
  return b.d;
}

#include "bg_ff.h"

/* s + e = a + b exactly (Knuth's two_sum: no condition on the magnitudes) */
static bg_ff_t two_sum(float a, float b)
{
  bg_ff_t r;
  r.hi = a + b;
  const float bb = r.hi - a;
  r.lo = (a - (r.hi - bb)) + (b - bb);
  return r;
}

bg_ff_t imest__bg_ff_madd(bg_ff_t c, bg_ff_t a, bg_ff_t b)
{
  const float p = a.hi * b.hi;
  const float pl = BG_FMAF(a.hi, b.lo, BG_FMAF(a.lo, b.hi, BG_FMAF(a.hi, b.hi, -p)));
  bg_ff_t s = two_sum(c.hi, p);
  s.lo += c.lo + pl;
  return two_sum(s.hi, s.lo);
}

/* x = m 2^(e-52), m < 2^53: hi = the top 24 bits of m, exact; lo = the other
 * 29, rounded once to float32 (error <= 2^4 of 2^(e-52) <= 2^-48 |x|). By
 * the bits: a soft-double subtraction would cost ~90 instructions a value.
 * For -32 <= e < 32 both scales, 2^(e-23) and 2^(e-52), are normal. */
int imest__bg_ff_of(const double *v, int n, bg_ff_t *f)
{
  for (int i = 0; i < n; ++i) {
    bits64_t b;
    b.d = v[i];
    const int ex = (int)((b.u >> 52) & 0x7FFu);
    f[i].hi = f[i].lo = 0.0f;
    if ((b.u << 1) == 0u) continue; /* +-0 */
    if (ex < 1023 - 32 || ex > 1023 + 31) return 0;
    const uint64_t m = (b.u & 0xFFFFFFFFFFFFFull) | 0x10000000000000ull;
    union {
      float f;
      uint32_t u;
    } sh, sl;
    sh.u = (uint32_t)(ex - 1023 - 23 + 127) << 23;
    sl.u = (uint32_t)(ex - 1023 - 52 + 127) << 23;
    const float sg = ((b.u >> 63) != 0u) ? -1.0f : 1.0f;
    f[i].hi = sg * ((float)(uint32_t)(m >> 29) * sh.f);
    f[i].lo = sg * ((float)(uint32_t)(m & 0x1FFFFFFFu) * sl.f);
  }
  return 1;
}
#endif
