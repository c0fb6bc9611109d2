/* SPDX-License-Identifier: Apache-2.0 */
// Self-commissioning (include/imest/imest_commission.h): closed loop on the simulator
// (tools/commission/commission_sim.c: imsim with external duties, firmware timing, 2 us dead
// time, 1 V / 0.8 V drops with slopes, 12-bit sensors with offsets and gain errors, 4096-count
// encoder) on four motors, the wiring and encoder mistakes a user makes, and the routine's
// protections on synthetic inputs.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <string>

#include "commission_online.h"
#include "commission_sim.h"
#include "imest/imest_commission.h"

namespace {

double rel(double a, double b)
{
  return (a - b) / b;
}

comm_sim_out_t run(const comm_sim_opts_t &o)
{
  comm_sim_out_t out;
  EXPECT_EQ(comm_sim_run(&o, &out), 0);
  return out;
}

comm_sim_opts_t opts(const char *preset)
{
  comm_sim_opts_t o;
  EXPECT_EQ(comm_sim_defaults(&o, preset), 0);
  return o;
}

// The accuracy the issue asks for, on each motor, closed loop.
void expect_accurate(const comm_sim_out_t &out, double i_max)
{
  const imest_comm_result_t &r = out.r;
  ASSERT_EQ(r.state, IMEST_COMM_DONE) << imest_comm_reason_name(r.reason);
  ASSERT_TRUE(r.valid);
  // R_S against what a terminal measurement can see (winding + min(r_sw, r_d))
  EXPECT_LT(std::fabs(rel(r.rs_ohm.value, out.rs_identifiable_ohm)), 0.01);
  EXPECT_LT(std::fabs(rel(r.ls_h.value, out.ls_h)), 0.02);
  EXPECT_LT(std::fabs(rel(r.sigma.value, out.sigma)), 0.05);
  EXPECT_LT(std::fabs(rel(r.sigma_ls_h.value, out.sigma_ls_h)), 0.01);
  EXPECT_LT(std::fabs(rel(r.tr_s.value, out.tr_s)), 0.01);
  EXPECT_EQ(r.pole_pairs, out.pole_pairs);
  EXPECT_EQ(r.encoder_dir, 1);
  EXPECT_FLOAT_EQ(r.encoder_cpr, 4096.0f);
  EXPECT_NEAR(r.inverter.dead_time_s, out.sim.dead_time_s, 0.02e-6);
  EXPECT_NEAR(r.v_threshold_v.value, 0.5 * (out.sim.v_switch_v + out.sim.v_diode_v), 0.03);
  // the inverter model's per-leg voltage error against the simulator's devices
  EXPECT_LT(out.inv_err_model_v, 0.1);
  // sensors
  for (int x = 0; x < 3; ++x) {
    EXPECT_NEAR(r.i_offset_a[x], out.sim.i_offset_a[x], 0.002 * out.sim.i_range_a);
    const double gm = (out.sim.i_gain_err[0] + out.sim.i_gain_err[1] + out.sim.i_gain_err[2]) / 3.0;
    EXPECT_NEAR(r.i_gain_rel[x], (1.0 + out.sim.i_gain_err[x]) / (1.0 + gm), 5e-4);
    EXPECT_EQ(r.wiring_map[x], x + 1);
  }
  // the limit held, the rotor stayed put at standstill
  EXPECT_LE(out.i_peak_true_a, i_max);
  EXPECT_LT(r.rotor_moved_rad, 0.2f);
  EXPECT_TRUE(r.flags & IMEST_COMM_FLAG_ROTATED);
  EXPECT_TRUE(r.flags & IMEST_COMM_FLAG_GAINS);
}

} // namespace

class CommissionMotor : public ::testing::TestWithParam<const char *> {};

// A deep-bar rotor's description at high frequency as imest_comm_apply() fills it: the square
// wave's rotor resistance over the tones' R_R' (the flag's threshold is 3 x the tails' R_R') and
// its sigma*L_S over the slip-frequency one (the outer cage's leakage, about 44 % low), the bus.
static void expect_rotor_hf(const imest_comm_result_t &r, const imest_config_t &cfg)
{
  EXPECT_FLOAT_EQ(cfg.rotor_hf_rr_ratio, r.rr_hf_ohm.value / r.rr_slip_ohm.value);
  EXPECT_GT(cfg.rotor_hf_rr_ratio, 3.0f);
  EXPECT_FLOAT_EQ(cfg.rotor_hf_sigma_ratio, r.sigma_ls_hf_h.value / r.sigma_ls_slip_h.value);
  EXPECT_LT(cfg.rotor_hf_sigma_ratio, 0.7f);
  EXPECT_GT(cfg.rotor_hf_sigma_ratio, 0.3f);
  EXPECT_FLOAT_EQ(cfg.inverter_vdc_v, r.vdc_v);
  const char *field = nullptr;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_OK) << (field ? field : "");
}

TEST_P(CommissionMotor, ClosedLoopWithinTheIssuesAccuracy)
{
  const comm_sim_opts_t o = opts(GetParam());
  const comm_sim_out_t out = run(o);
  expect_accurate(out, out.cc.i_max_a);
  // the config it fills is one the estimator accepts
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.fs_hz = (float)out.sim.fs_hz;
  cfg.pwm_hz = (float)out.sim.carrier_hz;
  EXPECT_EQ(imest_comm_apply(&out.r, &cfg), 7); // with the magnetising curve
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_OK);
  EXPECT_EQ(cfg.pole_pairs, out.pole_pairs);
  EXPECT_FLOAT_EQ(cfg.ls_h, out.r.ls_h.value);
  EXPECT_FLOAT_EQ(cfg.inverter.dead_time_s, out.r.inverter.dead_time_s);
  EXPECT_GT(cfg.inverter.uncertainty, 0.0f);
  EXPECT_EQ(cfg.inverter.i_band_a, 0.0f); // the estimator's band per leg and sample
  // the stated uncertainty of L_S and sigma: the rule's floors (rotating), and it covers
  // what commissioning is actually off by
  EXPECT_GE(cfg.ls_uncertainty, IMEST_COMM_LS_FLOOR);
  EXPECT_LT(cfg.ls_uncertainty, 0.01f);
  EXPECT_GE(cfg.sigma_uncertainty, IMEST_COMM_SIGMA_FLOOR);
  EXPECT_LT(cfg.sigma_uncertainty, 0.02f);
  EXPECT_GT(cfg.ls_uncertainty, std::fabs(rel(out.r.ls_h.value, out.ls_h)));
  EXPECT_GT(cfg.sigma_uncertainty, std::fabs(rel(out.r.sigma.value, out.sigma)));
  std::printf("%s: L_S %+.3f %% (stated %.2f %%), sigma %+.3f %% (stated %.2f %%)\n", GetParam(),
              100.0 * rel(out.r.ls_h.value, out.ls_h), 100.0 * cfg.ls_uncertainty,
              100.0 * rel(out.r.sigma.value, out.sigma), 100.0 * cfg.sigma_uncertainty);
}

INSTANTIATE_TEST_SUITE_P(Presets, CommissionMotor, ::testing::Values("exp1", "4kw", "11kw", "37kw"),
                         [](const ::testing::TestParamInfo<const char *> &i) {
                           return std::string("m") + i.param;
                         });

// Then the online estimator on the same drive at rated load, fed the duty cycles (no voltage
// sensors) with the identified constants and inverter model: T_R within 1 %, and what
// commissioning costs against the true constants within 0.1 % of T_R.
TEST_P(CommissionMotor, ThenTheEstimatorOnTheDutyCyclesGetsTrWithinOnePercent)
{
  const comm_sim_opts_t o = opts(GetParam());
  const comm_sim_out_t out = run(o);
  ASSERT_TRUE(out.r.valid);
  comm_online_t id, tr;
  ASSERT_EQ(comm_online_run(&o, 1.0, 20.0, &out.r, &id), 0);
  ASSERT_EQ(comm_online_run(&o, 1.0, 20.0, nullptr, &tr), 0);
  ASSERT_GT(id.windows, 10);
  EXPECT_LT(std::fabs(id.tr_all_rel), 0.01);
  EXPECT_LT(std::fabs(id.tr_all_rel - tr.tr_all_rel), 0.001);
  if (id.tr_valid > 0) EXPECT_LT(std::fabs(id.tr_rel), 0.01);
}

// The curve's levels: their fluxes L_S i against the rated point's, evenly from 1 down to the
// lowest (commissioning's CM_ROT_FLUX_MIN, 0.45: field weakening to twice base speed, where the
// drive's flux is 0.46-0.48 of rated at rated power on the envelope's motors). Each level is set
// from a predicted L_S: high where the curve is concave (below about 0.85 of rated flux), so the
// lowest level's flux is at or below its target, by less than 3 % of the rated flux (measured
// 0.3 ... 1.5 %); the highest, where a saturating curve is convex, within 3 % either way
// (measured up to +1.8 %).
constexpr double kFluxFw2 = 0.46; // field weakening to 2x base speed at rated power
void expect_curve_spans_field_weakening(const imest_comm_result_t &r)
{
  ASSERT_EQ(r.ls_curve_points, 4u);
  const double flux_rated = (double)r.ls_curve_h[3] * r.ls_curve_i_a[3];
  const double target[3] = {0.45, 0.45 + 0.55 / 3.0, 0.45 + 1.1 / 3.0};
  for (unsigned int j = 0; j < 3u; ++j) {
    const double f = (double)r.ls_curve_h[j] * r.ls_curve_i_a[j] / flux_rated;
    EXPECT_LE(f, target[j] + (j == 0u ? 0.005 : 0.03)) << "point " << j;
    EXPECT_GT(f, target[j] - 0.03) << "point " << j;
  }
  EXPECT_LT((double)r.ls_curve_h[0] * r.ls_curve_i_a[0] / flux_rated, kFluxFw2);
}

// The magnetising curve of a linear motor is flat: L_S the same at every level (within the
// rotating measurement's own error), the rated point found with the first level: the rated
// flux's current also on the paper's motor, whose R_S drop (R_S / (w L_S) 0.05) and small
// current limit (the staircase's top, 1.1 x the rated flux's current) once held it at 0.84 of it.
TEST_P(CommissionMotor, LinearMotorHasAFlatCurveAtRatedFlux)
{
  const comm_sim_out_t out = run(opts(GetParam()));
  const imest_comm_result_t &r = out.r;
  ASSERT_TRUE(r.valid);
  expect_curve_spans_field_weakening(r);
  EXPECT_FLOAT_EQ(r.ls_curve_h[3], r.ls_h.value);
  EXPECT_FLOAT_EQ(r.ls_curve_i_a[3], r.rotating_i_a);
  for (unsigned int j = 0; j < r.ls_curve_points; ++j)
    EXPECT_LT(std::fabs(rel(r.ls_curve_h[j], out.ls_h)), 0.01) << "point " << j;
  EXPECT_LT(std::fabs(rel(r.rotating_i_a, out.i_rated_flux_a)), 0.01);
  EXPECT_LT(r.ls_h.spread_rel, 0.01f);              // no flux dependence to speak of
  EXPECT_LT(r.ls_h.std_rel, 0.01f);                 // also the curve's points'
  EXPECT_FALSE(r.flags & IMEST_COMM_FLAG_ROTOR_HF); // a single cage
}

// A saturating motor (the simulator's static magnetising curve, L_m at rated flux 25 % below
// unsaturated; and the preset's real motor: saturation, iron loss, double cage): the standstill
// L_S is about half the rated-flux one, which once set the rotating run 10-19 % too low. The
// levels now find the rated flux: L_S within 2 % of L_S there, the flux within 1 %, each point of
// the curve within 2 % of the truth at its current, the curve down to field weakening's flux, and
// the flux dependence reported. Also on the paper's 0.4 kW motor (exp1, saturation 0.25), small
// and of high R_S, which its current limit once held at 0.84 of the rated flux's current (L_S
// +9.6 %). T_R (standstill) is as far off as before; its reported spread says so.
struct SatCase {
  const char *preset;
  int real_motor;
};
void PrintTo(const SatCase &c, std::ostream *os)
{
  *os << c.preset << (c.real_motor ? " real motor" : " saturation 0.25");
}
class CommissionSaturating : public ::testing::TestWithParam<SatCase> {};

TEST_P(CommissionSaturating, LsAtRatedFluxAndTheCurveWithinTwoPercent)
{
  comm_sim_opts_t o = opts(GetParam().preset);
  if (GetParam().real_motor)
    o.real_motor = 1;
  else
    o.sat_fraction = 0.25;
  const comm_sim_out_t out = run(o);
  const imest_comm_result_t &r = out.r;
  ASSERT_EQ(r.state, IMEST_COMM_DONE) << imest_comm_reason_name(r.reason);
  ASSERT_TRUE(r.valid);
  EXPECT_LT(std::fabs(rel(r.ls_h.value, out.ls_h)), 0.02);
  EXPECT_LT(std::fabs(rel(r.rotating_i_a, out.i_rated_flux_a)), 0.02);
  EXPECT_LT(std::fabs(rel((double)r.ls_h.value * r.rotating_i_a, out.ls_h * out.i_rated_flux_a)), 0.01);
  expect_curve_spans_field_weakening(r);
  // each point within the uncertainty the estimator takes for it: imest_comm_apply's
  // ls_uncertainty, a share of the rated point's reactive voltage, so rated / flux times it at a
  // point of lower flux (bg_flux.c). The lowest flux's point once read 1.4 % high on the 4 kW
  // real motor against 0.69 % (the dead time's error at a current 3 x the ripple band, and the
  // rotor flux not settled: T_R there up to twice the standstill one)
  imest_config_t applied;
  imest_config_default(&applied);
  ASSERT_GE(imest_comm_apply(&r, &applied), 1);
  const double flux_rated = (double)r.ls_h.value * r.rotating_i_a;
  for (unsigned int j = 0; j < r.ls_curve_points; ++j) {
    double ls_true = 0.0;
    ASSERT_EQ(comm_sim_true_at(&out.sim, r.ls_curve_i_a[j], &ls_true, nullptr, nullptr), 0);
    EXPECT_LT(std::fabs(rel(r.ls_curve_h[j], ls_true)), 0.02) << "point " << j;
    const double flux = (double)r.ls_curve_h[j] * r.ls_curve_i_a[j];
    EXPECT_LE(std::fabs(rel(r.ls_curve_h[j], ls_true)), applied.ls_uncertainty * flux_rated / flux)
        << "point " << j;
    if (j > 0) {
      EXPECT_GT(r.ls_curve_i_a[j], r.ls_curve_i_a[j - 1]);
      EXPECT_LT(r.ls_curve_h[j], r.ls_curve_h[j - 1]); // saturating: L_S falls with the current
    }
  }
  // ... and no more than the measurement supports: the rated point's two levels, 0.1 % each
  // (3 standard errors, at most 1.58 x by the interpolation's weights: 0.47 %), and a bound of
  // the interpolation's remainder (below 0.2 % here). Not the interpolation's correction to the
  // nearest level, which the curve is measured through (the search ends up to 3.5 % of the
  // current from the rated point, where L_S changes 0.55-0.6 % per 1 %): as that, 1.8 % and
  // 5.5 % on the 11 and 37 kW motors with saturation alone refused every T_R there.
  EXPECT_LT(applied.ls_uncertainty, 0.0067f);
  // the flux dependence is reported: L_S over the curve (0.45 rated flux and up) changes by more
  // than 10 %, and T_R's spread covers the standstill T_R's error at rated flux
  EXPECT_GT(r.ls_h.spread_rel, 0.1f);
  EXPECT_GE(r.sigma.spread_rel, r.ls_h.spread_rel);
  EXPECT_GT(r.tr_s.spread_rel, std::fabs(rel(r.tr_s.value, out.tr_s)));
  if (!GetParam().real_motor) {
    EXPECT_LT(std::fabs(rel(r.sigma.value, out.sigma)), 0.02);
    EXPECT_FALSE(r.flags & IMEST_COMM_FLAG_ROTOR_HF); // saturation alone is not a deep-bar rotor
  } else {
    // the double cage's sigma*L_S at fs/8 is its high-frequency one (about 44 % low): flagged,
    // and sigma comes from the slip-frequency test, whose tones find their own magnetising
    // branch (the incremental one at the test's flux; the standstill tails' T_R, from steps
    // through the curve, once put it 35 % low): within 1 % of the truth at rated flux, and the
    // uncertainty stated for sigma covers its error and is far below the data sheet's 0.2
    EXPECT_TRUE(r.flags & IMEST_COMM_FLAG_ROTOR_HF);
    EXPECT_TRUE(r.flags & IMEST_COMM_FLAG_SIGMA_SLIP);
    EXPECT_LT(rel(r.sigma_ls_hf_h.value, out.sigma_ls_h), -0.3);
    EXPECT_LT(std::fabs(rel(r.sigma_ls_slip_h.value, out.sigma_ls_h)), 0.01);
    EXPECT_GE(r.sigma.spread_rel, std::fabs(rel(r.sigma.value, out.sigma)));
    imest_config_t cfg;
    imest_config_default(&cfg);
    EXPECT_EQ(imest_comm_apply(&r, &cfg), 8); // sigma too, the curve copied, the rotor at fs/8
    EXPECT_FLOAT_EQ(cfg.sigma, r.sigma.value);
    expect_rotor_hf(r, cfg);
    EXPECT_GT(cfg.sigma_uncertainty, std::fabs(rel(r.sigma.value, out.sigma)));
    EXPECT_LT(cfg.sigma_uncertainty, 0.03f);
    EXPECT_FLOAT_EQ(cfg.ls_h, r.ls_h.value);
    std::printf("%s real motor: sigma*L_S at slip frequency %+.3f %% (spread %.2f %%), sigma %+.3f %% "
                "(stated %.2f %%)\n",
                GetParam().preset, 100.0 * rel(r.sigma_ls_slip_h.value, out.sigma_ls_h),
                100.0 * r.sigma_ls_slip_h.spread_rel, 100.0 * rel(r.sigma.value, out.sigma),
                100.0 * cfg.sigma_uncertainty);
  }
}

INSTANTIATE_TEST_SUITE_P(Presets, CommissionSaturating,
                         ::testing::Values(SatCase{"4kw", 0}, SatCase{"11kw", 0}, SatCase{"4kw", 1},
                                           SatCase{"exp1", 0}),
                         [](const ::testing::TestParamInfo<SatCase> &i) {
                           return std::string("m") + i.param.preset + (i.param.real_motor ? "_real" : "_sat");
                         });

// A deep-bar rotor (the simulator's double cage, no saturation or iron loss): the square wave
// at fs/8 sees its outer cage's leakage (44 % low), the slip-frequency test the leakage the
// estimator needs. Truth: sigma*L_S = L_S - M^2 / (M + L_lr(f)) with L_lr(f) the cage
// branches' inductance at rotor frequency f, at 0 and at the rated slip frequency; the value
// within its stated uncertainty of both, and the uncertainty imest_comm_apply() states for sigma
// covers sigma's error at both.
class CommissionDeepBar : public ::testing::TestWithParam<const char *> {};

TEST_P(CommissionDeepBar, SigmaAtSlipFrequencyWithinItsStatedUncertainty)
{
  comm_sim_opts_t o = opts(GetParam());
  o.real_motor = 1;
  o.real_off = COMM_SIM_OFF_SATURATION | COMM_SIM_OFF_IRON_LOSS;
  const comm_sim_out_t out = run(o);
  const imest_comm_result_t &r = out.r;
  ASSERT_EQ(r.state, IMEST_COMM_DONE) << imest_comm_reason_name(r.reason);
  ASSERT_TRUE(r.valid);
  ASSERT_TRUE(r.flags & IMEST_COMM_FLAG_ROTOR_HF);
  ASSERT_TRUE(r.flags & IMEST_COMM_FLAG_SIGMA_SLIP);
  imsim_real_params_t rp;
  ASSERT_EQ(imsim_real_params(&out.sim, &rp), 0);
  ASSERT_GT(rp.r2_ohm, 0.0); // a double cage
  const double m = rp.lm0_h, ls = rp.lls_h + m;
  const auto sigma_ls_at = [&](double f_hz) { // L_S - M^2 / (M + L_lr(f))
    const double w = 6.283185307179586 * f_hz;
    // the two branches in parallel: Z = 1 / (1 / z1 + 1 / z2), z_k = r_k + j w l_k
    const double a1 = rp.r1_ohm, b1 = w * rp.l1_h, a2 = rp.r2_ohm, b2 = w * rp.l2_h;
    const double d1 = a1 * a1 + b1 * b1, d2 = a2 * a2 + b2 * b2;
    const double yr = a1 / d1 + a2 / d2, yi = -b1 / d1 - b2 / d2;
    const double zi = -yi / (yr * yr + yi * yi);
    const double llr = w > 0.0 ? zi / w : rp.llr_h;
    return ls - m * m / (m + llr);
  };
  const double f_sl = out.sim.rated_freq_hz *
                      (1.0 - out.sim.rated_speed_rpm * out.pole_pairs / (60.0 * out.sim.rated_freq_hz));
  ASSERT_GT(f_sl, 0.1);
  ASSERT_LT(f_sl, r.slip_test_hz); // the rated slip lies inside the range the value stands for
  EXPECT_NEAR(sigma_ls_at(0.0), out.sigma_ls_h, 1e-6 * out.sigma_ls_h); // the tool's truth: DC
  const imest_comm_value_t &v = r.sigma_ls_slip_h;
  const double u = std::fmax(3.0 * v.std_rel, v.spread_rel);
  for (const double f : {0.0, f_sl}) {
    const double truth = sigma_ls_at(f);
    EXPECT_LT(std::fabs(rel(v.value, truth)), u) << "rotor at " << f << " Hz";
    EXPECT_LT(std::fabs(rel(v.value, truth)), 0.01) << "rotor at " << f << " Hz";
  }
  EXPECT_FLOAT_EQ(r.sigma_ls_h.value, v.value);
  EXPECT_LT(rel(r.sigma_ls_hf_h.value, out.sigma_ls_h), -0.3); // the outer cage's leakage
  // the config gets sigma, with an uncertainty that covers its error at 0 and at rated slip
  imest_config_t cfg;
  imest_config_default(&cfg);
  EXPECT_EQ(imest_comm_apply(&r, &cfg), 8); // with the rotor's description at fs/8
  EXPECT_FLOAT_EQ(cfg.sigma, r.sigma.value);
  expect_rotor_hf(r, cfg);
  for (const double f : {0.0, f_sl}) {
    const double sigma_true = sigma_ls_at(f) / ls;
    EXPECT_GT(cfg.sigma_uncertainty, std::fabs(rel(cfg.sigma, sigma_true))) << "rotor at " << f << " Hz";
  }
  EXPECT_LT(cfg.sigma_uncertainty, 0.03f); // far below the data sheet's 0.2
  std::printf("%s double cage: sigma*L_S at slip frequency %+.3f %% (rotor at 0 Hz), %+.3f %% (%.2f Hz), "
              "stated %.2f %%; at fs/8 %+.1f %%; sigma %+.3f %% (stated %.2f %%); tones %.2f / %.2f Hz\n",
              GetParam(), 100.0 * rel(v.value, sigma_ls_at(0.0)), 100.0 * rel(v.value, sigma_ls_at(f_sl)),
              f_sl, 100.0 * u, 100.0 * rel(r.sigma_ls_hf_h.value, out.sigma_ls_h),
              100.0 * rel(cfg.sigma, out.sigma), 100.0 * cfg.sigma_uncertainty, r.slip_test_hz,
              3.0 * r.slip_test_hz);
}

INSTANTIATE_TEST_SUITE_P(Presets, CommissionDeepBar, ::testing::Values("4kw", "11kw"),
                         [](const ::testing::TestParamInfo<const char *> &i) {
                           return std::string("m") + i.param;
                         });

TEST(Commission, StandstillOnlyFillsLsFromTheFluxTails)
{
  comm_sim_opts_t o = opts("4kw");
  o.allow_rotation = 0;
  const comm_sim_out_t out = run(o);
  ASSERT_EQ(out.r.state, IMEST_COMM_DONE);
  EXPECT_TRUE(out.r.valid);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_LS_STANDSTILL);
  EXPECT_FALSE(out.r.flags & IMEST_COMM_FLAG_ROTATED);
  EXPECT_LT(std::fabs(rel(out.r.ls_h.value, out.ls_h)), 0.01);
  EXPECT_LT(std::fabs(rel(out.r.sigma.value, out.sigma)), 0.02);
  EXPECT_EQ(out.r.pole_pairs, 0u); // not identified without turning
  imest_config_t cfg;
  imest_config_default(&cfg);
  EXPECT_EQ(imest_comm_apply(&out.r, &cfg), 5); // all but n_p
  // standstill only: the larger floors, covering the actual error
  EXPECT_GE(cfg.ls_uncertainty, IMEST_COMM_LS_FLOOR_STANDSTILL);
  EXPECT_GE(cfg.sigma_uncertainty, IMEST_COMM_SIGMA_FLOOR_STANDSTILL);
  EXPECT_GT(cfg.ls_uncertainty, std::fabs(rel(out.r.ls_h.value, out.ls_h)));
  EXPECT_GT(cfg.sigma_uncertainty, std::fabs(rel(out.r.sigma.value, out.sigma)));
  cfg.pole_pairs = 2; // not identified at standstill: the user's
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_OK);
  std::printf("4kw standstill: L_S %+.3f %% (stated %.2f %%), sigma %+.3f %% (stated %.2f %%)\n",
              100.0 * rel(out.r.ls_h.value, out.ls_h), 100.0 * cfg.ls_uncertainty,
              100.0 * rel(out.r.sigma.value, out.sigma), 100.0 * cfg.sigma_uncertainty);
}

// A valid result with R_S only: what the tests of imest_comm_apply()'s rules fill in.
static imest_comm_result_t handmade_result()
{
  imest_comm_result_t r;
  std::memset(&r, 0, sizeof r);
  r.valid = 1;
  r.rs_ohm.value = 1.4f;
  r.tr_s.value = NAN;
  r.inverter.uncertainty = -1.0f;
  return r;
}

// imest_comm_apply()'s rule for ls_uncertainty and sigma_uncertainty (imest_commission.h), on
// hand-made results: the floors, 3 standard errors, the axes' spread, sigma's sum, the cap.
TEST(Commission, ApplyStatesTheConstantsUncertaintyByItsRule)
{
  imest_comm_result_t r = handmade_result();
  const auto set = [](imest_comm_value_t &v, float value, float std_rel, float spread_rel) {
    v.value = value;
    v.std_rel = std_rel;
    v.spread_rel = spread_rel;
  };
  set(r.ls_h, 0.178f, NAN, NAN);
  set(r.sigma, 0.0645f, NAN, NAN);
  set(r.sigma_ls_h, 0.0115f, NAN, NAN);
  set(r.ls_standstill_h, 0.178f, NAN, NAN);
  imest_config_t cfg;
  imest_config_default(&cfg);
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, IMEST_COMM_LS_FLOOR); // nothing known: the floors
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, IMEST_COMM_SIGMA_FLOOR);
  set(r.ls_h, 0.178f, 0.004f, 0.002f);        // 3 standard errors
  set(r.sigma_ls_h, 0.0115f, 0.001f, 0.009f); // the spread, plus L_S's
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, 0.012f);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.009f + 0.012f);
  set(r.sigma, 0.0645f, 0.01f, NAN); // sigma's own quality when larger
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.03f);
  set(r.ls_h, 0.178f, NAN, 0.9f); // at most IMEST_COMM_UNCERTAINTY_MAX
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, IMEST_COMM_UNCERTAINTY_MAX);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, IMEST_COMM_UNCERTAINTY_MAX);
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_ERR_CONFIG); // pole_pairs not set
  cfg.pole_pairs = 2;
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_OK);
  // standstill only: its floors, and the standstill L_S's spread
  set(r.ls_h, 0.178f, NAN, NAN);
  set(r.sigma, 0.0645f, NAN, NAN);
  set(r.sigma_ls_h, 0.0115f, NAN, NAN);
  r.flags = IMEST_COMM_FLAG_LS_STANDSTILL;
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, IMEST_COMM_LS_FLOOR_STANDSTILL);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, IMEST_COMM_SIGMA_FLOOR_STANDSTILL);
  set(r.ls_standstill_h, 0.178f, NAN, 0.03f);
  ASSERT_GE(imest_comm_apply(&r, &cfg), 3);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, 0.03f);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.03f);
}

// With the magnetising curve in the result, imest_comm_apply() copies it and states L_S's and
// sigma's uncertainty without their change over the curve (the estimator follows it); without
// a curve that change is what the stated figure covers (saturation: T_R refused, not wrong).
TEST(Commission, ApplyCopiesTheCurveAndLeavesItsSpreadOut)
{
  imest_comm_result_t r = handmade_result();
  r.ls_h = {0.178f, 0.001f, 0.35f};   // L_S changes by 35 % over the curve
  r.sigma = {0.0645f, 0.001f, 0.35f}; // and sigma with it
  r.sigma_ls_h = {0.0115f, 0.001f, NAN};
  r.ls_standstill_h = {0.1f, NAN, NAN};
  imest_config_t cfg;
  imest_config_default(&cfg);
  const int without = imest_comm_apply(&r, &cfg);
  EXPECT_EQ(cfg.ls_curve_points, 0u);
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, 0.35f);
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.003f + 0.35f); // sigma*L_S's plus L_S's
  r.ls_curve_points = 3u;
  const float ia[3] = {2.0f, 2.5f, 3.0f}, lh[3] = {0.21f, 0.195f, 0.178f};
  for (unsigned int k = 0; k < 3u; ++k) {
    r.ls_curve_i_a[k] = ia[k];
    r.ls_curve_h[k] = lh[k];
  }
  EXPECT_EQ(imest_comm_apply(&r, &cfg), without + 1); // the curve counts as one field
  ASSERT_EQ(cfg.ls_curve_points, 3u);
  for (unsigned int k = 0; k < 3u; ++k) {
    EXPECT_FLOAT_EQ(cfg.ls_curve_i_a[k], ia[k]);
    EXPECT_FLOAT_EQ(cfg.ls_curve_h[k], lh[k]);
  }
  EXPECT_FLOAT_EQ(cfg.ls_uncertainty, 0.003f);             // 3 standard errors
  EXPECT_FLOAT_EQ(cfg.sigma_uncertainty, 0.003f + 0.003f); // sigma*L_S's plus L_S's
  cfg.pole_pairs = 2;
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_OK);
}

TEST(Commission, EncoderCountingBackwardsIsFound)
{
  comm_sim_opts_t o = opts("4kw");
  o.encoder_reversed = 1;
  const comm_sim_out_t out = run(o);
  ASSERT_EQ(out.r.state, IMEST_COMM_DONE);
  EXPECT_EQ(out.r.encoder_dir, -1);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_ENCODER_REVERSED);
  EXPECT_EQ(out.r.pole_pairs, 2u);
}

TEST(Commission, WrongCountsPerRevolutionWithTheNameplate)
{
  comm_sim_opts_t o = opts("11kw");
  o.cpr_assumed = 1024; // quadrature x4 forgotten
  const comm_sim_out_t out = run(o);
  ASSERT_EQ(out.r.state, IMEST_COMM_DONE);
  EXPECT_EQ(out.r.pole_pairs, 2u);
  EXPECT_FLOAT_EQ(out.r.encoder_cpr, 4096.0f);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_CPR_MISMATCH);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_NP_NAMEPLATE);
}

TEST(Commission, ElectricalAngleWithoutNameplateGivesAConsistentProduct)
{
  // the firmware passes the electrical angle (its counts are the true ones / n_p): without the
  // rated speed the routine cannot tell, and reports n_p = 1, which with that angle is right
  comm_sim_opts_t o = opts("exp1");
  o.nameplate_speed = 0;
  o.cpr_assumed = 2048;
  const comm_sim_out_t out = run(o);
  ASSERT_EQ(out.r.state, IMEST_COMM_DONE);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_NP_ASSUMED_CPR);
  EXPECT_EQ(out.r.pole_pairs * 4096u / 2048u, out.pole_pairs);
}

TEST(Commission, CountsThatFitNoPolePairNumberFail)
{
  comm_sim_opts_t o = opts("4kw");
  o.nameplate_speed = 0;
  o.cpr_assumed = 3000;
  const comm_sim_out_t out = run(o);
  EXPECT_EQ(out.r.state, IMEST_COMM_FAILED);
  EXPECT_EQ(out.r.reason, IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS);
  EXPECT_NEAR(out.r.speed_ratio, 2.0 * 3000.0 / 4096.0, 0.01);
}

TEST(Commission, AnEncoderThatDoesNotMoveIsNamed)
{
  comm_sim_opts_t o = opts("4kw");
  o.encoder_stuck = 1;
  const comm_sim_out_t out = run(o);
  EXPECT_EQ(out.r.state, IMEST_COMM_FAILED);
  EXPECT_EQ(out.r.reason, IMEST_COMM_REASON_ENCODER_STILL);
  EXPECT_TRUE(out.r.flags & IMEST_COMM_FLAG_STANDSTILL); // the standstill part stands
  EXPECT_LT(std::fabs(rel(out.r.rs_ohm.value, out.rs_identifiable_ohm)), 0.01);
}

TEST(Commission, SwappedCurrentChannelsStopAtTheWiringCheck)
{
  comm_sim_opts_t o = opts("4kw");
  o.swap_sensors_bc = 1;
  const comm_sim_out_t out = run(o);
  EXPECT_EQ(out.r.state, IMEST_COMM_FAILED);
  EXPECT_EQ(out.r.reason, IMEST_COMM_REASON_WIRING);
  EXPECT_EQ(out.r.stage, IMEST_COMM_STAGE_WIRING);
  EXPECT_EQ(out.r.wiring_map[0], 1);
  EXPECT_EQ(out.r.wiring_map[1], 3); // leg b is read by channel c
  EXPECT_EQ(out.r.wiring_map[2], 2);
  EXPECT_LT(out.r.time_s, 1.0f);
}

TEST(Commission, TwoSensorsWorkWithoutTheGainCheck)
{
  comm_sim_opts_t o = opts("4kw");
  o.two_sensors = 1;
  const comm_sim_out_t out = run(o);
  ASSERT_EQ(out.r.state, IMEST_COMM_DONE);
  EXPECT_FALSE(out.r.flags & IMEST_COMM_FLAG_GAINS);
  for (int x = 0; x < 3; ++x) EXPECT_FLOAT_EQ(out.r.i_gain_rel[x], 1.0f);
  // the gain errors of a and b (+1 %, -0.4 %) now reach R_S and L_S: within their mean
  EXPECT_LT(std::fabs(rel(out.r.rs_ohm.value, out.rs_identifiable_ohm)), 0.01);
  EXPECT_LT(std::fabs(rel(out.r.ls_h.value, out.ls_h)), 0.01);
}

// ---------------------------------------------------------------------------
// Protections, on synthetic inputs

namespace {

imest_comm_config_t base_config()
{
  imest_comm_config_t cc;
  imest_comm_config_default(&cc);
  cc.fs_hz = 8000.0f;
  cc.i_max_a = 10.0f;
  return cc;
}

// Zero currents at a 560 V bus until the routine stops commanding (at most n samples); the
// background called every sample or never. Returns the samples taken.
int run_silent(imest_comm_t *c, int n, bool background)
{
  float d[3];
  const float i0[3] = {0.0f, 0.0f, 0.0f};
  int rc = 1, k = 0;
  for (; k < n && rc == 1; ++k) {
    rc = imest_comm_isr(c, i0, 560.0f, 0.0f, d);
    if (background) (void)imest_comm_background(c);
  }
  return k;
}

} // namespace

TEST(CommissionGuard, ConfigCheckNamesTheField)
{
  imest_comm_config_t cc;
  imest_comm_config_default(&cc);
  const char *field = nullptr;
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "i_max_a"); // required
  cc = base_config();
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_OK);
  EXPECT_EQ(field, nullptr);
  cc.allow_rotation = 1;
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "rated_voltage_v");
  cc = base_config();
  cc.n_sensors = 1u;
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "n_sensors");
  cc = base_config();
  cc.pwm_hz = 1000.0f; // slower than the ISR
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_ERR_CONFIG);
  EXPECT_STREQ(field, "pwm_hz");
  static imest_comm_t c;
  EXPECT_EQ(imest_comm_init(&c, &cc), IMEST_ERR_CONFIG);
  EXPECT_EQ(imest_comm_init(nullptr, &cc), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_config_check(nullptr, nullptr), IMEST_ERR_NULL);
}

// Every bound of the config check at its edge, just inside and just outside, and the field it
// names: the check is one table walked in order (commission_init.c), so a row's bound, open end,
// fs_hz scaling or rotation condition written wrong shows here.
TEST(CommissionGuard, ConfigCheckBoundsAtTheirEdges)
{
  struct edge {
    float imest_comm_config_t::*f;
    const char *name;
    float value;
    bool ok;
  };
  const float inf = INFINITY, nan = NAN, below_1e9 = std::nextafter(1.0e9f, 0.0f);
  const edge edges[] = {
      {&imest_comm_config_t::fs_hz, "fs_hz", 1000.0f, true},
      {&imest_comm_config_t::fs_hz, "fs_hz", 999.9f, false},
      {&imest_comm_config_t::fs_hz, "fs_hz", 1.0e5f, true},
      {&imest_comm_config_t::fs_hz, "fs_hz", 1.0001e5f, false},
      {&imest_comm_config_t::fs_hz, "fs_hz", nan, false},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", 0.0f, true},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", 8000.0f, true},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", 7999.0f, false},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", 64.0f * 8000.0f, true},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", 64.01f * 8000.0f, false},
      {&imest_comm_config_t::pwm_hz, "pwm_hz", -1.0f, false},
      {&imest_comm_config_t::i_max_a, "i_max_a", 0.0f, false},
      {&imest_comm_config_t::i_max_a, "i_max_a", 1.0e5f, true},
      {&imest_comm_config_t::i_max_a, "i_max_a", 1.0001e5f, false},
      {&imest_comm_config_t::level_frac, "level_frac", 0.1f, true},
      {&imest_comm_config_t::level_frac, "level_frac", 0.099f, false},
      {&imest_comm_config_t::level_frac, "level_frac", 0.95f, true},
      {&imest_comm_config_t::level_frac, "level_frac", 0.951f, false},
      {&imest_comm_config_t::v_max_v, "v_max_v", 0.0f, true},
      {&imest_comm_config_t::v_max_v, "v_max_v", -1.0e-6f, false},
      {&imest_comm_config_t::v_max_v, "v_max_v", FLT_MAX, true},
      {&imest_comm_config_t::v_max_v, "v_max_v", inf, false},
      {&imest_comm_config_t::time_max_s, "time_max_s", 0.0f, false},
      {&imest_comm_config_t::time_max_s, "time_max_s", 3600.0f, true},
      {&imest_comm_config_t::time_max_s, "time_max_s", 3601.0f, false},
      {&imest_comm_config_t::tr_max_s, "tr_max_s", 0.01f, true},
      {&imest_comm_config_t::tr_max_s, "tr_max_s", 0.0099f, false},
      {&imest_comm_config_t::tr_max_s, "tr_max_s", 20.0f, true},
      {&imest_comm_config_t::tr_max_s, "tr_max_s", 20.01f, false},
      {&imest_comm_config_t::encoder_cpr, "encoder_cpr", 0.0f, true},
      {&imest_comm_config_t::encoder_cpr, "encoder_cpr", -1.0f, false},
      {&imest_comm_config_t::encoder_cpr, "encoder_cpr", below_1e9, true},
      {&imest_comm_config_t::encoder_cpr, "encoder_cpr", 1.0e9f, false},
      {&imest_comm_config_t::r_series_ohm, "r_series_ohm", 0.0f, true},
      {&imest_comm_config_t::r_series_ohm, "r_series_ohm", -1.0e-3f, false},
      {&imest_comm_config_t::r_series_ohm, "r_series_ohm", nan, false},
      {&imest_comm_config_t::rated_voltage_v, "rated_voltage_v", 0.0f, false},
      {&imest_comm_config_t::rated_freq_hz, "rated_freq_hz", 0.0f, false},
      {&imest_comm_config_t::rated_freq_hz, "rated_freq_hz", 799.9f, true}, /* below 0.1 fs_hz */
      {&imest_comm_config_t::rated_freq_hz, "rated_freq_hz", 800.0f, false},
      {&imest_comm_config_t::rated_speed_rpm, "rated_speed_rpm", 0.0f, true},
      {&imest_comm_config_t::rated_speed_rpm, "rated_speed_rpm", -1.0f, false},
      {&imest_comm_config_t::rated_speed_rpm, "rated_speed_rpm", 2999.0f, true}, /* below 60 f */
      {&imest_comm_config_t::rated_speed_rpm, "rated_speed_rpm", 3000.0f, false},
      {&imest_comm_config_t::speed_frac, "speed_frac", 0.05f, true},
      {&imest_comm_config_t::speed_frac, "speed_frac", 0.049f, false},
      {&imest_comm_config_t::speed_frac, "speed_frac", 1.0f, true},
      {&imest_comm_config_t::speed_frac, "speed_frac", 1.001f, false},
      {&imest_comm_config_t::ramp_s, "ramp_s", 0.1f, true},
      {&imest_comm_config_t::ramp_s, "ramp_s", 0.099f, false},
      {&imest_comm_config_t::ramp_s, "ramp_s", 60.0f, true},
      {&imest_comm_config_t::ramp_s, "ramp_s", 60.1f, false},
  };
  imest_comm_config_t rot = base_config();
  rot.allow_rotation = 1;
  rot.rated_voltage_v = 400.0f;
  rot.rated_freq_hz = 50.0f;
  rot.rated_speed_rpm = 1441.0f;
  const char *field = nullptr;
  ASSERT_EQ(imest_comm_config_check(&rot, &field), IMEST_OK);
  for (const edge &e : edges) {
    imest_comm_config_t cc = rot;
    cc.*e.f = e.value;
    const int rc = imest_comm_config_check(&cc, &field);
    EXPECT_EQ(rc, e.ok ? IMEST_OK : IMEST_ERR_CONFIG) << e.name << " = " << e.value;
    if (!e.ok) EXPECT_STREQ(field, e.name) << e.value;
  }
  // the rotating part's fields only with rotation allowed; n_sensors 2 or 3
  imest_comm_config_t cc = base_config();
  cc.rated_voltage_v = 0.0f;
  cc.rated_freq_hz = nan;
  EXPECT_EQ(imest_comm_config_check(&cc, &field), IMEST_OK);
  for (unsigned int n : {0u, 1u, 2u, 3u, 4u, 0xFFFFFFFFu}) {
    cc = base_config();
    cc.n_sensors = n;
    EXPECT_EQ(imest_comm_config_check(&cc, &field), n == 2u || n == 3u ? IMEST_OK : IMEST_ERR_CONFIG) << n;
  }
}

TEST(CommissionGuard, NonFiniteInputStopsWithZeroVoltage)
{
  static imest_comm_t c;
  const imest_comm_config_t cc = base_config();
  ASSERT_EQ(imest_comm_init(&c, &cc), IMEST_OK);
  float d[3];
  const float i0[3] = {0.0f, 0.0f, 0.0f};
  EXPECT_EQ(imest_comm_isr(&c, i0, 560.0f, 0.0f, d), 1);
  const float bad[3] = {0.0f, NAN, 0.0f};
  EXPECT_EQ(imest_comm_isr(&c, bad, 560.0f, 0.0f, d), 0);
  EXPECT_FLOAT_EQ(d[0], 0.5f);
  EXPECT_FLOAT_EQ(d[1], 0.5f);
  EXPECT_FLOAT_EQ(d[2], 0.5f);
  imest_comm_status_t st;
  ASSERT_EQ(imest_comm_status(&c, &st), IMEST_OK);
  EXPECT_EQ(st.state, IMEST_COMM_FAILED);
  EXPECT_EQ(st.reason, IMEST_COMM_REASON_INPUT_FAULT);
  EXPECT_EQ(imest_comm_isr(&c, i0, 560.0f, 0.0f, d), 0); // stays stopped
}

TEST(CommissionGuard, OvercurrentStops)
{
  static imest_comm_t c;
  const imest_comm_config_t cc = base_config();
  ASSERT_EQ(imest_comm_init(&c, &cc), IMEST_OK);
  float d[3];
  const float i0[3] = {0.0f, 0.0f, 0.0f}, big[3] = {10.5f, -5.0f, -5.5f};
  EXPECT_EQ(imest_comm_isr(&c, i0, 560.0f, 0.0f, d), 1);
  EXPECT_EQ(imest_comm_isr(&c, big, 560.0f, 0.0f, d), 0);
  imest_comm_result_t r;
  ASSERT_EQ(imest_comm_result(&c, &r), IMEST_OK);
  EXPECT_EQ(r.state, IMEST_COMM_FAILED);
  EXPECT_EQ(r.reason, IMEST_COMM_REASON_OVERCURRENT);
  EXPECT_FLOAT_EQ(r.i_peak_a, 10.5f);
  EXPECT_FALSE(r.valid);
  imest_config_t cfg;
  imest_config_default(&cfg);
  EXPECT_EQ(imest_comm_apply(&r, &cfg), IMEST_ERR_ARG); // nothing filled from a failed run
}

TEST(CommissionGuard, AbortAtAnySample)
{
  comm_sim_opts_t o = opts("4kw");
  imsim_config_t sc;
  ASSERT_EQ(comm_sim_config(&o, &sc), 0);
  imest_comm_config_t cc;
  comm_sim_comm_config(&o, &sc, &cc);
  static imest_comm_t c;
  static imsim_t sim;
  imsim_sample_t s;
  ASSERT_EQ(imest_comm_init(&c, &cc), IMEST_OK);
  ASSERT_EQ(imsim_init(&sim, &sc, &s), 0);
  float d[3];
  int n = 0;
  for (; n < 20000; ++n) { // into the staircase
    const float i[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
    ASSERT_EQ(imest_comm_isr(&c, i, (float)s.vdc_v, 0.0f, d), 1);
    (void)imest_comm_background(&c);
    const double dd[3] = {d[0], d[1], d[2]};
    imsim_set_duty(&sim, dd);
    imsim_step(&sim, &s);
  }
  imest_comm_status_t st;
  ASSERT_EQ(imest_comm_status(&c, &st), IMEST_OK);
  EXPECT_EQ(st.stage, IMEST_COMM_STAGE_STAIRCASE);
  EXPECT_GT(st.progress, 0.05f);
  EXPECT_LT(st.progress, 0.5f);
  EXPECT_EQ(imest_comm_abort(&c), IMEST_OK);
  const float i[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
  EXPECT_EQ(imest_comm_isr(&c, i, (float)s.vdc_v, 0.0f, d), 0);
  EXPECT_FLOAT_EQ(d[0], 0.5f);
  ASSERT_EQ(imest_comm_status(&c, &st), IMEST_OK);
  EXPECT_EQ(st.state, IMEST_COMM_ABORTED);
  EXPECT_EQ(st.reason, IMEST_COMM_REASON_ABORTED);
}

TEST(CommissionGuard, NoCurrentAnswerIsAnOpenPhase)
{
  // a plant that never answers (motor not connected): the pulses double up to half the bus,
  // then the wiring check says open phase
  static imest_comm_t c;
  const imest_comm_config_t cc = base_config();
  ASSERT_EQ(imest_comm_init(&c, &cc), IMEST_OK);
  const int n = run_silent(&c, 100000, true);
  imest_comm_result_t r;
  ASSERT_EQ(imest_comm_result(&c, &r), IMEST_OK);
  EXPECT_EQ(r.state, IMEST_COMM_FAILED);
  EXPECT_EQ(r.reason, IMEST_COMM_REASON_OPEN_PHASE);
  EXPECT_LT(n, 8000); // within a second
}

TEST(CommissionGuard, BackgroundNeverCalledTimesOut)
{
  static imest_comm_t c;
  const imest_comm_config_t cc = base_config();
  ASSERT_EQ(imest_comm_init(&c, &cc), IMEST_OK);
  const int n = run_silent(&c, 100000, false);
  imest_comm_status_t st;
  ASSERT_EQ(imest_comm_status(&c, &st), IMEST_OK);
  EXPECT_EQ(st.state, IMEST_COMM_FAILED);
  EXPECT_EQ(st.reason, IMEST_COMM_REASON_BACKGROUND);
  EXPECT_LT(n, 8000 * 12); // 10 s of waiting
}

TEST(CommissionGuard, NamesAndNullArguments)
{
  EXPECT_STREQ(imest_comm_reason_name(IMEST_COMM_REASON_WIRING), "wiring");
  EXPECT_STREQ(imest_comm_reason_name(IMEST_COMM_REASON_CURRENT_LIMIT_ROTATING), "current_limit_rotating");
  EXPECT_STREQ(imest_comm_reason_name(99), "unknown");
  EXPECT_STREQ(imest_comm_stage_name(IMEST_COMM_STAGE_STAIRCASE), "staircase");
  EXPECT_STREQ(imest_comm_state_name(IMEST_COMM_DONE), "done");
  float d[3];
  const float i0[3] = {0, 0, 0};
  EXPECT_EQ(imest_comm_isr(nullptr, i0, 1.0f, 0.0f, d), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_background(nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_abort(nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_status(nullptr, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_result(nullptr, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_comm_apply(nullptr, nullptr), IMEST_ERR_NULL);
}
