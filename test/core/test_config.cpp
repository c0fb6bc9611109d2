/* SPDX-License-Identifier: Apache-2.0 */
// The config defaults write every field: a config on the stack (garbage in
// it) and a zeroed one come out of imest_config_default() byte for byte the
// same. tr_nominal_known was once left as it was, and T_R was then judged
// against the default nominal at random.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

extern "C" {
#include "imest/imest.h"
#include "imest/imest_commission.h"
}

#include "config_cases.h"

template <typename T, typename F> static void expect_every_field_written(F fill_default)
{
  T a, b;
  std::memset(&a, 0xA5, sizeof a);
  std::memset(&b, 0x00, sizeof b);
  fill_default(&a);
  fill_default(&b);
  EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
}

TEST(ConfigDefault, EstimatorWritesEveryField)
{
  expect_every_field_written<imest_config_t>(imest_config_default);
  imest_config_t cfg;
  std::memset(&cfg, 0xFF, sizeof cfg);
  imest_config_default(&cfg);
  EXPECT_EQ(cfg.tr_nominal_known, 0);
}

TEST(ConfigDefault, CommissioningWritesEveryField)
{
  expect_every_field_written<imest_comm_config_t>(imest_comm_config_default);
}

// The magnetising curve (ls_curve_*): 0 points is none; 2 to IMEST_LS_CURVE_POINTS points, each
// current and L_S finite and positive, the currents strictly increasing. Each bad curve is
// refused naming its field, and imest_init() refuses it too.
namespace {
imest_config_t curve_config(unsigned int n)
{
  imest_config_t c = config_cases::motor();
  const float i_a[IMEST_LS_CURVE_POINTS] = {3.3f, 5.1f, 6.6f, 8.1f};
  const float l_h[IMEST_LS_CURVE_POINTS] = {0.230f, 0.206f, 0.181f, 0.160f};
  for (int k = 0; k < IMEST_LS_CURVE_POINTS; ++k) {
    c.ls_curve_i_a[k] = i_a[k];
    c.ls_curve_h[k] = l_h[k];
  }
  c.ls_curve_points = n;
  return c;
}

const char *curve_field(const imest_config_t &c)
{
  return config_cases::refused_field(c);
}
} // namespace

TEST(ConfigCurve, UsableCurvesPass)
{
  for (unsigned int n : {0u, 2u, 3u, 4u}) EXPECT_STREQ(curve_field(curve_config(n)), "") << n;
  imest_config_t c = curve_config(0u); // no curve: whatever the points hold is not judged
  c.ls_curve_i_a[0] = -1.0f;
  c.ls_curve_h[1] = NAN;
  EXPECT_STREQ(curve_field(c), "");
}

TEST(ConfigCurve, BadCurvesAreRefusedNamingTheField)
{
  EXPECT_STREQ(curve_field(curve_config(1u)), "ls_curve_points") << "one point is ls_h";
  EXPECT_STREQ(curve_field(curve_config(IMEST_LS_CURVE_POINTS + 1u)), "ls_curve_points");
  imest_config_t c = curve_config(4u);
  c.ls_curve_i_a[2] = 5.0f; // below the point before: unsorted
  EXPECT_STREQ(curve_field(c), "ls_curve_i_a");
  c = curve_config(4u);
  c.ls_curve_i_a[2] = c.ls_curve_i_a[1]; // equal: a segment of zero width
  EXPECT_STREQ(curve_field(c), "ls_curve_i_a");
  c = curve_config(3u);
  c.ls_curve_i_a[0] = 0.0f;
  EXPECT_STREQ(curve_field(c), "ls_curve_i_a");
  c = curve_config(3u);
  c.ls_curve_i_a[1] = NAN;
  EXPECT_STREQ(curve_field(c), "ls_curve_i_a");
  c = curve_config(3u);
  c.ls_curve_i_a[2] = INFINITY;
  EXPECT_STREQ(curve_field(c), "ls_curve_i_a");
  c = curve_config(2u);
  c.ls_curve_h[1] = -0.1f;
  EXPECT_STREQ(curve_field(c), "ls_curve_h");
  c = curve_config(2u);
  c.ls_curve_h[0] = 0.0f;
  EXPECT_STREQ(curve_field(c), "ls_curve_h");
  c = curve_config(4u);
  c.ls_curve_h[3] = NAN;
  EXPECT_STREQ(curve_field(c), "ls_curve_h");
  c = curve_config(3u);
  c.ls_curve_h[3] = NAN; // beyond the points in use: not judged
  EXPECT_STREQ(curve_field(c), "");
}
