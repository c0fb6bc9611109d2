/* SPDX-License-Identifier: Apache-2.0 */
// The soft-double shortcuts of bg_float.c against what they replace, bit for
// bit: imest__bg_scale2 against the multiplication by imest__bg_pow2, and
// imest__bg_sqrt against the correctly rounded sqrt, on random bit patterns
// (every exponent, subnormals), numbers next to squares and to the rounding
// midpoints (y + 1/2 ulp)^2, and the special values; imest__bg_div against the
// division, on random bit patterns, quotients next to the rounding midpoints
// and to the ends of the normal range, and the special values; fmax, fmaxf and fminf
// against newlib's rule.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "bg_float.h"

namespace {

uint64_t bits(double x)
{
  uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

double from_bits(uint64_t u)
{
  double x;
  std::memcpy(&x, &u, sizeof x);
  return x;
}

// random doubles: any bit pattern, every exponent with equal weight, subnormals
double random_double(std::mt19937_64 &rng, int kind)
{
  const uint64_t u = rng();
  switch (kind % 3) {
  case 0: return from_bits(u);
  case 1: return from_bits((u & 0x800FFFFFFFFFFFFFull) | ((uint64_t)(1 + rng() % 2046) << 52));
  default: return from_bits(u & 0x800FFFFFFFFFFFFFull); // subnormal
  }
}

#if BG_SOFT_DOUBLE
// zeros, subnormals, the ends of the range, non-finite, next to 1, 2 and 4
const double kSpecial[] = {0.0,
                           -0.0,
                           1.0,
                           2.0,
                           4.0,
                           0.25,
                           -1.0,
                           -0.5e-310,
                           std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::denorm_min(),
                           std::numeric_limits<double>::min(),
                           std::numeric_limits<double>::max(),
                           std::nextafter(4.0, 0.0),
                           std::nextafter(1.0, 2.0)};
#endif

} // namespace

TEST(BgFloat, Scale2IsTheMultiplication)
{
  std::mt19937_64 rng(20261202);
  const double special[] = {0.0,
                            -0.0,
                            1.0,
                            -1.0,
                            std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::denorm_min(),
                            std::numeric_limits<double>::min(),
                            std::numeric_limits<double>::max()};
  long mismatches = 0;
  for (int i = 0; i < 400000; ++i) {
    const double x = (i < 10 * 50) ? special[i % 10] : random_double(rng, i);
    const int e = (i < 10 * 50) ? (i / 10) * 45 - 1100 : (int)(rng() % 2201) - 1100;
    const double want = x * imest__bg_pow2(e), got = imest__bg_scale2(x, e);
    if (std::isnan(want) ? !std::isnan(got) : bits(want) != bits(got)) {
      if (++mismatches <= 5)
        ADD_FAILURE() << std::hexfloat << x << " * 2^" << e << ": " << got << ", want " << want;
    }
  }
  EXPECT_EQ(mismatches, 0);
}

#if BG_SOFT_DOUBLE
TEST(BgFloat, SqrtIsCorrectlyRounded)
{
  std::mt19937_64 rng(7001);
  long mismatches = 0;
  auto check = [&](double x) {
    const double want = std::sqrt(x), got = imest__bg_sqrt(x);
    if (std::isnan(want) ? !std::isnan(got) : bits(want) != bits(got)) {
      if (++mismatches <= 5)
        ADD_FAILURE() << std::hexfloat << "sqrt(" << x << ") = " << got << ", want " << want;
    }
  };
  for (double x : kSpecial) check(x);
  for (int i = 0; i < 600000; ++i) check(random_double(rng, i));
  for (int i = 0; i < 200000; ++i) {
    // next to squares and to rounding midpoints (y + 1/2 ulp)^2: the decisions that need every bit
    const double y = 1.0 + (double)(rng() >> 12) * 0x1p-52;
    const long double mid = ((long double)y + 0x1p-53L) * ((long double)y + 0x1p-53L);
    const double base[2] = {y * y, (double)mid};
    for (double b : base)
      for (int k = -2; k <= 2; ++k)
        check(std::ldexp(from_bits(bits(b) + (uint64_t)(int64_t)k), (int)(rng() % 200) - 100));
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(BgFloat, DivIsCorrectlyRounded)
{
  std::mt19937_64 rng(7002);
  long mismatches = 0;
  auto check = [&](double x, double y) {
    const double want = x / y, got = imest__bg_div(x, y);
    if (std::isnan(want) ? !std::isnan(got) : bits(want) != bits(got)) {
      if (++mismatches <= 5)
        ADD_FAILURE() << std::hexfloat << x << " / " << y << " = " << got << ", want " << want;
    }
  };
  for (double x : kSpecial)
    for (double y : kSpecial) check(x, y);
  for (int i = 0; i < 600000; ++i) check(random_double(rng, i), random_double(rng, i / 3));
  for (int i = 0; i < 200000; ++i) {
    // x = (q + 1/2 ulp +- a few ulp) y: quotients next to the rounding midpoints, where the
    // decision needs the exact remainder; and exponents at the ends of the normal range
    const double y = 1.0 + (double)(rng() >> 12) * 0x1p-52;
    const double q = 1.0 + (double)(rng() >> 12) * 0x1p-52;
    const double x = (double)(((long double)q + 0x1p-53L) * (long double)y);
    for (int k = -2; k <= 2; ++k) {
      const double xk = from_bits(bits(x) + (uint64_t)(int64_t)k);
      check(xk, y);
      const int e = (int)(rng() % 2100) - 1050;
      check(std::ldexp(xk, e / 2), std::ldexp(y, -(e - e / 2)));
    }
  }
  EXPECT_EQ(mismatches, 0);
}
#endif

#if BG_SOFT_DOUBLE
// fmax, fmaxf, fminf of bg_float.c: the other operand where one is a NaN (a NaN only
// where both are), else x > y ? x : y (x < y for the minimum; y where they compare
// equal, as newlib's): bit for bit, on the special values and random bit patterns.
TEST(BgFloat, MaxMinAreNewlibs)
{
  std::mt19937_64 rng(7003);
  long mismatches = 0;
  auto same = [](double a, double b) { return std::isnan(a) ? std::isnan(b) : bits(a) == bits(b); };
  auto check = [&](double x, double y) {
    const double want = std::isnan(x) ? y : std::isnan(y) ? x : (x > y ? x : y);
    const float xf = (float)x, yf = (float)y;
    const float want_max = std::isnan(xf) ? yf : std::isnan(yf) ? xf : (xf > yf ? xf : yf);
    const float want_min = std::isnan(xf) ? yf : std::isnan(yf) ? xf : (xf < yf ? xf : yf);
    if (!same(imest__bg_fmax(x, y), want) || !same(imest__bg_fmaxf(xf, yf), want_max) ||
        !same(imest__bg_fminf(xf, yf), want_min)) {
      if (++mismatches <= 5) ADD_FAILURE() << std::hexfloat << "max/min of " << x << ", " << y;
    }
  };
  for (double x : kSpecial)
    for (double y : kSpecial) check(x, y);
  for (int i = 0; i < 100000; ++i) check(random_double(rng, i), random_double(rng, i / 3));
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(bits(imest__bg_fmax(0.0, -0.0)), bits(-0.0)); // y where equal, as newlib's
  EXPECT_TRUE(std::isnan(imest__bg_fmax(NAN, NAN)));
}
#endif
