/* SPDX-License-Identifier: Apache-2.0 */
// Generic resultant (docs/METHOD.md §4) on random symmetric positive semi-definite
// R_W = A'A (no structure): degree 20 with leading coefficient
// 16 R44 (R33 R44 - R34^2) >= 0 and r(0) = -16 R77 (R77 R88 - R78^2) <= 0;
// with column 3 = -m column 4 the K2^19, K2^20 coefficients vanish to
// round-off and K2^18 has 8 R44 (m^2 R11 R44 - m^2 R14^2 + 2m R12 R44
// - 2m R14 R24 + R22 R44 - R24^2). Unscaled tables (s = g = c = 1).
#include <gtest/gtest.h>

#include "solve_util.hpp"

namespace {

double R(const bg_sums_t &s, int i, int j)
{
  return s.rw[i - 1][j - 1];
}

bg_sums_t random_psd(std::mt19937_64 &rng, bool structured, double m)
{
  std::normal_distribution<double> N(0, 1);
  double A[12][8];
  for (auto &row : A)
    for (double &v : row) v = N(rng);
  if (structured)
    for (auto &row : A) row[2] = -m * row[3];
  double y[12];
  for (double &v : y) v = N(rng);
  bg_sums_t s{};
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 12; ++k) s.rw[i][j] += A[k][i] * A[k][j];
    for (int k = 0; k < 12; ++k) s.rwy[i] += A[k][i] * y[k]; // R_Wy = A'y: structured with A
  }
  s.ry = 10 + std::fabs(N(rng));
  return s;
}

} // namespace

TEST(Resultant, GenericDegree20)
{
  std::mt19937_64 rng(7);
  for (int it = 0; it < 500; ++it) {
    const bg_sums_t s = random_psd(rng, false, 0);
    bg_tables_t t;
    imest__bg_tables_scaled(&s, 0, 0, 0, &t);
    double rw[22];
    imest__bg_resultant(&t, rw, 1);
    EXPECT_EQ(rw[0], 0.0); // weight 0: r_w = kappa r
    const double *r = rw + 1;
    double mag = 0;
    for (int k = 0; k < 21; ++k) mag = std::max(mag, std::fabs(r[k]));
    const double lead = 16 * R(s, 4, 4) * (R(s, 3, 3) * R(s, 4, 4) - R(s, 3, 4) * R(s, 3, 4));
    const double r0 = -16 * R(s, 7, 7) * (R(s, 7, 7) * R(s, 8, 8) - R(s, 7, 8) * R(s, 7, 8));
    EXPECT_NEAR(r[20], lead, 1e-11 * mag) << it;
    EXPECT_NEAR(r[0], r0, 1e-11 * mag) << it;
    EXPECT_GE(lead, 0.0);
    EXPECT_LE(r[0], 1e-12 * mag);
    // generic flag keeps r[19], r[20]; the regressor flag zeroes them
    double r18[22];
    imest__bg_resultant(&t, r18, 0);
    EXPECT_EQ(r18[20], 0.0);
    EXPECT_EQ(r18[21], 0.0);
    for (int k = 0; k < 20; ++k) EXPECT_EQ(r18[k], rw[k]);
    // r(0) < 0 and lead > 0 => at least one positive root, found
    double roots[20];
    const int n = imest__bg_roots_positive(r, 20, roots, 20);
    EXPECT_GE(n, 1) << it;
  }
}

TEST(Resultant, StructuredDegree18)
{
  std::mt19937_64 rng(11);
  const double m = (1 - 0.096) / 0.096;
  for (int it = 0; it < 500; ++it) {
    const bg_sums_t s = random_psd(rng, true, m);
    bg_tables_t t;
    imest__bg_tables_scaled(&s, 0, 0, 0, &t);
    double rw[22];
    imest__bg_resultant(&t, rw, 1);
    const double *r = rw + 1;
    double mag = 0;
    for (int k = 0; k < 21; ++k) mag = std::max(mag, std::fabs(r[k]));
    EXPECT_LE(std::fabs(r[20]), 1e-12 * mag) << it;
    EXPECT_LE(std::fabs(r[19]), 1e-12 * mag) << it;
    const double R11 = R(s, 1, 1), R12 = R(s, 1, 2), R14 = R(s, 1, 4), R22 = R(s, 2, 2), R24 = R(s, 2, 4),
                 R44 = R(s, 4, 4);
    const double lead18 = 8 * R44 *
                          (m * m * R11 * R44 - m * m * R14 * R14 + 2 * m * R12 * R44 - 2 * m * R14 * R24 +
                           R22 * R44 - R24 * R24);
    EXPECT_NEAR(r[18], lead18, 1e-10 * mag) << it;
    EXPECT_GE(lead18, -1e-12 * mag);
    EXPECT_LE(r[0], 1e-12 * mag);
  }
}

// Weighted cost (bg_tables.h): r_w = a0^2 bw2 - a0 a1 bw1 + a1^2 bw0 with
// bw_t = kappa b_t + cw t'. For this regressor r_w[21] and r_w[20] vanish for
// any cw (the K2^19 coefficient of the cw part is 8 e2[6] (4 e2[6] e0[8] -
// e1[7]^2) = 32 R44 (R33 R44 - R34^2) = 0) and r_w[19] = r[18] (cw-free).
// Defining property: r_w(kappa) = a1^2 p2w(k = -a0/a1) with
// p2w = (kappa^2 + cw) dP/dkappa - 4 kappa P, P = sum (e2 k^2 + e1 k + e0) kappa^m.
TEST(Resultant, WeightedStructuredDegree19)
{
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> U(0, 1);
  const double m = (1 - 0.096) / 0.096;
  for (int it = 0; it < 300; ++it) {
    const bg_sums_t s = random_psd(rng, true, m);
    bg_tables_t t;
    imest__bg_tables_scaled(&s, 0, 0, 0, &t);
    double r0[22];
    imest__bg_resultant(&t, r0, 1);
    const double cw = std::pow(10.0, -2 + 4 * U(rng));
    imest__bg_tables_weight(&t, cw);
    EXPECT_EQ(t.cw, cw);
    double r[22];
    imest__bg_resultant(&t, r, 1);
    double mag = 0;
    for (double v : r) mag = std::max(mag, std::fabs(v));
    EXPECT_LE(std::fabs(r[21]), 1e-12 * mag) << it;
    EXPECT_LE(std::fabs(r[20]), 1e-12 * mag) << it;
    EXPECT_NEAR(r[19], r0[19], 1e-10 * mag) << it;
    for (int q = 0; q < 4; ++q) {
      const long double x = std::pow(10.0, -1.5 + 3 * U(rng));
      long double e[3] = {0, 0, 0}, de[3] = {0, 0, 0}, mg = 0;
      const double *tab[3] = {t.e2, t.e1, t.e0};
      const int len[3] = {7, 8, 9};
      for (int o = 0; o < 3; ++o)
        for (int k = 0; k < len[o]; ++k) {
          e[o] += tab[o][k] * std::pow(x, k);
          if (k > 0) de[o] += k * tab[o][k] * std::pow(x, k - 1);
        }
      const long double a1 = 2 * e[0], a0 = e[1], k = -a0 / a1;
      const long double P = (e[0] * k + e[1]) * k + e[2], Px = (de[0] * k + de[1]) * k + de[2];
      const long double ref = a1 * a1 * ((x * x + cw) * Px - 4 * x * P);
      long double val = 0;
      for (int j = 21; j >= 0; --j) {
        val = val * x + r[j];
        mg = mg * x + std::fabs(r[j]);
      }
      EXPECT_LE(std::fabs((double)(val - ref)), 1e-9 * (double)mg) << it << " x " << (double)x;
    }
  }
}

#if BG_SOFT_DOUBLE
namespace {

// out = conv(a, b) with sign, and its magnitude sum |a_i b_j|, in long double
void conv_ld(const long double *a, int na, const long double *b, int nb, long double sign, long double *out,
             long double *mag)
{
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j) {
      out[i + j] += sign * a[i] * b[j];
      mag[i + j] += std::fabs(a[i] * b[j]);
    }
}

} // namespace

// Where double is soft the resultant and the table values run in float-float
// (bg_ff.h): within the stated bound (3n + 10) 2^-48 sum |terms| (n <= 15;
// 2e-13) of a long double reference, on random weighted tables inside the
// float-float range, and the table values within (8 + 3 * 8 + 4) 2^-48 (1.3e-13).
TEST(Resultant, FloatFloatWithinItsBound)
{
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> U(0, 1);
  int in_range = 0;
  double worst_r = 0, worst_v = 0;
  for (int it = 0; it < 300; ++it) {
    const bg_sums_t s = random_psd(rng, it % 2 == 0, (1 - 0.096) / 0.096);
    bg_tables_t t;
    imest__bg_tables_scaled(&s, 0, 0, 0, &t);
    imest__bg_tables_weight(&t, (it % 3 == 0) ? 0.0 : std::pow(10.0, -2 + 4 * U(rng)));
    if (!t.ff_ok) continue;
    ++in_range;
    double r[22];
    imest__bg_resultant(&t, r, 1);
    long double a0[8], a1[7], b2[8], b1[9], b0[10], u[15] = {0}, um[15] = {0}, sq[13] = {0}, sqm[13] = {0};
    long double ref[22] = {0}, mag[22] = {0}, ignore[22] = {0};
    for (int k = 0; k < 8; ++k) a0[k] = t.a0[k], b2[k] = t.bw2[k];
    for (int k = 0; k < 7; ++k) a1[k] = t.a1[k];
    for (int k = 0; k < 9; ++k) b1[k] = t.bw1[k];
    for (int k = 0; k < 10; ++k) b0[k] = t.bw0[k];
    conv_ld(a0, 8, b2, 8, 1, u, um);
    conv_ld(a1, 7, b1, 9, -1, u, um);
    conv_ld(a1, 7, a1, 7, 1, sq, sqm);
    conv_ld(a0, 8, u, 15, 1, ref, ignore);
    conv_ld(sq, 13, b0, 10, 1, ref, ignore);
    long double a0m[8];
    for (int k = 0; k < 8; ++k) a0m[k] = std::fabs(a0[k]);
    long double b0m[10];
    for (int k = 0; k < 10; ++k) b0m[k] = std::fabs(b0[k]);
    conv_ld(a0m, 8, um, 15, 1, mag, ignore);
    conv_ld(sqm, 13, b0m, 10, 1, mag, ignore);
    for (int k = 0; k < 22; ++k) {
      const double err = (double)std::fabs(r[k] - ref[k]);
      EXPECT_LE(err, 2e-13 * (double)mag[k]) << it << " r[" << k << "]";
      if (mag[k] > 0) worst_r = std::max(worst_r, err / (double)mag[k]);
    }
    for (int q = 0; q < 4; ++q) {
      const double x = std::pow(2.0, -8 + 16 * U(rng));
      double v[3];
      imest__bg_tables_values(&t, x, v);
      const double *tab[3] = {t.e2, t.e1, t.e0};
      const int len[3] = {7, 8, 9};
      for (int o = 0; o < 3; ++o) {
        long double e = 0, m = 0;
        for (int k = len[o] - 1; k >= 0; --k) {
          e = e * x + tab[o][k];
          m = m * x + std::fabs(tab[o][k]);
        }
        const double err = (double)std::fabs(v[o] - e);
        EXPECT_LE(err, 1.3e-13 * (double)m) << it << " x " << x;
        worst_v = std::max(worst_v, err / (double)m);
      }
    }
  }
  EXPECT_GE(in_range, 200); // the float-float path is what this tests
  std::printf("[float-float] %d of 300 in range; worst |r - ref| / sum|terms| %.2g, values %.2g\n", in_range,
              worst_r, worst_v);
}
#endif
