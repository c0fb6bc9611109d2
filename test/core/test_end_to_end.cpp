/* SPDX-License-Identifier: Apache-2.0 */
// End to end on an independent float64 motor model: sample -> ISR -> background.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "motor_ref.hpp"

extern "C" {
#include "imest/imest.h"
}

namespace {
struct RunOut {
  std::vector<imest_result_t> res;
  std::vector<double> tr_true, rs_true;
};

// Runs the motor for `seconds`, feeding exact samples at fs from t_start on.
RunOut run(MotorRef &mot, double seconds, double t_start, bool at_rest, float window_s = 1.0f)
{
  const double fs = 4000.0;
  const int sub = 16;
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = (float)fs;
  cfg.window_s = window_s;
  cfg.start_at_rest = at_rest ? 1 : 0;
  static imest_t s;
  EXPECT_EQ(imest_init(&s, &cfg), IMEST_OK);
  RunOut out;
  while (mot.t < t_start - 1e-12)
    for (int k = 0; k < sub; ++k) mot.step(1.0 / fs / sub);
  const long n = (long)std::lround(seconds * fs);
  for (long j = 0; j < n; ++j) {
    double u[3], i[3];
    mot.phases(u, i);
    const float uf[3] = {(float)u[0], (float)u[1], (float)u[2]};
    const float iff[3] = {(float)i[0], (float)i[1], (float)i[2]};
    const float th = (float)std::fmod(mot.x[5], 2 * M_PI);
    if (imest_isr_abc(&s, uf, iff, th)) {
      imest_result_t r;
      while (imest_background(&s, &r) == 1) out.res.push_back(r);
    }
    for (int k = 0; k < sub; ++k) mot.step(1.0 / fs / sub);
  }
  return out;
}
} // namespace

// Paper's experiment 2 operating point with exact samples, record starting
// mid-run: the first window is warm-up (123 samples for the filters and
// 3183 for the offset tracker not used: invalid, more than half of it), and
// every later window recovers T_R and R_S.
TEST(EndToEnd, LoadedSteadyStateRecoversTrAndRs)
{
  MotorRef mot;
  mot.vll = 115;
  mot.f = 30;
  mot.load = 2.064;
  RunOut r = run(mot, 4.0, 1.5, false);
  ASSERT_EQ(r.res.size(), 4u);
  EXPECT_TRUE(r.res[0].flags & IMEST_FLAG_WARMUP);
  EXPECT_EQ(r.res[0].used_samples, 4000u - 123u - 3183u);
  EXPECT_EQ(r.res[0].status, IMEST_REASON_WARMUP);
  for (size_t k = 1; k < r.res.size(); ++k) {
    const imest_result_t &w = r.res[k];
    EXPECT_TRUE(w.valid) << k << " " << imest_reason_name(w.status);
    EXPECT_NEAR(w.tr_s, 0.12, 0.12 * 2e-3) << k;
    EXPECT_NEAR(w.rs_ohm, 5.04, 5.04 * 5e-3) << k;
    EXPECT_LT(w.pe_k2_rel, 0.04);
    EXPECT_TRUE(w.flags & IMEST_FLAG_HESSIAN_PD);
  }
}

// Paper's experiment 1: 60 Hz applied at standstill. The run-up window is
// valid; once at no-load speed the slip is ~0 and T_R is unobservable.
TEST(EndToEnd, RunUpValidThenZeroSlipInvalid)
{
  MotorRef mot;
  RunOut r = run(mot, 3.0, 0.0, true);
  ASSERT_EQ(r.res.size(), 3u);
  EXPECT_TRUE(r.res[0].valid) << imest_reason_name(r.res[0].status);
  EXPECT_NEAR(r.res[0].tr_s, 0.12, 0.12 * 1e-2);
  EXPECT_NEAR(r.res[0].rs_ohm, 5.04, 5.04 * 2e-2);
  for (size_t k = 1; k < r.res.size(); ++k) {
    EXPECT_FALSE(r.res[k].valid) << k;
    EXPECT_EQ(r.res[k].status, IMEST_REASON_ZERO_SLIP) << k << " " << imest_reason_name(r.res[k].status);
  }
}

// No supply at all: no current, a clear reason, never a number marked valid.
TEST(EndToEnd, NoCurrentIsInvalidWithReason)
{
  MotorRef mot;
  mot.vll = 0;
  RunOut r = run(mot, 2.0, 0.0, true);
  ASSERT_EQ(r.res.size(), 2u);
  for (const auto &w : r.res) {
    EXPECT_FALSE(w.valid);
    EXPECT_EQ(w.status, IMEST_REASON_NO_CURRENT);
  }
}
