/* SPDX-License-Identifier: Apache-2.0 */
// The T_R tracker (include/imest/imest_tracker.h): every rule of imest_tracker_update() on
// hand-made result sequences.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "imest/imest_tracker.h"

namespace {

constexpr float kNominal = 0.12f;
constexpr double kRate = 1e-3;       // the default rate limit [1/s]
constexpr double kFallback = 2.6e-4; // the default fall-back rate [1/s]: the rotor's cooling

imest_result_t result(double t_end_s, int tr_valid, double tr_s, double bound = 0.0005)
{
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  r.t_end_s = t_end_s;
  r.tr_valid = tr_valid;
  r.tr_s = tr_s;
  r.tr_bound_rel = bound;
  r.tr_reason = tr_valid ? IMEST_REASON_NONE : IMEST_REASON_ZERO_SLIP;
  return r;
}

struct Tracker : ::testing::Test {
  imest_tracker_config_t cfg{};
  imest_tracker_t t{};
  double now = 0.0;
  void SetUp() override
  {
    imest_tracker_config_default(&cfg, kNominal);
    ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  }
  int feed(int valid, double tr, double dt = 1.0, double bound = 0.0005)
  {
    now += dt;
    const imest_result_t r = result(now, valid, tr, bound);
    return imest_tracker_update(&t, &r);
  }
  // two agreeing valid windows: acquired at once (acquire_jump)
  void acquire(double tr)
  {
    ASSERT_EQ(feed(1, tr), 0);
    ASSERT_EQ(feed(1, tr), 1);
    ASSERT_EQ(t.state, IMEST_TRACKER_TRACKING);
    ASSERT_FLOAT_EQ(t.tr_s, static_cast<float>(tr));
  }
};

TEST_F(Tracker, DefaultsAndInit)
{
  EXPECT_FLOAT_EQ(cfg.tr_nominal_s, kNominal);
  EXPECT_FLOAT_EQ(cfg.rate_rel_per_s, 1e-3f);
  EXPECT_FLOAT_EQ(cfg.stale_after_s, 60.0f);
  EXPECT_FLOAT_EQ(cfg.fallback_rel_per_s, static_cast<float>(kFallback));
  EXPECT_FLOAT_EQ(cfg.nominal_bound_rel, 0.35f);
  EXPECT_FLOAT_EQ(cfg.gate_min_rel, 0.005f);
  EXPECT_EQ(cfg.confirm_windows, 2u);
  EXPECT_NE(cfg.acquire_jump, 0);
  EXPECT_FLOAT_EQ(t.tr_s, kNominal);
  EXPECT_FLOAT_EQ(t.tr_bound_rel, 0.35f);
  EXPECT_EQ(t.state, IMEST_TRACKER_NOMINAL);
  EXPECT_EQ(t.age_s, 0.0f);
  EXPECT_EQ(t.accepted + t.rejected + t.pending, 0u);
  // the default rate passes the fastest real heating (0.0043 /K x 10 K/min), not a 1 % jump per window
  EXPECT_GT(cfg.rate_rel_per_s, 0.0043f * 10.0f / 60.0f);
  EXPECT_LT(cfg.rate_rel_per_s * 1.0f, 0.01f);
  // the default fall-back is the fastest a rotor cools (0.0039 /K x 80 K rise / 1200 s), slower
  // than the rate limit
  EXPECT_NEAR(cfg.fallback_rel_per_s, 0.0039 * 80.0 / 1200.0, 1e-6);
  EXPECT_LT(cfg.fallback_rel_per_s, cfg.rate_rel_per_s);
}

TEST_F(Tracker, StateNames)
{
  EXPECT_STREQ(imest_tracker_state_name(IMEST_TRACKER_NOMINAL), "nominal");
  EXPECT_STREQ(imest_tracker_state_name(IMEST_TRACKER_TRACKING), "tracking");
  EXPECT_STREQ(imest_tracker_state_name(IMEST_TRACKER_HOLDING), "holding");
  EXPECT_STREQ(imest_tracker_state_name(IMEST_TRACKER_STALE), "stale");
  EXPECT_STREQ(imest_tracker_state_name(42), "unknown");
}

TEST_F(Tracker, BadConfigsRejected)
{
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  struct Case {
    const char *field;
    void (*set)(imest_tracker_config_t *, float);
    float bad[4];
  };
  const Case cases[] = {
      {"tr_nominal_s",
       [](imest_tracker_config_t *c, float v) { c->tr_nominal_s = v; },
       {0.0f, -0.1f, nan, inf}},
      {"nominal_bound_rel",
       [](imest_tracker_config_t *c, float v) { c->nominal_bound_rel = v; },
       {-0.01f, 11.0f, nan, inf}},
      {"rate_rel_per_s",
       [](imest_tracker_config_t *c, float v) { c->rate_rel_per_s = v; },
       {0.0f, -1e-3f, 1.5f, nan}},
      {"stale_after_s",
       [](imest_tracker_config_t *c, float v) { c->stale_after_s = v; },
       {0.0f, -1.0f, nan, inf}},
      {"fallback_rel_per_s",
       [](imest_tracker_config_t *c, float v) { c->fallback_rel_per_s = v; },
       {-1e-4f, 1.5f, nan, inf}},
      {"gate_min_rel",
       [](imest_tracker_config_t *c, float v) { c->gate_min_rel = v; },
       {-0.001f, 1.0f, nan, inf}},
  };
  for (const Case &k : cases) {
    for (float v : k.bad) {
      imest_tracker_config_t c = cfg;
      k.set(&c, v);
      const char *field = nullptr;
      EXPECT_EQ(imest_tracker_config_check(&c, &field), IMEST_ERR_CONFIG) << k.field << " " << v;
      EXPECT_STREQ(field, k.field);
      imest_tracker_t u;
      std::memset(&u, 0x5a, sizeof u);
      EXPECT_EQ(imest_tracker_init(&u, &c), IMEST_ERR_CONFIG);
      unsigned char expect[sizeof u];
      std::memset(expect, 0x5a, sizeof expect);
      // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison): every byte, padding too, must be unwritten
      EXPECT_EQ(std::memcmp(&u, expect, sizeof u), 0) << "init changed the tracker on a bad config";
    }
  }
  for (unsigned int n : {0u, 17u}) {
    imest_tracker_config_t c = cfg;
    c.confirm_windows = n;
    const char *field = nullptr;
    EXPECT_EQ(imest_tracker_config_check(&c, &field), IMEST_ERR_CONFIG);
    EXPECT_STREQ(field, "confirm_windows");
  }
  const char *field = "x";
  EXPECT_EQ(imest_tracker_config_check(&cfg, &field), IMEST_OK);
  EXPECT_EQ(field, nullptr);
  EXPECT_EQ(imest_tracker_config_check(&cfg, nullptr), IMEST_OK);
}

TEST_F(Tracker, NullAndInvalidInputs)
{
  const imest_result_t r = result(1.0, 1, 0.1);
  EXPECT_EQ(imest_tracker_init(nullptr, &cfg), IMEST_ERR_NULL);
  EXPECT_EQ(imest_tracker_init(&t, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_tracker_update(nullptr, &r), IMEST_ERR_NULL);
  EXPECT_EQ(imest_tracker_update(&t, nullptr), IMEST_ERR_NULL);
  const char *field = nullptr;
  EXPECT_EQ(imest_tracker_config_check(nullptr, &field), IMEST_ERR_NULL);
  EXPECT_STREQ(field, "cfg");
  imest_tracker_config_default(nullptr, 0.1f); // no crash

  acquire(0.1);
  unsigned char before[sizeof t]; // its bytes, padding too (a struct copy need not copy padding)
  std::memcpy(before, &t, sizeof t);
  imest_result_t bad = result(std::numeric_limits<double>::quiet_NaN(), 1, 0.1);
  EXPECT_EQ(imest_tracker_update(&t, &bad), IMEST_ERR_ARG);
  bad.t_end_s = now - 0.5; // earlier than the previous result: the estimator was re-initialised
  EXPECT_EQ(imest_tracker_update(&t, &bad), IMEST_ERR_ARG);
  // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison): every byte, padding too, must be unwritten
  EXPECT_EQ(std::memcmp(before, &t, sizeof t), 0) << "a refused result changed the tracker";

  // valid verdict with an unusable number: counts as not valid
  EXPECT_EQ(feed(1, std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(feed(1, -0.1), 0);
  EXPECT_EQ(feed(1, 0.0), 0);
  EXPECT_EQ(t.state, IMEST_TRACKER_HOLDING);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
  EXPECT_EQ(t.rejected, 1u); // only the first window of the acquisition
}

TEST_F(Tracker, FirstWindowNeedsConfirmationThenJumps)
{
  EXPECT_EQ(feed(1, 0.095), 0);
  EXPECT_EQ(t.state, IMEST_TRACKER_NOMINAL);
  EXPECT_FLOAT_EQ(t.tr_s, kNominal);
  EXPECT_EQ(t.pending, 1u);
  EXPECT_EQ(feed(0, 0.3), 0); // a window that is not valid does not break the confirmation
  EXPECT_EQ(feed(1, 0.0951), 1);
  EXPECT_EQ(t.state, IMEST_TRACKER_TRACKING);
  EXPECT_FLOAT_EQ(t.tr_s, 0.0951f); // 21 % from the nominal at once
  EXPECT_EQ(t.accepted, 1u);
  EXPECT_EQ(t.pending, 0u);
  EXPECT_FLOAT_EQ(t.age_s, 0.0f);
  EXPECT_NEAR(t.tr_bound_rel, 0.0005, 1e-6);
}

TEST_F(Tracker, FirstWindowsThatDisagreeAreNotAcquired)
{
  EXPECT_EQ(feed(1, 0.095), 0);
  EXPECT_EQ(feed(1, 0.110), 0); // 16 % apart: the second starts a new confirmation
  EXPECT_EQ(t.state, IMEST_TRACKER_NOMINAL);
  EXPECT_EQ(t.pending, 1u);
  EXPECT_EQ(feed(1, 0.1101), 1);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1101f);
}

TEST_F(Tracker, AcquisitionWithoutJumpIsRateLimited)
{
  cfg.acquire_jump = 0;
  ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  feed(1, 0.1);
  EXPECT_EQ(feed(1, 0.1), 1);
  EXPECT_FLOAT_EQ(t.tr_s, kNominal * (1.0f - 1e-3f));
  // its bound says how far it is from the estimate it goes to
  EXPECT_NEAR(t.tr_bound_rel, (t.tr_s - 0.1 + 0.0005 * 0.1) / t.tr_s, 1e-5);
}

TEST_F(Tracker, HoldsThroughInvalidWindows)
{
  acquire(0.1);
  for (int k = 1; k <= 50; ++k) {
    EXPECT_EQ(feed(0, 0.5), 0); // a not-valid window's number is never used
    EXPECT_EQ(t.state, IMEST_TRACKER_HOLDING);
    EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
    EXPECT_FLOAT_EQ(t.age_s, static_cast<float>(k));
    // its bound grows with the drift the rate limit allows since
    EXPECT_NEAR(t.tr_bound_rel, 0.0005 + kRate * k, 1e-6);
  }
  EXPECT_EQ(t.accepted, 1u);
}

TEST_F(Tracker, AgeCounts)
{
  EXPECT_EQ(feed(0, 0.1, 2.5), 0);
  EXPECT_FLOAT_EQ(t.age_s, 2.5f); // no window accepted: the estimator's time
  acquire(0.1);
  EXPECT_FLOAT_EQ(t.age_s, 0.0f);
  feed(0, 0.1, 0.25);
  feed(0, 0.1, 3.0);
  EXPECT_FLOAT_EQ(t.age_s, 3.25f);
  feed(1, 0.1, 1.0); // accepted again
  EXPECT_FLOAT_EQ(t.age_s, 0.0f);
  feed(1, 0.2, 1.0); // an outlier: not accepted, the age goes on
  EXPECT_FLOAT_EQ(t.age_s, 1.0f);
  EXPECT_EQ(t.state, IMEST_TRACKER_HOLDING);
}

TEST_F(Tracker, IgnoresASingleOutlier)
{
  acquire(0.1);
  for (int k = 0; k < 5; ++k) ASSERT_EQ(feed(1, 0.1), 1);
  EXPECT_EQ(feed(1, 0.13), 0); // a window whose verdict was wrong
  EXPECT_EQ(t.state, IMEST_TRACKER_HOLDING);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
  EXPECT_EQ(t.rejected, 2u); // with the acquisition's first window
  EXPECT_EQ(feed(1, 0.1), 1);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
  EXPECT_EQ(t.state, IMEST_TRACKER_TRACKING);
  // an outlier below, then one above: neither confirms the other
  EXPECT_EQ(feed(1, 0.07), 0);
  EXPECT_EQ(feed(1, 0.14), 0);
  EXPECT_EQ(feed(1, 0.1), 1);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
}

TEST_F(Tracker, ConfirmedStepIsRateLimited)
{
  acquire(0.1);
  EXPECT_EQ(feed(1, 0.105), 0); // 5 % at once: awaits confirmation
  EXPECT_EQ(feed(1, 0.105), 1); // confirmed: the goal, reached at the rate limit only
  float prev = t.tr_s;
  EXPECT_NEAR(prev, 0.1 * (1.0 + kRate), 1e-7);
  int steps = 1;
  while (t.tr_s < 0.105f && steps < 1000) {
    ASSERT_EQ(feed(1, 0.105), 1);
    // at most the rate limit, to float32 rounding of the value (an ulp of 0.1 is 7.5e-9)
    EXPECT_LE(static_cast<double>(t.tr_s) - prev, kRate * prev + 1.5e-8);
    EXPECT_EQ(t.state, IMEST_TRACKER_TRACKING);
    prev = t.tr_s;
    ++steps;
  }
  EXPECT_FLOAT_EQ(t.tr_s, 0.105f);
  // ln(1.05) / ln(1.001) = 48.8 windows of 1 s
  EXPECT_EQ(steps, 49);
}

TEST_F(Tracker, StepDownIsRateLimitedToo)
{
  acquire(0.1);
  feed(1, 0.09);
  EXPECT_EQ(feed(1, 0.09), 1);
  EXPECT_NEAR(t.tr_s, 0.1 * (1.0 - kRate), 1e-7);
  feed(0, 0.0, 10.0); // holding: goes on towards the accepted value, 10 s worth
  EXPECT_NEAR(t.tr_s, 0.1 * (1.0 - kRate) * (1.0 - 10 * kRate), 1e-7);
  EXPECT_EQ(t.state, IMEST_TRACKER_HOLDING);
}

// A rotor warming: T_R falls at a rate (relative per second); windows carry +-0.02 % of noise.
double ramp(double t, double rate)
{
  return 0.12 * std::exp(-rate * t);
}

TEST_F(Tracker, FollowsARealThermalRampWithoutLag)
{
  const double rate = 7.2e-4; // the fastest real heating (0.0043 /K x 10 K/min)
  double worst = 0.0;
  for (int k = 1; k <= 600; ++k) {
    const double truth = ramp(now + 1.0, rate), noise = 2e-4 * ((k % 3) - 1);
    feed(1, truth * (1.0 + noise));
    if (k > 2) {
      EXPECT_EQ(t.state, IMEST_TRACKER_TRACKING) << k;
      worst = std::fmax(worst, std::fabs(t.tr_s / truth - 1.0));
    }
  }
  EXPECT_LT(worst, 2.5e-4);         // the noise, no lag
  EXPECT_LT(t.tr_s, 0.12f * 0.66f); // and it went down 35 %
}

TEST_F(Tracker, RampFasterThanTheLimitLagsByTheRateOnly)
{
  const double rate = 3e-3; // faster than any rotor heats: the tracker moves at its limit
  acquire(0.12);
  float prev = t.tr_s;
  for (int k = 1; k <= 100; ++k) {
    ASSERT_EQ(feed(1, 0.12 * std::exp(-rate * k)), 1) << k; // each window agrees with the last
    EXPECT_NEAR(t.tr_s / prev, 1.0 - kRate, 1e-6) << k;
    prev = t.tr_s;
  }
}

// Falls back from 0.09 s to the nominal once stale, at the configured fall-back rate: returns the
// number of 1-s steps after the first stale one until tr_s is on the nominal.
int stale_fallback_steps(Tracker &f, double rate)
{
  f.acquire(0.09);
  for (int k = 1; k <= 60; ++k) {
    f.feed(0, 0.0);
    EXPECT_EQ(f.t.state, IMEST_TRACKER_HOLDING) << k;
    EXPECT_FLOAT_EQ(f.t.tr_s, 0.09f);
  }
  f.feed(0, 0.0); // 61 s: stale
  EXPECT_EQ(f.t.state, IMEST_TRACKER_STALE);
  EXPECT_NEAR(f.t.tr_s, 0.09 * (1.0 + rate), 1e-7);
  int k = 0;
  float prev = f.t.tr_s;
  while (f.t.tr_s < kNominal && k < 10000) {
    f.feed(0, 0.0);
    EXPECT_EQ(f.t.state, IMEST_TRACKER_STALE);
    // never faster than the configured rate (to float32 rounding of the value)
    EXPECT_LE(static_cast<double>(f.t.tr_s) - prev, rate * prev + 1.5e-8) << k;
    prev = f.t.tr_s;
    ++k;
  }
  EXPECT_FLOAT_EQ(f.t.tr_s, kNominal);
  EXPECT_NEAR(f.t.tr_bound_rel, 0.35, 1e-6); // at the nominal: the nominal's bound
  f.feed(0, 0.0, 100.0);
  EXPECT_FLOAT_EQ(f.t.tr_s, kNominal);
  EXPECT_EQ(f.t.state, IMEST_TRACKER_STALE);
  return k;
}

// ln(0.12/0.09) / ln(1 + rate) steps of 1 s reach the nominal; the first was taken on going stale
int expected_steps(double rate)
{
  return static_cast<int>(std::ceil(std::log(0.12 / 0.09) / std::log1p(rate))) - 1;
}

TEST_F(Tracker, StaleFallsBackToNominalAtTheCoolingRate)
{
  const int k = stale_fallback_steps(*this, kFallback);
  EXPECT_EQ(k, expected_steps(kFallback)); // 1106.6 s at 2.6e-4 /s, less the first step
  EXPECT_EQ(k, 1106);
}

TEST_F(Tracker, StaleFallsBackAtTheRateLimitWhenConfigured)
{
  cfg.fallback_rel_per_s = cfg.rate_rel_per_s; // the fall-back of earlier versions
  ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  const int k = stale_fallback_steps(*this, kRate);
  EXPECT_EQ(k, expected_steps(kRate)); // 287.8 s at 1e-3 /s, less the first step
  EXPECT_EQ(k, 287);
}

TEST_F(Tracker, StaleFallbackRateIsItsOwn)
{
  cfg.fallback_rel_per_s = 5e-4f; // a small motor's cooling (10-min thermal time constant)
  ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  acquire(0.09);
  feed(0, 0.0, 61.0); // stale: 61 s at half the rate limit
  EXPECT_EQ(t.state, IMEST_TRACKER_STALE);
  EXPECT_NEAR(t.tr_s, 0.09 * (1.0 + 61 * 5e-4), 1e-7);
  cfg.fallback_rel_per_s = 0.0f; // hold, but say it is stale
  ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  now = 0.0;
  acquire(0.09);
  feed(0, 0.0, 500.0);
  EXPECT_EQ(t.state, IMEST_TRACKER_STALE);
  EXPECT_FLOAT_EQ(t.tr_s, 0.09f);
  EXPECT_NEAR(t.tr_bound_rel, 0.0005 + kRate * 500, 1e-6); // the drift allowed since
}

TEST_F(Tracker, StaleReacquiresWithConfirmationAndJumps)
{
  acquire(0.09);
  feed(0, 0.0, 200.0); // one late result: stale, and 200 s towards the nominal
  EXPECT_EQ(t.state, IMEST_TRACKER_STALE);
  EXPECT_NEAR(t.tr_s, 0.09 * (1.0 + 200 * kFallback), 1e-6);
  // a window within the (now wide) drift of the last accepted one still needs confirmation
  EXPECT_EQ(feed(1, 0.092), 0);
  EXPECT_EQ(t.state, IMEST_TRACKER_STALE);
  EXPECT_EQ(feed(1, 0.092), 1);
  EXPECT_EQ(t.state, IMEST_TRACKER_TRACKING);
  EXPECT_FLOAT_EQ(t.tr_s, 0.092f);
}

TEST_F(Tracker, ConfirmationExpires)
{
  acquire(0.1);
  EXPECT_EQ(feed(1, 0.2), 0);
  feed(0, 0.0, 30.0);
  // 61 s later: the old outlier no longer confirms anything, even though they agree
  EXPECT_EQ(feed(1, 0.2, 31.0), 0);
  EXPECT_EQ(t.pending, 1u);
}

TEST_F(Tracker, ConfirmWindowsOneAcceptsEveryValidWindow)
{
  cfg.confirm_windows = 1;
  ASSERT_EQ(imest_tracker_init(&t, &cfg), IMEST_OK);
  EXPECT_EQ(feed(1, 0.1), 1);
  EXPECT_FLOAT_EQ(t.tr_s, 0.1f);
  EXPECT_EQ(feed(1, 0.13), 1);                    // no outlier rejection
  EXPECT_NEAR(t.tr_s, 0.1 * (1.0 + kRate), 1e-7); // but still rate-limited
}

TEST_F(Tracker, NonFiniteBoundTakesTheFloor)
{
  acquire(0.1);
  EXPECT_EQ(feed(1, 0.1, 1.0, std::numeric_limits<double>::quiet_NaN()), 1);
  EXPECT_NEAR(t.tr_bound_rel, 0.005, 1e-7);
  // and the agreement test: 0.55 % off is inside 0.5 % + 0.1 % drift, 0.7 % is not
  EXPECT_EQ(feed(1, 0.1 * 1.0055, 1.0, 0.0), 1);
  EXPECT_EQ(feed(1, 0.1 * 1.0055 * 1.007, 1.0, 0.0), 0);
}

} // namespace
