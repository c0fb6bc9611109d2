/* SPDX-License-Identifier: Apache-2.0 */
// Thermal drift: one hour of exp2 heats the motor as in the paper's experiment 2.
#include <gtest/gtest.h>

#include "common.hpp"

using namespace simtest;

// Paper: T_R 0.115 -> 0.09 s, R_S 5 -> 5.8 ohm over ~1 h at rated load (ratios 0.7826, 1.16).
// Ideal V/f supply, coarse sampling (500 Hz, 1 ms steps) to keep the test fast; the thermal
// model only sees the copper losses, which this reproduces.
TEST(SimThermal, OneHourOfExp2ReachesPaperTargets)
{
  imsim_config_t c;
  imsim_config_preset(&c, "exp2");
  c.ideal_sensors = true;
  c.fs_hz = 500;
  c.steps_per_sample = 2;
  static imsim_t sim;
  imsim_sample_t s;
  ASSERT_EQ(imsim_init(&sim, &c, &s), 0);
  EXPECT_DOUBLE_EQ(s.tr_s, 0.12);
  EXPECT_DOUBLE_EQ(s.rs_ohm, 5.04);
  double tr_10min = 0;
  for (long k = 1; k <= 3600L * 500; ++k) {
    imsim_step(&sim, &s);
    if (k == 600L * 500) tr_10min = s.tr_s;
  }
  EXPECT_NEAR(s.t, 3600.0, 1e-9);
  EXPECT_NEAR(s.tr_s / 0.12, 0.09 / 0.115, 0.01);
  EXPECT_NEAR(s.rs_ohm / 5.04, 5.8 / 5.0, 0.01);
  EXPECT_GT(tr_10min, s.tr_s); // monotone heating
  EXPECT_LT(tr_10min, 0.12);
  EXPECT_GT(s.temp_stator_c, 50.0);
  EXPECT_NEAR(s.load_nm, 2.064, 1e-12);
  // still at the rated operating point (speed drops a little as R_R rises)
  EXPECT_NEAR(s.speed_rad_s * 30 / kPi, 843, 3);
}

TEST(SimThermal, NoThermalKeepsParametersAndSpeedupScalesTime)
{
  imsim_config_t c;
  imsim_config_preset(&c, "exp2");
  c.ideal_sensors = true;
  c.fs_hz = 500;
  c.steps_per_sample = 2;
  c.thermal = false;
  auto s = run(c, 500 * 60);
  ASSERT_FALSE(s.empty());
  EXPECT_DOUBLE_EQ(s.back().tr_s, 0.12);
  EXPECT_DOUBLE_EQ(s.back().rs_ohm, 5.04);
  c.thermal = true;
  c.thermal_speedup = 60; // 60 s behave like one hour
  s = run(c, 500 * 60);
  EXPECT_LT(s.back().tr_s, 0.12 * 0.85);
}
