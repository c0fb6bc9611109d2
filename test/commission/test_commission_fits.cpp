/* SPDX-License-Identifier: Apache-2.0 */
// The commissioning fits' own numerics (src/commission/fits/commission_fit.h): exp without libm
// and the weighted straight line the probe and the sensor-gain fits share.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

extern "C" {
#include "commission_fit.h"
}

namespace {

// ulps between a and the reference b (b > 0)
double ulps(double a, double b)
{
  return std::fabs(a - b) / (b * std::numeric_limits<double>::epsilon());
}

} // namespace

TEST(CommissionFits, ExpWithinTwoUlpOfLibm)
{
  double worst = 0.0, at = 0.0;
  for (double x = -699.5; x <= 700.0; x += 0.0173) {
    const double e = ulps(imest__cm_exp(x), std::exp(x));
    if (e > worst) {
      worst = e;
      at = x;
    }
  }
  // the fits' arguments: ts / tau (1e-6 .. 1) and ln tau offsets (within +-12)
  for (double x = -1e-3; x <= 1e-3; x += 1.37e-7) {
    const double e = ulps(imest__cm_exp(x), std::exp(x));
    if (e > worst) {
      worst = e;
      at = x;
    }
  }
  EXPECT_LE(worst, 2.0) << "at x = " << at;
  EXPECT_EQ(imest__cm_exp(0.0), 1.0);
  EXPECT_EQ(imest__cm_exp(-800.0), 0.0);
  EXPECT_TRUE(std::isnan(imest__cm_exp(std::nan(""))));
  EXPECT_GT(imest__cm_exp(800.0), 1e300); // held at e^700, finite
  EXPECT_TRUE(std::isfinite(imest__cm_exp(800.0)));
}

TEST(CommissionFits, LineFitRecoversSlopeAndResidual)
{
  cm_line_t l = {};
  const double x[5] = {0.1, 0.4, 0.5, 0.9, 1.3}, w[5] = {1.0, 2.0, 3.0, 1.0, 4.0};
  const double e[5] = {0.01, -0.02, 0.015, -0.01, 0.002}; // residuals about the line
  for (int k = 0; k < 5; ++k) imest__cm_line_add(&l, w[k], x[k], 2.0 - 3.0 * x[k] + e[k]);
  double a = 0.0;
  const double sse = imest__cm_line_fit(&l, &a);
  // the weighted least-squares answer, computed here from the centred sums
  double sw = 0, sx = 0, sy = 0;
  for (int k = 0; k < 5; ++k) {
    sw += w[k];
    sx += w[k] * x[k];
    sy += w[k] * (2.0 - 3.0 * x[k] + e[k]);
  }
  const double xm = sx / sw, ym = sy / sw;
  double sxx = 0, sxy = 0;
  for (int k = 0; k < 5; ++k) {
    const double y = 2.0 - 3.0 * x[k] + e[k];
    sxx += w[k] * (x[k] - xm) * (x[k] - xm);
    sxy += w[k] * (x[k] - xm) * (y - ym);
  }
  const double a_ref = sxy / sxx, c_ref = ym - a_ref * xm;
  double sse_ref = 0;
  for (int k = 0; k < 5; ++k) {
    const double r = 2.0 - 3.0 * x[k] + e[k] - (c_ref + a_ref * x[k]);
    sse_ref += w[k] * r * r;
  }
  EXPECT_NEAR(a, a_ref, 1e-12);
  EXPECT_NEAR(sse, sse_ref, 1e-12);
  EXPECT_NEAR(a, -3.0, 0.05);
}

TEST(CommissionFits, LineFitWithOneDistinctXHasNoSlope)
{
  cm_line_t l = {};
  imest__cm_line_add(&l, 1.0, 0.5, 1.0);
  imest__cm_line_add(&l, 3.0, 0.5, 2.0);
  double a = 7.0;
  const double sse = imest__cm_line_fit(&l, &a);
  EXPECT_EQ(a, 0.0);
  EXPECT_NEAR(sse, 1.0 * 0.75 * 0.75 + 3.0 * 0.25 * 0.25, 1e-12); // about the mean 1.75
  cm_line_t empty = {};
  EXPECT_EQ(imest__cm_line_fit(&empty, &a), 0.0);
  EXPECT_EQ(a, 0.0);
}
