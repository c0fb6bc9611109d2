/* SPDX-License-Identifier: Apache-2.0 */
// Robustness of the whole public path (imest_isr_abc -> imest_background)
// against bad samples and hard operating conditions, on realistic signals from
// the simulator (exp2 operating point in steady state, 12-bit sensors with
// 1 LSB noise, 4096-count encoder, window 0.5 s = 2000 samples at 4 kHz).
//
// For every fault the tests assert:
//   - the windows that contain it are invalid, with the expected status;
//   - no result is ever valid with a non-finite number or T_R / R_S outside
//     the configured bands (rig.hpp: expect_sane, applied to every result);
//   - the estimator recovers by itself: at most 2 windows after the window in
//     which the fault ends, every window is valid again with T_R within
//     kTolRel of the estimate before the fault.
//
// Denormal inputs (decision): a subnormal float is a finite number, ~0 for any
// sensor; it is not an input fault. Denormal currents/voltages are just "no
// current" (status no_current), a denormal angle is the angle 0.
#include <cfloat>
#include <cstdio>
#include <limits>
#include <random>

#include "rig.hpp"

using namespace rob;

namespace {

constexpr double kTolRel = 0.01; // 1 %: window-to-window spread of T_R here is ~0.2 %
constexpr int kMaxRecovery = 2;  // windows after the one in which the fault ends
const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
const float kDenorm = 1.0e-40f; // subnormal float32
constexpr float k2Pi = 6.2831853f;

float wrap(float th)
{
  th = std::fmod(th, k2Pi);
  return th < 0 ? th + k2Pi : th;
}

// Mean T_R of the valid windows in [first, last].
double mean_tr(const Rig &r, uint32_t first, uint32_t last)
{
  double s = 0;
  int n = 0;
  for (const auto &w : r.res)
    if (w.seq >= first && w.seq <= last && w.valid) {
      s += w.tr_s;
      ++n;
    }
  return n ? s / n : std::nan("");
}

// Asserts the pattern described at the top of the file. Windows
// [fault_first, fault_last] contain the fault; `expect` is their status
// (0: any invalid status). Returns the number of windows after fault_last
// until the first valid one (recovery), and prints it with the estimates.
// strict = false: only the first recovery is checked, not that every later
// window is valid (see DISABLED_IfocLoadedSteadyStateEveryWindowValid).
int check_fault(const Rig &r, const char *name, uint32_t fault_first, uint32_t fault_last, int expect,
                double pre_tr, bool strict = true)
{
  SCOPED_TRACE(name);
  EXPECT_TRUE(std::isfinite(pre_tr)) << r.dump();
  for (uint32_t k = fault_first; k <= fault_last; ++k) {
    const imest_result_t *w = r.window(k);
    if (w == nullptr) continue; // dropped (overrun)
    EXPECT_FALSE(w->valid) << "window " << k << "\n" << r.dump();
    if (expect != 0)
      EXPECT_EQ(w->status, expect) << "window " << k << " is " << imest_reason_name(w->status) << "\n"
                                   << r.dump();
  }
  int recovery = -1;
  double tr_after = std::nan("");
  for (const auto &w : r.res) {
    if (w.seq <= fault_last) continue;
    const int after = (int)(w.seq - fault_last);
    if (recovery < 0 && w.valid) {
      recovery = after;
      tr_after = w.tr_s;
    }
    if (strict && after >= kMaxRecovery) {
      EXPECT_TRUE(w.valid) << "window " << w.seq << " (" << after << " after the fault) is "
                           << imest_reason_name(w.status) << "\n"
                           << r.dump();
    }
    if (w.valid) EXPECT_NEAR(w.tr_s, pre_tr, kTolRel * pre_tr) << "window " << w.seq << "\n" << r.dump();
  }
  EXPECT_GE(recovery, 1) << r.dump();
  EXPECT_LE(recovery, kMaxRecovery) << r.dump();
  std::printf("[ robust   ] %-44s status %-17s recovery %d window(s), T_R %.5f -> %.5f s\n", name,
              r.window(fault_first) ? imest_reason_name(r.window(fault_first)->status) : "(dropped)",
              recovery, pre_tr, tr_after);
  return recovery;
}

enum Chan { kCurrent, kVoltage, kAngle };
const char *chan_name(Chan c)
{
  return c == kCurrent ? "current" : c == kVoltage ? "voltage" : "angle";
}
void put(Sample &s, Chan c, float v)
{
  if (c == kCurrent)
    s.i[1] = v;
  else if (c == kVoltage)
    s.u[2] = v;
  else
    s.theta = v;
}

// Three clean windows, then a burst of `len` corrupted samples starting at
// position `pos` of window 3, then clean windows up to window 8.
void bad_value_case(Chan c, float v, int expect, int pos = 700, int len = 3)
{
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  const long at = 3L * r.window_n + pos;
  r.run(6, [&](Sample &s) {
    if (s.n >= at && s.n < at + len) put(s, c, v);
  });
  const uint32_t last = (uint32_t)((at + len - 1) / r.window_n);
  char name[96];
  std::snprintf(name, sizeof name, "%s = %g x%d", chan_name(c), (double)v, len);
  check_fault(r, name, 3, last, expect, pre);
  const imest_result_t *w = r.window(3);
  ASSERT_NE(w, nullptr);
  // detected: the faulty samples and the filter restart after them are not accumulated
  if (expect != 0) EXPECT_LT(w->used_samples, r.window_n);
}

} // namespace

// ---------------------------------------------------------------------------
// NaN, Inf, huge values: input fault

TEST(RobustInput, NonFiniteSamplesAreInputFaults)
{
  for (Chan c : {kCurrent, kVoltage, kAngle})
    for (float v : {kNaN, kInf, -kInf}) bad_value_case(c, v, IMEST_REASON_INPUT_FAULT);
}

TEST(RobustInput, HugeSamplesAreInputFaults)
{
  // beyond i_absurd_a (1e4) / u_absurd_v (1e5) / the 1e8 rad angle bound
  for (float v : {1.0e30f, FLT_MAX, -FLT_MAX, 1.5e4f}) bad_value_case(kCurrent, v, IMEST_REASON_INPUT_FAULT);
  for (float v : {1.0e30f, FLT_MAX, -2.0e5f}) bad_value_case(kVoltage, v, IMEST_REASON_INPUT_FAULT);
  for (float v : {1.0e9f, -FLT_MAX, FLT_MAX}) bad_value_case(kAngle, v, IMEST_REASON_INPUT_FAULT);
}

// A single-sample spike below the absurd limits cannot be told from a real
// sample; it corrupts its window, which must then be invalid (the solve's
// quality indices catch it), and the next window is clean.
TEST(RobustInput, PlausibleSpikeInvalidatesOnlyItsWindow)
{
  for (float v : {20.0f, 1000.0f, 9999.0f}) bad_value_case(kCurrent, v, 0, 700, 1);
  for (float v : {1000.0f, 9.0e4f}) bad_value_case(kVoltage, v, 0, 700, 1);
}

// A fault in the last samples of a window: the filter restart (warm-up) spills
// into the next window (flagged warmup, fewer samples used). With the default
// warm-up (30 ms) that window may still be valid; with a warm-up longer than
// half a window (here 0.3 s of 0.5 s) it is invalid as warmup, and the one
// after is valid.
TEST(RobustInput, FaultAtWindowEndSpillsWarmupIntoNextWindow)
{
  for (float warmup_s : {0.0f, 0.3f}) {
    SCOPED_TRACE(warmup_s);
    Rig r;
    r.cfg.warmup_s = warmup_s;
    r.start();
    r.run(3);
    const double pre = mean_tr(r, 1, 2);
    r.run(6, [&](Sample &s) {
      if (s.window == 3 && s.pos == (int)r.window_n - 5) s.i[0] = kNaN;
    });
    const imest_result_t *w4 = r.window(4);
    ASSERT_NE(w4, nullptr);
    EXPECT_TRUE(w4->flags & IMEST_FLAG_WARMUP) << r.dump();
    EXPECT_LT(w4->used_samples, r.window_n);
    const int rec = check_fault(
        r, warmup_s > 0 ? "NaN at window end, warm-up 0.3 s" : "NaN at window end, default warm-up", 3, 3,
        IMEST_REASON_INPUT_FAULT, pre);
    if (warmup_s > 0) {
      EXPECT_EQ(w4->status, IMEST_REASON_WARMUP) << r.dump();
      EXPECT_EQ(rec, 2);
    }
  }
}

// A fault lasting longer than a window: every window it touches is invalid.
TEST(RobustInput, LongFaultBurstOverSeveralWindows)
{
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  const long from = 3L * r.window_n + 1500, to = 5L * r.window_n + 300;
  r.run(7, [&](Sample &s) {
    if (s.n >= from && s.n < to) s.u[0] = kInf;
  });
  check_fault(r, "Inf voltage for 1.4 windows", 3, 5, IMEST_REASON_INPUT_FAULT, pre);
  ASSERT_NE(r.window(4), nullptr);
  EXPECT_EQ(r.window(4)->used_samples, 0u);
}

// ---------------------------------------------------------------------------
// Denormals

TEST(RobustDenormal, DenormalCurrentsAndVoltagesAreNoCurrent)
{
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  float th_hold = 0;
  // drive off for windows 3..5: every current and voltage is a denormal (of
  // either sign), the rotor stands still at the last angle
  r.run(8, [&](Sample &s) {
    if (s.window >= 3 && s.window <= 5) {
      if (s.window == 3 && s.pos == 0) th_hold = s.theta;
      for (int k = 0; k < 3; ++k) {
        s.i[k] = (s.n + k) % 2 ? kDenorm : -kDenorm * (float)(k + 1);
        s.u[k] = (s.n + k) % 3 ? -kDenorm : kDenorm;
      }
      s.theta = th_hold;
    }
  });
  for (uint32_t k = 3; k <= 5; ++k) {
    const imest_result_t *w = r.window(k);
    ASSERT_NE(w, nullptr);
    EXPECT_FALSE(w->flags & IMEST_FLAG_INPUT_FAULT) << k;
    if (k >= 4) EXPECT_EQ(w->status, IMEST_REASON_NO_CURRENT) << k << "\n" << r.dump();
  }
  // window 3 holds the switch-off (a step no fault check can see), window 6
  // the switch-on: both invalid, whatever the reason
  check_fault(r, "denormal u, i (drive off) 3 windows", 3, 6, 0, pre);
}

// A denormal angle is the angle 0: replacing every exact 0 of the encoder by a
// denormal changes nothing.
TEST(RobustDenormal, DenormalAngleIsZero)
{
  Rig a, b;
  a.start();
  b.start();
  a.run(5);
  int replaced = 0;
  b.run(5, [&](Sample &s) {
    if (s.theta == 0.0f) {
      s.theta = kDenorm;
      ++replaced;
    }
  });
  EXPECT_GE(replaced, 1);
  ASSERT_EQ(a.res.size(), b.res.size());
  for (size_t k = 0; k < a.res.size(); ++k) {
    EXPECT_EQ(a.res[k].status, b.res[k].status);
    EXPECT_EQ(a.res[k].flags, b.res[k].flags);
    if (a.res[k].valid) EXPECT_NEAR(a.res[k].tr_s, b.res[k].tr_s, 1e-6 * a.res[k].tr_s);
  }
  // at standstill at angle 0 (DC excitation) every sample is 0: alternate
  // +-denormal; still standstill, no encoder or input fault
  Rig c;
  c.sc.freq_hz = 0.0;
  c.sc.vll_v = 20.0;
  c.sc.load_nm = 0.0;
  c.start();
  c.run(4, [&](Sample &s) {
    ASSERT_EQ(s.theta, 0.0f);
    s.theta = s.n % 2 ? kDenorm : -kDenorm;
  });
  for (const auto &w : c.res) {
    EXPECT_FALSE(w.flags & (IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ENCODER_FAULT));
    if (w.seq > 1) EXPECT_EQ(w.status, IMEST_REASON_STANDSTILL) << c.dump(); // 0, 1: first-start warm-up
  }
}

// ---------------------------------------------------------------------------
// ADC saturation

// Current: the sensor range is 3 A (rated-load phase peak 2.3 A); a 1 s
// overload at 1.6x rated torque drives the current into the ADC limit. The
// simulator clips exactly like the ADC (top code), and i_limit_a is that code.
TEST(RobustSaturation, CurrentClippedByTheAdcDuringAnOverload)
{
  Rig r;
  r.sc.i_range_a = 3.0;
  const double lsb = 2.0 * r.sc.i_range_a / 4096.0;
  r.cfg.i_limit_a = (float)(r.sc.i_range_a - lsb);
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  const long on = 3L * r.window_n + 500, off = on + 4000;
  long clipped = 0;
  r.run(
      7,
      [&](Sample &s) {
        for (int k = 0; k < 3; ++k) clipped += std::fabs(s.i[k]) >= r.cfg.i_limit_a;
      },
      [&](long n) {
        if (n == on) imsim_set_load(&r.sim, 1.6 * 2.064);
        if (n == off) imsim_set_load(&r.sim, 2.064);
      });
  EXPECT_GT(clipped, 100);
  // the overload samples end at window 5 (position 500): windows 3..5 clip
  check_fault(r, "current ADC clipped (1 s overload)", 3, 5, IMEST_REASON_ADC_SATURATION, pre);
}

// Voltage: a sensor offset burst pushes the voltage channel into its limit.
TEST(RobustSaturation, VoltageClippedAtTheLimit)
{
  Rig r;
  r.cfg.u_limit_v = 120.0f; // phase peak of exp2 is ~94 V
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(6, [&](Sample &s) {
    if (s.window == 3 && s.pos >= 600 && s.pos < 900) s.u[0] = std::fmin(s.u[0] + 60.0f, r.cfg.u_limit_v);
  });
  check_fault(r, "voltage offset burst clipped", 3, 3, IMEST_REASON_ADC_SATURATION, pre);
}

// ---------------------------------------------------------------------------
// Encoder

TEST(RobustEncoder, GlitchBurstIsAnEncoderFault)
{
  // 1000 wrong counts (1.53 rad) for 3 samples, then the right angle again
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(6, [&](Sample &s) {
    if (s.window == 3 && s.pos >= 300 && s.pos < 303) s.theta = wrap(s.theta + 1000 * k2Pi / 4096);
  });
  check_fault(r, "encoder glitch 1000 counts x3", 3, 3, IMEST_REASON_ENCODER_FAULT, pre);
}

TEST(RobustEncoder, OffsetJumpIsAnEncoderFaultThenSameEstimate)
{
  // the angle jumps by 1 rad and keeps the offset (lost index pulse): the
  // model is rotation invariant, so T_R after the jump equals T_R before
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(6, [&](Sample &s) {
    if (s.n >= 3L * r.window_n + 250) s.theta = wrap(s.theta + 1.0f);
  });
  check_fault(r, "encoder offset jump 1 rad", 3, 3, IMEST_REASON_ENCODER_FAULT, pre);
}

TEST(RobustEncoder, SubThresholdGlitchInvalidatesOnlyItsWindow)
{
  // 400 counts (0.61 rad) in one sample: 2450 rad/s, below the 3000 rad/s
  // speed limit, so not detectable per sample; the window must not be valid
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(6, [&](Sample &s) {
    if (s.window == 3 && s.pos == 300) s.theta = wrap(s.theta + 400 * k2Pi / 4096);
  });
  check_fault(r, "encoder glitch 400 counts x1 (undetectable)", 3, 3, 0, pre);
}

TEST(RobustEncoder, OneCountGlitchesDoNotMatter)
{
  // an encoder that bounces by +-1 count now and then stays valid
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(4, [&](Sample &s) {
    if (s.window >= 3 && s.pos % 97 == 0)
      s.theta = wrap(s.theta + ((s.pos / 97) % 2 ? 1.0f : -1.0f) * k2Pi / 4096);
  });
  for (uint32_t k = 3; k <= 6; ++k) {
    ASSERT_NE(r.window(k), nullptr);
    EXPECT_TRUE(r.window(k)->valid) << r.dump();
    EXPECT_NEAR(r.window(k)->tr_s, pre, kTolRel * pre);
  }
}

// ---------------------------------------------------------------------------
// Operating conditions where T_R is not identifiable

// DC at standstill (supply at 0 Hz, line-line voltage vll_v): no rotor
// currents, every window after the first-start warm-up (windows 0, 1) is
// standstill.
static void expect_standstill_with_dc(double vll_v)
{
  Rig r;
  r.sc.freq_hz = 0.0;
  r.sc.vll_v = vll_v;
  r.sc.load_nm = 0.0;
  r.start();
  r.run(5);
  for (uint32_t k = 2; k < 5; ++k) {
    ASSERT_NE(r.window(k), nullptr);
    EXPECT_EQ(r.window(k)->status, IMEST_REASON_STANDSTILL) << r.dump();
  }
}

// DC magnetisation at standstill: i_rms ~4 A.
TEST(RobustCondition, StandstillWithDcExcitation)
{
  expect_standstill_with_dc(20.0);
}

// DC at the magnetising current of this motor (i_rms ~2 A, 12-bit sensors):
// the old slip measure (rms current rate) read ~0.07 from noise alone and the
// window came out no_root; the rotation-rate measure reads ~0 -> standstill.
TEST(RobustCondition, StandstillAtMagnetisingCurrent)
{
  expect_standstill_with_dc(10.0);
}

// Field-oriented drive magnetised at rest (speed reference 0): the encoder
// dithers by one count, then the drive accelerates to 850 rpm with rated
// load: valid within 2 windows.
TEST(RobustCondition, StandstillThenRunUnderIfoc)
{
  Rig ref;
  ref.start();
  ref.run(3);
  const double pre = mean_tr(ref, 1, 2);
  Rig r;
  r.sc.supply = IMSIM_SUPPLY_IFOC;
  r.sc.start = IMSIM_START_REST;
  r.sc.ifoc_ideal_stage = true;
  r.sc.speed_ref_rpm = 0.0;
  r.sc.load_on_s = 1e9;
  r.start();
  r.run(9, nullptr, [&](long n) {
    if (n == 4L * r.window_n) {
      imsim_set_speed_ref(&r.sim, 850.0);
      imsim_set_load(&r.sim, 2.064);
    }
  });
  // windows 0..2 hold the flux build-up, 3 is magnetised at rest
  check_fault(r, "IFOC magnetised at rest, then run", 0, 3, 0, pre, /*strict=*/false);
}

// FINDING (reported to the lead): in IFOC loaded steady state (ideal voltage
// stage, 850 rpm, rated load, window 0.5 s) about one window in four selects
// the spurious stationary point T_R ~ 5.7 ms, R_S ~ 27 ohm (roots 0.1189,
// 0.0628, 0.00566 s, all admissible; src/estimator/solve/bg_select.c keeps the least E) and is
// then reported poorly_determined: never a wrong valid result, but lost
// windows. The V/f supply at the same operating point loses none (40 of 40
// valid). Enable when the selection prefers the well-determined minimum.
TEST(RobustCondition, IfocLoadedSteadyStateEveryWindowValid)
{
  Rig r;
  r.sc.supply = IMSIM_SUPPLY_IFOC;
  r.sc.start = IMSIM_START_REST;
  r.sc.ifoc_ideal_stage = true;
  r.sc.load_on_s = 1.0;
  r.sc.load_ramp_s = 0.5;
  r.start();
  r.run(20);
  for (const auto &w : r.res)
    if (w.seq >= 5) EXPECT_TRUE(w.valid) << r.dump();
}

// At rest under IFOC the encoder toggles by one count (1.5 mrad = 6 rad/s for
// one sample); the standstill test uses the window's mean speed, in which
// that averages to zero (an rms speed measure called it zero_slip).
TEST(RobustCondition, IfocAtRestIsStandstill)
{
  Rig r;
  r.sc.supply = IMSIM_SUPPLY_IFOC;
  r.sc.start = IMSIM_START_REST;
  r.sc.ifoc_ideal_stage = true;
  r.sc.speed_ref_rpm = 0.0;
  r.sc.load_on_s = 1e9;
  r.start();
  r.run(4);
  ASSERT_NE(r.window(3), nullptr);
  EXPECT_EQ(r.window(3)->status, IMEST_REASON_STANDSTILL) << r.dump();
}

// Drive disabled for 2 s: zero voltage, the current sensors read ADC noise
// around 0, the rotor coasts; then re-enabled.
TEST(RobustCondition, NoCurrentThenReenabled)
{
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const float lsb = 40.0f / 4096.0f;
  r.run(10, [&](Sample &s) {
    if (s.window >= 3 && s.window <= 6) {
      for (int k = 0; k < 3; ++k) {
        s.i[k] = std::round(noise(rng)) * lsb;
        s.u[k] = 0.0f;
      }
    }
  });
  for (uint32_t k = 4; k <= 6; ++k) {
    ASSERT_NE(r.window(k), nullptr);
    EXPECT_EQ(r.window(k)->status, IMEST_REASON_NO_CURRENT) << r.dump();
  }
  check_fault(r, "no current (drive off 2 s)", 3, 7, 0, pre);
}

// No load at constant speed: slip ~0, T_R unobservable; then rated load.
TEST(RobustCondition, ZeroSlipThenLoad)
{
  Rig ref;
  ref.start();
  ref.run(3);
  const double pre = mean_tr(ref, 1, 2);
  Rig r(0.5f, 0.0);
  r.start();
  r.run(8, nullptr, [&](long n) {
    if (n == 4L * r.window_n) imsim_set_load(&r.sim, 2.064);
  });
  // windows 0, 1: first-start warm-up
  check_fault(r, "zero slip (no load), then rated load", 2, 3, IMEST_REASON_ZERO_SLIP, pre);
}

// ---------------------------------------------------------------------------
// Overrun: the background does not run for 3 windows

TEST(RobustOverrun, StarvedBackgroundDropsWindowsAndRecovers)
{
  Rig r;
  r.start();
  r.run(3);
  const double pre = mean_tr(r, 1, 2);
  r.run(7, [&](Sample &s) {
    if (s.window >= 3 && s.window <= 5) s.call_background = false;
  });
  // window 3 was handed over and waits; 4 and 5 are dropped; 6 carries the flag
  EXPECT_EQ(imest_overruns(&r.est), 2u);
  EXPECT_EQ(r.window(4), nullptr);
  EXPECT_EQ(r.window(5), nullptr);
  ASSERT_NE(r.window(3), nullptr);
  EXPECT_TRUE(r.window(3)->valid) << r.dump();
  ASSERT_NE(r.window(6), nullptr);
  EXPECT_TRUE(r.window(6)->flags & IMEST_FLAG_OVERRUN);
  EXPECT_EQ(r.window(6)->overruns, 2u);
  check_fault(r, "background starved 3 windows", 4, 5, 0, pre);
}

// ---------------------------------------------------------------------------
// Band: never a valid T_R outside [tr_min_s, tr_max_s] (T_R here is 0.119 s)

TEST(RobustBand, NoValidResultOutsideTheTrBand)
{
  for (auto band : {std::pair<float, float>{0.13f, 10.0f}, std::pair<float, float>{1e-3f, 0.11f}}) {
    Rig r;
    r.cfg.tr_min_s = band.first;
    r.cfg.tr_max_s = band.second;
    r.start();
    r.run(4);
    ASSERT_EQ(r.res.size(), 4u);
    // expect_sane checks that every finite T_R reported is inside the band;
    // outside [0.13, 10] no candidate is left (no_root); inside [1e-3, 0.11]
    // only the spurious T_R ~ 5.6 ms, which is poorly determined
    for (const auto &w : r.res) {
      EXPECT_FALSE(w.valid) << r.dump();
      if (!(w.flags & IMEST_FLAG_WARMUP)) {
        EXPECT_TRUE(w.status == IMEST_REASON_NO_ROOT || w.status == IMEST_REASON_POORLY_DETERMINED)
            << r.dump();
      }
    }
  }
}

// ---------------------------------------------------------------------------
// A storm of random faults (seeded): 1 % of the samples of windows 3..12 get
// an arbitrary value (NaN, Inf, huge, denormal, random) in a random channel.
// Every result is checked by expect_sane; afterwards the estimator recovers.

TEST(RobustStorm, RandomFaultsNeverGiveAWrongValidResult)
{
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    Rig r;
    r.start();
    r.run(3);
    const double pre = mean_tr(r, 1, 2);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    const float specials[] = {kNaN,    kInf,     -kInf, FLT_MAX, -FLT_MAX, 1e30f,
                              kDenorm, -kDenorm, 0.0f,  1e4f,    -1e5f,    1e8f};
    r.run(13, [&](Sample &s) {
      if (s.window < 3 || s.window > 12 || uni(rng) >= 0.01f) return;
      const int which = (int)(uni(rng) * 7.0f);
      float v = uni(rng) < 0.5f ? specials[(int)(uni(rng) * 12.0f) % 12]
                                : (uni(rng) - 0.5f) * std::pow(10.0f, uni(rng) * 12.0f - 3.0f);
      if (which < 3)
        s.i[which] = v;
      else if (which < 6)
        s.u[which - 3] = v;
      else
        s.theta = v;
    });
    check_fault(r, "random fault storm", 3, 12, 0, pre);
  }
}

// ---------------------------------------------------------------------------
// Sensor offsets

// Offsets of 100 mA (0.5 % of the +-20 A range, 6 % of this motor's current)
// and 1 V on the voltages: without the offset high-pass R_S comes out about
// 20 % high in windows that look valid; with it (the default) every window
// after the first-start warm-up is within the steady-state accuracy.
TEST(RobustSensor, OffsetsAreRemovedByDefault)
{
  for (float hz : {1.0f, 0.0f}) {
    SCOPED_TRACE(hz);
    Rig r;
    r.sc.i_offset_a[0] = 0.10;
    r.sc.i_offset_a[1] = -0.06;
    r.sc.i_offset_a[2] = 0.02;
    r.sc.u_offset_v[0] = 1.0;
    r.sc.u_offset_v[1] = -0.5;
    r.sc.u_offset_v[2] = 0.3;
    r.cfg.dc_block_hz = hz;
    r.start();
    r.run(6);
    double worst_rs = 0, worst_tr = 0;
    int valid = 0;
    for (const auto &w : r.res) {
      if (w.seq <= 1 || !w.valid) continue; // 0, 1: first-start warm-up
      ++valid;
      worst_tr = std::max(worst_tr, std::fabs(w.tr_s / 0.12 - 1));
      worst_rs = std::max(worst_rs, std::fabs(w.rs_ohm / 5.04 - 1));
    }
    if (hz > 0) {
      EXPECT_EQ(valid, 4) << r.dump();
      EXPECT_LT(worst_tr, 0.005) << r.dump();
      EXPECT_LT(worst_rs, 0.01) << r.dump();
    } else {
      EXPECT_GT(worst_rs, 0.05) << r.dump(); // what the default protects against
    }
  }
}
