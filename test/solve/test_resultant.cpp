// Generic resultant (MATH.md §4) on random symmetric positive semi-definite
// R_W = A'A (no structure): degree 20 with leading coefficient
// 16 R44 (R33 R44 - R34^2) >= 0 and r(0) = -16 R77 (R77 R88 - R78^2) <= 0;
// with column 3 = -m column 4 the K2^19, K2^20 coefficients vanish to
// round-off and K2^18 has 8 R44 (m^2 R11 R44 - m^2 R14^2 + 2m R12 R44
// - 2m R14 R24 + R22 R44 - R24^2). Unscaled tables (s = g = c = 1).
#include <gtest/gtest.h>

#include "solve_util.hpp"

namespace {

double R(const imest_sums_t &s, int i, int j) { return s.rw[i - 1][j - 1]; }

imest_sums_t random_psd(std::mt19937_64 &rng, bool structured, double m) {
  std::normal_distribution<double> N(0, 1);
  double A[12][8];
  for (auto &row : A)
    for (double &v : row) v = N(rng);
  if (structured)
    for (auto &row : A) row[2] = -m * row[3];
  double y[12];
  for (double &v : y) v = N(rng);
  imest_sums_t s{};
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 12; ++k) s.rw[i][j] += A[k][i] * A[k][j];
    for (int k = 0; k < 12; ++k) s.rwy[i] += A[k][i] * y[k];  // R_Wy = A'y: structured with A
  }
  s.ry = 10 + std::fabs(N(rng));
  return s;
}

}  // namespace

TEST(Resultant, GenericDegree20) {
  std::mt19937_64 rng(7);
  for (int it = 0; it < 500; ++it) {
    const imest_sums_t s = random_psd(rng, false, 0);
    imest_tables_t t;
    imest_tables_scaled(&s, 0, 0, 0, &t);
    double r[21];
    imest_resultant(&t, r, 1);
    double mag = 0;
    for (double v : r) mag = std::max(mag, std::fabs(v));
    const double lead = 16 * R(s, 4, 4) * (R(s, 3, 3) * R(s, 4, 4) - R(s, 3, 4) * R(s, 3, 4));
    const double r0 = -16 * R(s, 7, 7) * (R(s, 7, 7) * R(s, 8, 8) - R(s, 7, 8) * R(s, 7, 8));
    EXPECT_NEAR(r[20], lead, 1e-11 * mag) << it;
    EXPECT_NEAR(r[0], r0, 1e-11 * mag) << it;
    EXPECT_GE(lead, 0.0);
    EXPECT_LE(r[0], 1e-12 * mag);
    // generic flag keeps r[19], r[20]; the regressor flag zeroes them
    double r18[21];
    imest_resultant(&t, r18, 0);
    EXPECT_EQ(r18[19], 0.0);
    EXPECT_EQ(r18[20], 0.0);
    for (int k = 0; k < 19; ++k) EXPECT_EQ(r18[k], r[k]);
    // r(0) < 0 and lead > 0 => at least one positive root, found
    double roots[20];
    const int n = imest_poly_positive_roots(r, 20, roots, 20);
    EXPECT_GE(n, 1) << it;
  }
}

TEST(Resultant, StructuredDegree18) {
  std::mt19937_64 rng(11);
  const double m = (1 - 0.096) / 0.096;
  for (int it = 0; it < 500; ++it) {
    const imest_sums_t s = random_psd(rng, true, m);
    imest_tables_t t;
    imest_tables_scaled(&s, 0, 0, 0, &t);
    double r[21];
    imest_resultant(&t, r, 1);
    double mag = 0;
    for (double v : r) mag = std::max(mag, std::fabs(v));
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
