/* SPDX-License-Identifier: Apache-2.0 */
// Window timing, the lock-free hand-off, overruns, warm-up and faults.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

extern "C" {
#include "imest/imest.h"
}

namespace {
imest_config_t small_config()
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = 4000.0f;
  cfg.window_s = 0.1f; // 400 samples
  // the filter warm-up alone (123 samples); the offset tracker's longer
  // first-start warm-up has its own test below
  cfg.dc_block_hz = 0.0f;
  return cfg;
}
// a rotating current/voltage at constant speed (no physics needed here)
void feed(imest_t *s, int n, int &k, float amp = 1.0f)
{
  for (int j = 0; j < n; ++j, ++k) {
    const float ph = 2 * (float)M_PI * 30.0f * (float)k / 4000.0f;
    const float u[3] = {100 * std::cos(ph), 100 * std::cos(ph - 2.0944f), 100 * std::cos(ph + 2.0944f)};
    const float i[3] = {amp * std::cos(ph - 0.5f), amp * std::cos(ph - 2.6f), amp * std::cos(ph + 1.6f)};
    imest_isr_abc(s, u, i, std::fmod(0.5f * ph, 6.2831853f));
  }
}
} // namespace

TEST(Handoff, InitRejectsBadConfigNamingTheField)
{
  imest_config_t cfg = small_config();
  const char *field = nullptr;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_OK);
  cfg.sigma = 1.5f;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "sigma");
  static imest_t s;
  EXPECT_EQ(imest_init(&s, &cfg), IMEST_ERR_CONFIG);
  EXPECT_EQ(imest_init(nullptr, &cfg), IMEST_ERR_NULL);
  cfg = small_config();
  cfg.pole_pairs = 0;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "pole_pairs");
  cfg = small_config();
  cfg.filter_hz = 3000;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "filter_hz");
  cfg = small_config();
  EXPECT_EQ(cfg.voltage_kind, IMEST_VOLTAGE_STAIRCASE);
  cfg.voltage_kind = IMEST_VOLTAGE_SMOOTH;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_OK);
  cfg.voltage_kind = (imest_voltage_kind_t)2;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "voltage_kind");
  cfg.voltage_kind = (imest_voltage_kind_t)-1;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "voltage_kind");
}

// The constants' stated uncertainties: relative, in [0, 1); the defaults a data sheet's.
TEST(Handoff, ConstantsUncertaintyIsRangeChecked)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, 0.1f);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.2f);
  const char *field = nullptr;
  for (const float good : {0.0f, 0.05f, 0.99f}) {
    cfg = small_config();
    cfg.ls_uncertainty = good;
    cfg.sigma_uncertainty = good;
    EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_OK) << good;
  }
  for (const float bad : {-0.01f, 1.0f, 1.5f, NAN, INFINITY}) {
    cfg = small_config();
    cfg.ls_uncertainty = bad;
    EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG) << bad;
    EXPECT_STREQ(field, "ls_uncertainty");
    cfg = small_config();
    cfg.sigma_uncertainty = bad;
    EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_ERR_CONFIG) << bad;
    EXPECT_STREQ(field, "sigma_uncertainty");
  }
}

TEST(Handoff, IsrSignalsExactlyAtWindowEnds)
{
  imest_config_t cfg = small_config();
  static imest_t s;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  imest_result_t r;
  int k = 0, completed = 0;
  for (int n = 0; n < 1200; ++n, ++k) {
    const float u[3] = {1, 0, -1}, i[3] = {0.5f, -0.25f, -0.25f};
    const int done = imest_isr_abc(&s, u, i, 0.0f);
    if ((n + 1) % 400 == 0) {
      EXPECT_EQ(done, 1) << n;
      ASSERT_EQ(imest_background(&s, &r), 1);
      EXPECT_EQ(r.seq, (uint32_t)completed);
      EXPECT_EQ(r.samples, 400u);
      EXPECT_NEAR(r.t_end_s, (n) / 4000.0, 1e-9);
      ++completed;
    } else {
      EXPECT_EQ(done, 0) << n;
    }
    EXPECT_EQ(imest_background(&s, &r), 0);
  }
  EXPECT_EQ(completed, 3);
}

TEST(Handoff, OverrunIsCountedAndVisibleNeverTorn)
{
  imest_config_t cfg = small_config();
  static imest_t s;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  imest_result_t r;
  int k = 0;
  feed(&s, 400 * 3, k);              // three windows, background never ran
  EXPECT_EQ(imest_overruns(&s), 2u); // window 0 handed over; 1 and 2 dropped
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.seq, 0u);
  EXPECT_EQ(imest_background(&s, &r), 0);
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.seq, 3u); // the gap shows the dropped windows 1 and 2
  EXPECT_EQ(r.overruns, 2u);
  EXPECT_TRUE(r.flags & IMEST_FLAG_OVERRUN);
  EXPECT_EQ(r.samples, 400u);
  EXPECT_EQ(r.used_samples, 400u);
}

TEST(Handoff, WarmupIsMarkedAndStartAtRestSkipsIt)
{
  imest_config_t cfg = small_config();
  cfg.window_s = 0.05f; // 200 samples: the 123-sample warm-up is most of it
  static imest_t s;
  imest_result_t r;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  int k = 0;
  feed(&s, 200, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.status, IMEST_REASON_WARMUP);
  EXPECT_FALSE(r.valid);
  EXPECT_TRUE(r.flags & IMEST_FLAG_WARMUP);
  EXPECT_EQ(r.used_samples, 200u - 123u);
  feed(&s, 200, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_FALSE(r.flags & IMEST_FLAG_WARMUP);
  EXPECT_EQ(r.used_samples, 200u);

  // a longer window keeps its flag but is judged on the samples it used
  cfg = small_config();
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  k = 0;
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_TRUE(r.flags & IMEST_FLAG_WARMUP);
  EXPECT_NE(r.status, IMEST_REASON_WARMUP);
  EXPECT_EQ(r.used_samples, 400u - 123u);
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_FALSE(r.flags & IMEST_FLAG_WARMUP);
  EXPECT_EQ(r.used_samples, 400u);

  cfg.start_at_rest = 1;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  k = 0;
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_FALSE(r.flags & IMEST_FLAG_WARMUP);
  EXPECT_EQ(r.used_samples, 400u);
}

TEST(Handoff, NonFiniteSampleInvalidatesItsWindowAndRecovers)
{
  imest_config_t cfg = small_config();
  cfg.start_at_rest = 1;
  static imest_t s;
  imest_result_t r;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  int k = 0;
  feed(&s, 100, k);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float u[3] = {nan, 0, 0}, i[3] = {0, 0, 0};
  imest_isr_abc(&s, u, i, 0.0f);
  ++k;
  feed(&s, 299, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.status, IMEST_REASON_INPUT_FAULT);
  EXPECT_FALSE(r.valid);
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_FALSE(r.flags & (IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_WARMUP));
  EXPECT_EQ(r.used_samples, 400u);
  // every reported number is finite or NaN, never Inf with valid set
  if (r.valid) EXPECT_TRUE(std::isfinite(r.tr_s));
}

// The duty-cycle input: a NaN, Inf or absurd duty on one leg, or a NaN or
// absurd bus voltage, is a fault of its window (isr_step's plausibility test of
// the alpha/beta voltage), and the next window is clean.
TEST(Handoff, BadDutyOrBusVoltageInvalidatesItsWindow)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Bad {
    float d, vdc;
  };
  for (const Bad b :
       {Bad{nan, 560.0f}, Bad{inf, 560.0f}, Bad{-1.0e6f, 560.0f}, Bad{0.5f, nan}, Bad{0.5f, 2.0e5f}}) {
    SCOPED_TRACE(testing::Message() << "duty " << b.d << ", v_dc " << b.vdc);
    imest_config_t cfg = small_config();
    cfg.start_at_rest = 1;
    static imest_t s;
    imest_result_t r;
    ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
    // a rotating voltage and current at 30 Hz, as feed() (no physics needed)
    auto sample = [&](int k, bool fault) {
      const float ph = 2 * (float)M_PI * 30.0f * (float)k / 4000.0f;
      const float d[3] = {fault ? b.d : 0.5f + 0.2f * std::cos(ph), 0.5f + 0.2f * std::cos(ph - 2.0944f),
                          0.5f + 0.2f * std::cos(ph + 2.0944f)};
      const float i[3] = {std::cos(ph - 0.5f), std::cos(ph - 2.6f), std::cos(ph + 1.6f)};
      imest_isr_duty(&s, d, fault ? b.vdc : 560.0f, i, std::fmod(0.5f * ph, 6.2831853f));
    };
    for (int k = 0; k < 400; ++k) sample(k, k == 150);
    ASSERT_EQ(imest_background(&s, &r), 1);
    // a bus voltage beyond u_absurd_v that leaves the line voltages plausible
    // reads as a sample at the limit
    const bool at_limit = std::isfinite(b.d) && std::isfinite(b.vdc) && b.vdc > 1.0e5f;
    EXPECT_EQ(r.status, at_limit ? IMEST_REASON_ADC_SATURATION : IMEST_REASON_INPUT_FAULT);
    EXPECT_TRUE(r.flags & (at_limit ? IMEST_FLAG_ADC_SAT : IMEST_FLAG_INPUT_FAULT));
    EXPECT_FALSE(r.valid);
    for (int k = 400; k < 800; ++k) sample(k, false);
    ASSERT_EQ(imest_background(&s, &r), 1);
    EXPECT_FALSE(r.flags & (IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT));
  }
}

TEST(Handoff, EncoderJumpAndSaturationAreFlagged)
{
  imest_config_t cfg = small_config();
  cfg.start_at_rest = 1;
  cfg.i_limit_a = 5.0f;
  static imest_t s;
  imest_result_t r;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  int k = 0;
  feed(&s, 100, k);
  const float u[3] = {0, 0, 0}, i[3] = {0, 0, 0};
  imest_isr_abc(&s, u, i, 5.0f); // angle jumps by ~2.6 rad in one sample
  ++k;
  feed(&s, 299, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.status, IMEST_REASON_ENCODER_FAULT);
  feed(&s, 100, k);
  const float isat[3] = {5.0f, -2.5f, -2.5f};
  imest_isr_abc(&s, u, isat, 0.0f);
  ++k;
  feed(&s, 299, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.status, IMEST_REASON_ADC_SATURATION);
}

TEST(Handoff, FlushHandsOverAShortWindowWithItsOwnEndTime)
{
  imest_config_t cfg = small_config(); // 400-sample windows
  cfg.start_at_rest = 1;
  static imest_t s;
  imest_result_t r;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  EXPECT_EQ(imest_isr_flush(&s), 0); // nothing to hand over
  int k = 0;
  feed(&s, 400 + 250, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(imest_isr_flush(&s), 1);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.seq, 1u);
  EXPECT_EQ(r.samples, 250u);
  EXPECT_EQ(r.used_samples, 250u);
  EXPECT_NEAR(r.t_end_s, (650 - 1) / 4000.0, 1e-9);
  // the next window is a full one again, numbered on
  feed(&s, 400, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.seq, 2u);
  EXPECT_EQ(r.samples, 400u);
}

// With the offset tracker on (the default), only the very first start waits
// for it too: 123 filter samples + 5 tau of the 1 Hz high-pass (3183
// samples). A restart after a fault waits for the filters only, since the
// tracker keeps its state; a start at rest waits for nothing.
TEST(Handoff, OffsetTrackerLengthensOnlyTheFirstWarmup)
{
  imest_config_t cfg = small_config();
  cfg.dc_block_hz = 1.0f;
  cfg.window_s = 1.0f; // 4000 samples
  static imest_t s;
  imest_result_t r;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  int k = 0;
  feed(&s, 4000, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.used_samples, 4000u - 123u - 3183u);
  EXPECT_EQ(r.status, IMEST_REASON_WARMUP);
  // a NaN sample restarts the filters only
  const float nan_u[3] = {NAN, 0, 0}, i[3] = {0, 0, 0};
  (void)imest_isr_abc(&s, nan_u, i, 0.0f);
  ++k;
  feed(&s, 3999, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.used_samples, 4000u - 1u - 123u);
  EXPECT_EQ(r.status, IMEST_REASON_INPUT_FAULT);
  // an explicit warm-up is taken as given
  cfg.warmup_s = 0.01f;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  k = 0;
  feed(&s, 4000, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.used_samples, 4000u - 42u); // 0.01f s = 39.99.. samples, rounded down, + 3
  cfg.warmup_s = 0.0f;
  cfg.start_at_rest = 1;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  k = 0;
  feed(&s, 4000, k);
  ASSERT_EQ(imest_background(&s, &r), 1);
  EXPECT_EQ(r.used_samples, 4000u);
}
