/* SPDX-License-Identifier: Apache-2.0 */
// Verdicts against the simulator's truth. The systematic error bounds: at rated speed
// and light load the PWM staircase's aliased current moves T_R (and R_S) on
// a small motor without raising any statistical index; the bound must refuse
// those windows (tr_uncertain), while at rated load T_R stays valid.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "tool_run.hpp"

using namespace tool_run;

namespace {
// The paper's 0.37 kW motor on a 340 V bus, 60 Hz, 8 kHz PWM and samples,
// ideal sensors (the bias is systematic, not noise), phase voltages (the
// period's volt-seconds, half a sample behind the currents).
const std::string kSim =
    "--preset 4kw --pole-pairs 2 --ls 0.2908 --lr 0.2908 --sigma 0.096 --rs 5.04 --tr 0.12 "
    "--j 1.2e-3 --b 1e-4 --i-range 6 --u-range 250 --no-thermal --start steady --vdc 340 "
    "--freq 60 --vll 230 --duration 4 --ideal-sensors --encoder-counts 16384 --no-progress";
const std::string kReplay = " --pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 "
                            "--sigma-uncertainty 0 --from-rest no --u-delay 62.5e-6 ";

struct Tally {
  int windows = 0, tr_valid = 0, tr_valid_wrong = 0, tr_uncertain = 0;
};

Tally tally(const std::string &csv, const std::string &extra = "")
{
  const Out o = run(std::string(REPLAY_BIN) + kReplay + extra + " " + csv);
  EXPECT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int tr = col(r, "T_R_s"), v = col(r, "tr_valid"), why = col(r, "tr_reason");
  Tally t;
  for (size_t k = 2; k < r.size(); ++k) { // the first window is warm-up
    ++t.windows;
    const bool valid = r[k][v] == "1";
    t.tr_valid += valid;
    t.tr_valid_wrong += valid && std::fabs(std::stod(r[k][tr]) / 0.12 - 1.0) > 0.02;
    t.tr_uncertain += r[k][why] == "tr_uncertain";
  }
  return t;
}
} // namespace

TEST(ReplayBounds, LightLoadAtRatedSpeedIsTrUncertainNotWrong)
{
  // 10 % load: T_R +7 %, R_S -15 % (pe_k2_rel 0.01) before the bound
  const Tally t = tally(sim_csv("bounds_l10.csv", kSim + " --load-nm 0.2064"));
  EXPECT_GE(t.windows, 2);
  EXPECT_EQ(t.tr_valid_wrong, 0);
  EXPECT_EQ(t.tr_uncertain, t.windows);
}

TEST(ReplayBounds, RatedLoadKeepsTrValid)
{
  const Tally t = tally(sim_csv("bounds_l100.csv", kSim + " --load-nm 2.064"));
  EXPECT_GE(t.windows, 2);
  EXPECT_EQ(t.tr_valid, t.windows);
  EXPECT_EQ(t.tr_valid_wrong, 0);
}

TEST(ReplayBounds, ToleranceIsTheUsersToWiden)
{
  // with --tr-tolerance 0.2 the light-load windows pass again: the refusal
  // comes from the bound, not from another check
  const Tally t = tally(sim_csv("bounds_l10.csv", kSim + " --load-nm 0.2064"), "--tr-tolerance 0.2");
  EXPECT_EQ(t.tr_uncertain, 0);
  EXPECT_GE(t.tr_valid, 1);
}

// 11 kW at 80 % of rated speed, 75 % load, 12-bit sensors: the true T_R
// (0.476 s) is far from the default nominal 0.1 s that the first windows are
// centred on. The noise compensation then leaves the root's E below zero by
// the noise's bias at the root, which the bias at the centring does not
// bound: every window was no_root. Now T_R is valid and right from the second
// window on.
TEST(ReplayBounds, FarCentringStillFindsTheRoot)
{
  const std::string &csv =
      sim_csv("11kw_f80.csv", "--preset 11kw --no-thermal --start steady --vdc 560 --freq 40 "
                              "--vll 312 --load-nm 54 --duration 4 --encoder-counts 16384 "
                              "--no-progress");
  const Out o = run(std::string(REPLAY_BIN) +
                    " --pole-pairs 2 --ls 0.078331 --sigma 0.05518 --ls-uncertainty 0 --sigma-uncertainty 0 "
                    "--from-rest no " +
                    "--u-delay 62.5e-6 " + csv);
  ASSERT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int tr = col(r, "T_R_s"), v = col(r, "tr_valid");
  const auto truth = rows(slurp(csv));
  const double tr_true = std::stod(truth[1][col(truth, "T_R_true_s")]);
  int valid = 0;
  for (size_t k = 2; k < r.size(); ++k) {
    if (r[k][v] != "1") continue;
    ++valid;
    EXPECT_NEAR(std::stod(r[k][tr]) / tr_true, 1.0, 0.01) << o.out;
  }
  EXPECT_GE(valid, 2) << o.out;
}

// Window combination (docs/METHOD.md): the paper motor at 9 Hz and 25 % load
// with 12-bit sensors has too little information in one window
// (pe_k2_rel ~0.24 against 0.1); combined windows deliver T_R, with a slower

// The paper's motor at 9 Hz and 25 % load, 12-bit sensors: one window is poorly determined
// alone (the combined-window tests below).
static const std::string &paper_9hz_l25()
{
  return sim_csv("paper_9hz_l25.csv", "--preset 4kw --pole-pairs 2 --ls 0.2908 --lr 0.2908 "
                                      "--sigma 0.096 --rs 5.04 --tr 0.12 --j 1.2e-3 --b 1e-4 "
                                      "--i-range 6 --u-range 250 --no-thermal --start steady "
                                      "--vdc 340 --freq 9 --vll 34.5 --load-nm 0.516 --duration 12 "
                                      "--encoder-counts 16384 --no-progress");
}

// update, and say so (windows > 1, span_s).
TEST(ReplayBounds, CombinedWindowsDeliverTrWhereOneWindowCannot)
{
  const std::string &csv = paper_9hz_l25();
  const Out o = run(std::string(REPLAY_BIN) + kReplay + csv);
  ASSERT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int tr = col(r, "T_R_s"), v = col(r, "tr_valid"), n = col(r, "windows"), span = col(r, "span_s");
  int combined_valid = 0;
  for (size_t k = 2; k < r.size(); ++k) {
    if (r[k][v] != "1") continue;
    EXPECT_GT(std::stoi(r[k][n]), 1) << "a single window was valid: " << o.out;
    EXPECT_GT(std::stod(r[k][span]), 1.5);
    EXPECT_NEAR(std::stod(r[k][tr]) / 0.12, 1.0, 0.01) << o.out;
    ++combined_valid;
  }
  EXPECT_GE(combined_valid, 1) << o.out;
}

// The same record with the core built without window combination
// (IMEST_COMBINE=OFF): every window stands alone, and none of them is valid
// (each is poorly determined alone), so leaving the stage out costs exactly
// the combined windows above and gives no wrong T_R instead.
TEST(ReplayBounds, WithoutCombinationLightLoadWindowsStayAlone)
{
  const std::string &csv = paper_9hz_l25();
  const Out o = run(std::string(REPLAY_NOCOMBINE_BIN) + kReplay + csv);
  ASSERT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int v = col(r, "tr_valid"), n = col(r, "windows"), why = col(r, "tr_reason");
  int poorly = 0;
  ASSERT_GE(r.size(), 10u) << o.out;
  for (size_t k = 1; k < r.size(); ++k) {
    EXPECT_EQ(r[k][n], "1") << o.out;
    EXPECT_EQ(r[k][v], "0") << o.out;
    poorly += r[k][why] == "poorly_determined" ? 1 : 0;
  }
  EXPECT_GE(poorly, 8) << o.out;
}

// A current sensor reading 2 % high (three sensors): the zero sequence shows
// it; R_S (-8 %) is refused as gain_mismatch, T_R stays valid and within 1 %.
TEST(ReplayBounds, GainMismatchRefusesRsNotTr)
{
  const std::string &csv =
      sim_csv("exp2_gain.csv", "--preset exp2 --duration 6 --supply vf --seed 5 --i-gain-err 0.02,0,0");
  const Out o =
      run(std::string(REPLAY_BIN) +
          " --pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0 " + csv);
  ASSERT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int tr = col(r, "T_R_s"), tv = col(r, "tr_valid"), rv = col(r, "rs_valid"), why = col(r, "rs_reason");
  int tr_ok = 0;
  for (size_t k = 1; k < r.size(); ++k) {
    EXPECT_EQ(r[k][rv], "0") << o.out;
    if (r[k][tv] != "1") continue;
    ++tr_ok;
    EXPECT_EQ(r[k][why], "gain_mismatch") << o.out;
    EXPECT_NEAR(std::stod(r[k][tr]) / 0.12, 1.0, 0.01) << o.out;
  }
  EXPECT_GE(tr_ok, 3) << o.out;
}

// The duty-cycle input on the 2.2 kW motor of the dead-time table (560 V,
// 8 kHz, 1 V drops + slope, 12-bit sensors). T_R with the inverter model
// given: within 1 % wherever valid, refused otherwise (the inverter model's
// uncertainty bounds T_R too, and combined windows are not credited for an
// error that is the same in every window).
namespace {
const std::string kDuty22 =
    "--preset 4kw --pole-pairs 2 --ls 0.245 --lr 0.224 --sigma 0.085714 --rs 3.7 --tr 0.106667 "
    "--j 0.015 --b 9.7e-4 --i-range 18 --no-thermal --start steady --vdc 560 --duration 7 "
    "--encoder-counts 16384 --no-progress --v-switch 1 --r-switch 0.0727117 --v-diode 1 "
    "--r-diode 0.0727117 ";
const std::string kDutyReplay = " --pole-pairs 2 --ls 0.245 --sigma 0.085714 --ls-uncertainty 0 "
                                "--sigma-uncertainty 0 --from-rest no --voltage duty ";

struct DutyTally {
  int windows = 0, tr_valid = 0, tr_valid_off = 0, tr_uncertain = 0, combined_refused = 0;
};

// the smooth sign's band before it was each leg's own ripple: the ripple's peak at 50 % duty,
// V_dc / (8 sigma L_S f_pwm) (560 V, 21.0 mH, 8 kHz), for every leg
const std::string kOldBand = "--i-band 0.41667";

// model scale: the replay's inverter model is the simulator's times this
DutyTally duty_tally(const std::string &csv, double dead_s, double scale, const std::string &extra = "")
{
  char model[200];
  std::snprintf(model, sizeof model,
                "--dead-time %.6g --v-switch %.6g --r-switch %.6g --v-diode %.6g --r-diode %.6g ",
                dead_s * scale, scale, 0.0727117 * scale, scale, 0.0727117 * scale);
  const Out o = run(std::string(REPLAY_BIN) + kDutyReplay + model + extra + " " + csv);
  EXPECT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int tr = col(r, "T_R_s"), v = col(r, "tr_valid"), why = col(r, "tr_reason"), n = col(r, "windows");
  DutyTally t;
  for (size_t k = 3; k < r.size(); ++k) { // the first two windows: flux and speed settle
    ++t.windows;
    const bool valid = r[k][v] == "1";
    t.tr_valid += valid;
    t.tr_valid_off += valid && std::fabs(std::stod(r[k][tr]) / 0.106667 - 1.0) > 0.01;
    t.tr_uncertain += r[k][why] == "tr_uncertain";
    t.combined_refused += !valid && std::stoi(r[k][n]) > 1;
  }
  return t;
}
} // namespace

TEST(ReplayBounds, DutyInputLightLoadModelHighIsTrUncertainNotWrong)
{
  // 2 us, 25 % load, 30 Hz, the model 20 % high: T_R +2.2 % at pe_k2_rel 0.09
  // was valid before the inverter's uncertainty bounded T_R. With the smooth sign's old band (the
  // ripple's peak, fixed: --i-band) the bound is what refuses it; with each leg's own ripple as
  // the band T_R is -3.3 % at pe_k2_rel 0.11, poorly determined
  const std::string &csv = sim_csv(
      "duty22_dt2_l25.csv", kDuty22 + "--seed 5020 --freq 30 --vll 231.404 --load-nm 3.65 --dead-time 2e-6");
  const DutyTally t = duty_tally(csv, 2e-6, 1.2, kOldBand);
  EXPECT_GE(t.windows, 4);
  EXPECT_EQ(t.tr_valid_off, 0);
  EXPECT_GE(t.tr_uncertain, 1);
  const DutyTally d = duty_tally(csv, 2e-6, 1.2);
  EXPECT_EQ(d.tr_valid, 0);
}

TEST(ReplayBounds, DutyInputRatedLoadKeepsTrValid)
{
  const std::string &csv = sim_csv(
      "duty22_dt2_l100.csv", kDuty22 + "--seed 5026 --freq 30 --vll 256.946 --load-nm 14.6 --dead-time 2e-6");
  const DutyTally t = duty_tally(csv, 2e-6, 1.2);
  EXPECT_GE(t.windows, 4);
  EXPECT_GE(t.tr_valid, t.windows - 1);
  EXPECT_EQ(t.tr_valid_off, 0);
}

TEST(ReplayBounds, CombinedWindowsDoNotAverageAnInverterError)
{
  // 10 Hz, 25 % load, drops only, the model exact: one window is poorly
  // determined by the drops' harmonics, not by noise; four of them combined
  // gave T_R +4.8 % at pe_k2_rel 0.19 < 0.1 sqrt(4). That was the smooth sign's old band (the
  // ripple's peak, fixed: --i-band); with each leg's own ripple as the band a window is well
  // determined (T_R -0.4 to -0.8 %, pe_k2_rel 0.075) and nothing is combined
  const std::string &csv = sim_csv(
      "duty22_dt0_l25_f10.csv", kDuty22 + "--seed 5001 --freq 10 --vll 81.5191 --load-nm 3.65 --dead-time 0");
  const DutyTally t = duty_tally(csv, 0.0, 1.0, kOldBand);
  EXPECT_GE(t.windows, 4);
  EXPECT_EQ(t.tr_valid_off, 0);
  EXPECT_GE(t.combined_refused, 1);
}

TEST(ReplayBounds, DutyInputExactModelStatedCertainStillBoundsTr)
{
  // 1 us, 25 % load, 30 Hz, every number of the model exact and stated 3 %
  // uncertain (what commissioning reports): the zero crossings' shape is
  // still not the model's, and T_R was valid at +1.45 %
  const std::string &csv = sim_csv(
      "duty22_dt1_l25.csv", kDuty22 + "--seed 5011 --freq 30 --vll 228.335 --load-nm 3.65 --dead-time 1e-6");
  const DutyTally t = duty_tally(csv, 1e-6, 1.0, "--inverter-uncertainty 0.03");
  EXPECT_GE(t.windows, 4);
  EXPECT_EQ(t.tr_valid_off, 0);
  EXPECT_GE(t.tr_uncertain, 1);
}

namespace {
// The 4 kW preset at rated load (390 V, 50 Hz, 26.5 N m), sampled at 4 kHz
// with 12-bit sensors. A sine source (a line-fed motor): its phase voltages
// have no PWM staircase. The same motor on the PWM inverter with its carrier
// at the sample rate: a staircase (the period's volt-seconds, half a sample
// behind the currents).
const std::string kSine4kw =
    "--preset 4kw --supply sine --timing ideal --fs 4000 --start steady --duration 5 "
    "--no-thermal --no-progress";
const std::string kPwm4kw =
    "--preset 4kw --fs 4000 --carrier-hz 4000 --start steady --duration 5 --no-thermal --no-progress";
const std::string kReplay4kw =
    " --pole-pairs 2 --ls 0.178039 --sigma 0.0645168 --ls-uncertainty 0 --sigma-uncertainty 0 ";
const double kRs4kw = 1.405;

struct RsTally {
  int windows = 0, rs_valid = 0, rs_valid_within_1pct = 0, rs_uncertain = 0;
  double rs_err_max = 0.0; /* largest |R_S / true - 1| of every window */
};

RsTally rs_tally(const std::string &csv, const std::string &extra)
{
  const Out o = run(std::string(REPLAY_BIN) + kReplay4kw + extra + " " + csv);
  EXPECT_EQ(o.code, 0) << o.err;
  const auto r = rows(o.out);
  const int rs = col(r, "R_S_ohm"), v = col(r, "rs_valid"), why = col(r, "rs_reason");
  RsTally t;
  for (size_t k = 2; k < r.size(); ++k) { // the first window is warm-up
    ++t.windows;
    const double err = std::fabs(std::stod(r[k][rs]) / kRs4kw - 1.0);
    const bool valid = r[k][v] == "1";
    t.rs_valid += valid;
    t.rs_valid_within_1pct += valid && err < 0.01;
    t.rs_uncertain += r[k][why] == "rs_uncertain";
    t.rs_err_max = std::fmax(t.rs_err_max, err);
  }
  return t;
}
} // namespace

TEST(ReplayBounds, SmoothSourceRsIsValidWhenConfiguredSmooth)
{
  // measured: R_S within 0.1 %, its bound 1.5 % with --voltage-kind smooth;
  // by default the staircase's share (which a sine source does not have)
  // makes the bound 11 %, above the 5 % tolerance, in every window
  const std::string &csv = sim_csv("sine4kw_fs4k.csv", kSine4kw);
  const RsTally smooth = rs_tally(csv, "--voltage-kind smooth");
  EXPECT_GE(smooth.windows, 3);
  EXPECT_GE(smooth.rs_valid_within_1pct, smooth.windows - 1);
  EXPECT_EQ(smooth.rs_valid, smooth.rs_valid_within_1pct);
  const RsTally stair = rs_tally(csv, "");
  EXPECT_EQ(stair.windows, smooth.windows);
  EXPECT_EQ(stair.rs_uncertain, stair.windows);
  EXPECT_EQ(stair.rs_valid, 0);
  // the setting moves the bound only: the estimates are the same
  EXPECT_EQ(stair.rs_err_max, smooth.rs_err_max);
}

TEST(ReplayBounds, SmoothOnAStaircaseMissesItsShare)
{
  // what imest.h says of the wrong setting: on a PWM staircase at 4 kHz R_S
  // is 8.3 % low (the staircase's aliased images); the default bound refuses
  // it, smooth lets it through as valid
  const std::string &csv = sim_csv("pwm4kw_fs4k.csv", kPwm4kw);
  const RsTally stair = rs_tally(csv, "--u-delay 125e-6");
  EXPECT_GE(stair.windows, 3);
  EXPECT_EQ(stair.rs_uncertain, stair.windows);
  const RsTally smooth = rs_tally(csv, "--u-delay 125e-6 --voltage-kind smooth");
  EXPECT_GT(smooth.rs_err_max, 0.05);
  EXPECT_LT(smooth.rs_err_max, 0.12);
  EXPECT_GE(smooth.rs_valid, 1);
}

TEST(ReplayBounds, VoltageKindIsForThePhaseInput)
{
  const std::string &csv = sim_csv("sine4kw_fs4k.csv", kSine4kw);
  Out o = run(std::string(REPLAY_BIN) + kReplay4kw + "--voltage-kind sine " + csv);
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--voltage-kind takes staircase or smooth"), std::string::npos) << o.err;
  o = run(std::string(REPLAY_BIN) + kReplay4kw + "--voltage duty --voltage-kind smooth " + csv);
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--voltage-kind smooth applies to measured phase voltages"), std::string::npos)
      << o.err;
}
