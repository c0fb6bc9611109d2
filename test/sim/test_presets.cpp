/* SPDX-License-Identifier: Apache-2.0 */
// Industrial drive presets: each motor's rated point (phasor steady state at 400 V, 50 Hz,
// rated torque) near the catalogue speed and current, and each drive running its default point
// (390 V on the 560 V bus, firmware timing) without clipping, at the phasor solution's speed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "common.hpp"

using namespace simtest;

namespace {
const char *const kDrives[] = {"4kw", "11kw", "15kw", "37kw", "75kw"};
}

TEST(SimPresets, RatedPointNearCatalogue)
{
  std::printf("[ presets  ] %-5s %9s %9s %8s %8s %7s %7s %8s %8s\n", "", "n_cat", "n_model", "I_cat",
              "I_model", "T_R", "sigma", "T_bd/T_n", "I0/I_n");
  for (const char *name : kDrives) {
    imsim_config_t c;
    ASSERT_EQ(imsim_config_preset(&c, name), 0) << name;
    EXPECT_EQ(c.rated_voltage_v, 400.0);
    EXPECT_EQ(c.rated_freq_hz, 50.0);
    EXPECT_NEAR(c.rated_torque_nm * c.rated_speed_rpm * kPi / 30, c.rated_power_w, 1e-6 * c.rated_power_w);
    imsim_steady_t st, s0;
    ASSERT_EQ(imsim_steady_state(&c, 400.0, 50.0, c.rated_torque_nm, &st), 0) << name;
    ASSERT_EQ(imsim_steady_state(&c, 400.0, 50.0, 0.0, &s0), 0) << name;
    // the equivalent circuit has no iron or stray losses: slip within 2 % of synchronous
    // speed of the catalogue's, current 0..15 % below the catalogue's
    EXPECT_NEAR(st.speed_rpm, c.rated_speed_rpm, 0.02 * 1500) << name;
    EXPECT_LT(st.i_rms_phase, c.rated_current_a) << name;
    EXPECT_GT(st.i_rms_phase, 0.85 * c.rated_current_a) << name;
    // breakdown torque well above rated (bisection on the load the phasor solution carries)
    double lo = c.rated_torque_nm, hi = 20 * c.rated_torque_nm;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      imsim_steady_t t;
      (imsim_steady_state(&c, 400.0, 50.0, mid, &t) == 0 ? lo : hi) = mid;
    }
    EXPECT_GT(lo, 2.5 * c.rated_torque_nm) << name;
    // sensors sized from the nameplate: about 2.5 x rated peak current
    EXPECT_NEAR(c.i_range_a / (std::sqrt(2.0) * c.rated_current_a), 2.5, 0.2) << name;
    std::printf("[ presets  ] %-5s %9.1f %9.1f %8.1f %8.2f %7.3f %7.4f %8.2f %8.2f\n", name,
                c.rated_speed_rpm, st.speed_rpm, c.rated_current_a, st.i_rms_phase, c.tr_s, c.sigma,
                lo / c.rated_torque_nm, s0.i_rms_phase / c.rated_current_a);
  }
}

TEST(SimPresets, DefaultDriveRunsAtTheSteadyState)
{
  for (const char *name : kDrives) {
    imsim_config_t c;
    ASSERT_EQ(imsim_config_preset(&c, name), 0) << name;
    EXPECT_EQ(c.timing, IMSIM_TIMING_FIRMWARE);
    EXPECT_EQ(c.supply, IMSIM_SUPPLY_PWM);
    EXPECT_EQ(c.start, IMSIM_START_STEADY);
    imsim_steady_t st;
    ASSERT_EQ(imsim_steady_state(&c, c.vll_v, c.freq_hz, c.load_nm, &st), 0);
    static imsim_t sim;
    imsim_sample_t s;
    ASSERT_EQ(imsim_init(&sim, &c, &s), 0) << imsim_error(&sim);
    const long n = long(0.2 * c.fs_hz);
    double speed = 0, imax = 0;
    for (long k = 0; k < n; ++k) {
      imsim_step(&sim, &s);
      speed += s.speed_rad_s * 30 / kPi / double(n);
      for (int p = 0; p < 3; ++p) imax = std::max(imax, std::fabs(s.i_abc_true[p]));
    }
    imsim_pwm_stats_t ps;
    imsim_get_pwm_stats(&sim, &ps);
    EXPECT_EQ(ps.clipped_half_periods, 0u) << name;
    EXPECT_LT(ps.vdc_needed_v, c.vdc_v) << name;
    EXPECT_NEAR(speed, st.speed_rpm, 0.5) << name;
    EXPECT_LT(imax, 0.6 * c.i_range_a) << name;
    EXPECT_NEAR(s.load_nm, c.rated_torque_nm, 1e-12) << name;
  }
}
