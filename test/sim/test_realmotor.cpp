/* SPDX-License-Identifier: Apache-2.0 */
// Real-motor effects (saturation, iron loss, double cage): the derived sizes against their
// definitions, the time-domain steady state against an independent phasor equivalent circuit
// with the same effects, an energy balance, integration-step accuracy, and "off" = unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "common.hpp"
#include "imsim_cli.h"

using namespace simtest;

namespace {
// The drive preset on an ideal sine at its supply, steady start, exact samples, cold.
imsim_config_t real_sine(const char *preset, double sat, double fe, double cage)
{
  imsim_config_t c = ideal(preset);
  c.supply = IMSIM_SUPPLY_SINE;
  c.timing = IMSIM_TIMING_IDEAL;
  c.start = IMSIM_START_STEADY;
  c.sat_fraction = sat;
  c.iron_loss_fraction = fe;
  c.rotor_cage_ratio = cage;
  return c;
}

// Per-phase equivalent circuit written here from the parameters' definitions (sim/README.md):
// R_S + j X_ls in series with [R_fe || j X_m(|psi_m|) || rotor], the rotor R1/s + j X1 in
// parallel with R2/s + j X2; |psi_m| = |E| / w_e by fixed-point iteration. Power-invariant
// amplitudes (|u| = V_ll). Returns the stator current phasor for u = vll + j0 at speed w.
struct Ec {
  cd is, e;
  double psi_m;
};
Ec circuit(const imsim_config_t &c, const imsim_real_params_t &p, bool with_fe, bool with_cage2, double vll,
           double f, double w)
{
  const double we = 2 * kPi * f, slip = (we - c.pole_pairs * w) / we;
  cd zr = p.r1_ohm / slip + cd(0, we * p.l1_h);
  if (with_cage2 && p.r2_ohm > 0) {
    const cd z2 = p.r2_ohm / slip + cd(0, we * p.l2_h);
    zr = zr * z2 / (zr + z2);
  }
  double psi = p.psi_n_wb;
  Ec out{};
  for (int it = 0; it < 500; ++it) {
    const double lm = p.lm0_h / (1 + p.sat_a * std::pow(psi / p.psi_n_wb, 6));
    cd ym = 1.0 / cd(0, we * lm);
    if (with_fe && p.rfe_ohm > 0) ym += 1.0 / p.rfe_ohm;
    const cd zp = 1.0 / (ym + 1.0 / zr);
    out.is = vll / (c.rs_ohm + cd(0, we * p.lls_h) + zp);
    out.e = out.is * zp;
    const double next = std::abs(out.e) / we;
    psi = 0.5 * (psi + next); // damped: the map's slope is near -1 at strong saturation
  }
  out.psi_m = psi;
  return out;
}

double lm_static(const imsim_real_params_t &p, double psi)
{
  return p.lm0_h / (1 + p.sat_a * std::pow(psi / p.psi_n_wb, 6));
}
} // namespace

// The sizes are what the options promise: L_m(psi_n) = (1 - F) L_m0 = M, R_fe dissipates
// F x P_n at E_n = w_n psi_n, and the double cage has the single cage's DC resistance and DC
// leakage and RATIO x that resistance at f_n.
TEST(SimRealMotor, DerivedSizesMeetTheirDefinitions)
{
  const imsim_config_t c = real_sine("4kw", 0.2, 0.03, 1.4);
  imsim_real_params_t p;
  ASSERT_EQ(imsim_real_params(&c, &p), 0);
  const double m = std::sqrt((1 - c.sigma) * c.ls_h * c.lr_h);
  EXPECT_NEAR(lm_static(p, p.psi_n_wb), m, 1e-12 * m);
  EXPECT_NEAR(lm_static(p, p.psi_n_wb) / p.lm0_h, 0.8, 1e-12);
  EXPECT_NEAR(p.lls_h, c.ls_h - m, 1e-15);
  const double en = 2 * kPi * 50 * p.psi_n_wb;
  EXPECT_NEAR(en * en / p.rfe_ohm, 0.03 * 4000, 1e-9);
  const double rr = c.lr_h / c.tr_s;
  auto zr = [&](double wsl) {
    const cd z1(p.r1_ohm, wsl * p.l1_h), z2(p.r2_ohm, wsl * p.l2_h);
    return z1 * z2 / (z1 + z2);
  };
  EXPECT_NEAR(zr(1e-6).real(), rr, 1e-9 * rr);
  EXPECT_NEAR(zr(1e-3).imag() / 1e-3, p.llr_h, 1e-6 * p.llr_h);
  EXPECT_NEAR(zr(2 * kPi * 50).real() / rr, 1.4, 1e-9);
  // psi_n: |psi_m| of the linear machine at the rated point (400 V, 50 Hz, rated torque)
  imsim_config_t lin = c;
  lin.sat_fraction = lin.iron_loss_fraction = lin.rotor_cage_ratio = 0;
  imsim_steady_t st;
  ASSERT_EQ(imsim_steady_state(&lin, 400, 50, c.rated_torque_nm, &st), 0);
  const cd i(st.i_ab[0], st.i_ab[1]), psir(st.psi_ab[0], st.psi_ab[1]);
  EXPECT_NEAR(p.psi_n_wb, m * std::abs(i + (psir - m * i) / c.lr_h), 1e-12);
  // effects off: nothing derived
  imsim_config_t off = ideal("4kw");
  ASSERT_EQ(imsim_real_params(&off, &p), 0);
  EXPECT_EQ(p.lm0_h, 0.0);
  // an unreachable double-cage ratio is refused with the reachable maximum
  imsim_config_t bad = real_sine("4kw", 0, 0, 3.5);
  static imsim_t sim;
  EXPECT_EQ(imsim_init(&sim, &bad, nullptr), -1);
  EXPECT_NE(std::strstr(imsim_error(&sim), "at most"), nullptr) << imsim_error(&sim);
}

// Started in the steady state of the simulator's own phasor solver, the flux-linkage model run
// for 0.5 s (about 4 rotor time constants) must sit on the independent circuit above: stator
// current magnitude and phase (against the voltage) within 0.2 %, evaluated at the simulated
// speed. The circuit without the iron-loss branch or without the second cage misses by more,
// so the comparison can fail.
TEST(SimRealMotor, SteadyStateMatchesEquivalentCircuitWithEffects)
{
  struct Case {
    const char *preset;
    double sat, fe, cage;
  } cases[] = {{"4kw", 0.25, 0.035, 1.3},
               {"4kw", 0.2, 0, 0},
               {"4kw", 0, 0.04, 0},
               {"4kw", 0, 0, 1.5},
               {"37kw", 0.18, 0.02, 1.8}};
  for (const auto &k : cases) {
    const imsim_config_t c = real_sine(k.preset, k.sat, k.fe, k.cage);
    imsim_real_params_t p;
    ASSERT_EQ(imsim_real_params(&c, &p), 0);
    const auto s = run(c, static_cast<long>(0.5 * c.fs_hz));
    ASSERT_FALSE(s.empty()) << k.preset;
    for (size_t q = s.size() - 40; q < s.size(); q += 13) {
      const imsim_sample_t &x = s[q];
      const cd u(x.u_ab_true[0], x.u_ab_true[1]), i = iab(x);
      const cd y_sim = i / u; // admittance seen by the supply, independent of its phase
      const Ec ec = circuit(c, p, true, true, c.vll_v, c.freq_hz, x.speed_rad_s);
      const cd y_ec = ec.is / c.vll_v;
      const std::string what = std::string(k.preset) + " sat " + std::to_string(k.sat) + " fe " +
                               std::to_string(k.fe) + " cage " + std::to_string(k.cage);
      EXPECT_NEAR(std::abs(y_sim) / std::abs(y_ec), 1.0, 2e-3) << what;
      EXPECT_NEAR(std::arg(y_sim) / std::arg(y_ec), 1.0, 2e-3) << what;
      EXPECT_NEAR(x.psi_m_wb / ec.psi_m, 1.0, 2e-3) << what;
      if (k.fe > 0) {
        const Ec no_fe = circuit(c, p, false, true, c.vll_v, c.freq_hz, x.speed_rad_s);
        EXPECT_GT(std::abs(std::abs(no_fe.is / c.vll_v) / std::abs(y_sim) - 1.0) +
                      std::abs(std::arg(no_fe.is / c.vll_v) / std::arg(y_sim) - 1.0),
                  2e-3)
            << what;
      }
    }
  }
  // The double cage at standstill (locked rotor, 50 Hz, reduced voltage): here its deep-bar
  // resistance matters, and the single-cage circuit misses by far more than 0.2 %.
  imsim_config_t c = real_sine("4kw", 0, 0, 1.5);
  c.start = IMSIM_START_REST;
  c.vll_v = 80;
  c.j_kgm2 = 1e6; // the rotor stays at rest
  imsim_real_params_t p;
  ASSERT_EQ(imsim_real_params(&c, &p), 0);
  const auto s = run(c, static_cast<long>(1.2 * c.fs_hz));
  ASSERT_FALSE(s.empty());
  const imsim_sample_t &x = s.back();
  const cd y_sim = iab(x) / cd(x.u_ab_true[0], x.u_ab_true[1]);
  const Ec ec = circuit(c, p, true, true, c.vll_v, c.freq_hz, x.speed_rad_s);
  EXPECT_NEAR(std::abs(y_sim) / std::abs(ec.is / c.vll_v), 1.0, 2e-3);
  EXPECT_NEAR(std::arg(y_sim) / std::arg(ec.is / c.vll_v), 1.0, 2e-3);
  const Ec single = circuit(c, p, true, false, c.vll_v, c.freq_hz, x.speed_rad_s);
  EXPECT_GT(std::abs(std::abs(single.is / c.vll_v) / std::abs(y_sim) - 1.0), 2e-3);
}

// Energy balance over 0.1 s (5 periods) of the steady state with all three effects:
// int u.i = int (P_cu,S + P_cu,R1 + P_cu,R2 + P_fe + T_e w) + delta W_mag (Simpson). Leaving
// out the iron loss misses by far more than the 0.5 % tolerance.
TEST(SimRealMotor, EnergyBalanceWithEffects)
{
  imsim_config_t c = real_sine("4kw", 0.25, 0.035, 1.3);
  c.load_nm = 0.8 * c.rated_torque_nm; // steady start at this load: d(stored energy) is ~0
  const long n = 800;                  // 0.1 s at 8 kHz, an even number of intervals
  const auto s = run(c, n);
  ASSERT_FALSE(s.empty());
  auto simpson = [&](auto f) {
    double acc = f(s[0]) + f(s[size_t(n)]);
    for (long k = 1; k < n; ++k) acc += (k % 2 ? 4 : 2) * f(s[size_t(k)]);
    return acc / c.fs_hz / 3;
  };
  const double e_in = simpson([](const imsim_sample_t &x) {
    return x.u_ab_true[0] * x.i_ab_true[0] + x.u_ab_true[1] * x.i_ab_true[1];
  });
  const double e_cu = simpson([](const imsim_sample_t &x) { return x.p_cu_stator_w + x.p_cu_rotor_w; });
  const double e_fe = simpson([](const imsim_sample_t &x) { return x.p_fe_w; });
  const double e_mech = simpson([](const imsim_sample_t &x) { return x.torque_nm * x.speed_rad_s; });
  const double dw = s.back().w_mag_j - s.front().w_mag_j;
  const double e_out = e_cu + e_fe + e_mech + dw;
  EXPECT_GT(e_in, 300.0);
  EXPECT_NEAR(e_out / e_in, 1.0, 5e-3)
      << "in " << e_in << " cu " << e_cu << " fe " << e_fe << " mech " << e_mech << " dW " << dw;
  EXPECT_GT(std::abs((e_out - e_fe) / e_in - 1.0), 5e-3);
  std::printf("[ energy   ] 4 kW, all effects, sine: out / in - 1 = %.1e (in %.1f J, iron %.1f J)\n",
              e_out / e_in - 1.0, e_in, e_fe);
  // A direct-on-line start from rest (0.2 s, 4 kW, all effects): the flux builds up through
  // saturation, so the stored energy must be the field energy int i_m dpsi. Most of the input
  // goes into the rotor's kinetic energy here, so this case is held to 1e-4 (measured 1.1e-6,
  // Simpson on the transient); the co-energy int psi di_m in its place would miss by 2.5e-3.
  {
    imsim_config_t d = real_sine("4kw", 0.25, 0.035, 1.3);
    d.start = IMSIM_START_REST;
    d.load_nm = 0;
    const long nd = 1600;
    const auto t = run(d, nd);
    ASSERT_FALSE(t.empty());
    auto simp = [&](auto f) {
      double acc = f(t[0]) + f(t[size_t(nd)]);
      for (long k = 1; k < nd; ++k) acc += (k % 2 ? 4 : 2) * f(t[size_t(k)]);
      return acc / d.fs_hz / 3;
    };
    const double in = simp([](const imsim_sample_t &x) {
      return x.u_ab_true[0] * x.i_ab_true[0] + x.u_ab_true[1] * x.i_ab_true[1];
    });
    const double out = simp([](const imsim_sample_t &x) {
      return x.p_cu_stator_w + x.p_cu_rotor_w + x.p_fe_w + x.torque_nm * x.speed_rad_s;
    });
    const double dwm = t.back().w_mag_j - t.front().w_mag_j;
    EXPECT_GT(dwm, 1.0);
    EXPECT_NEAR((out + dwm) / in, 1.0, 1e-4) << "in " << in << " out " << out << " dW " << dwm;
    // the co-energy instead: psi_m i_m - W_m at the end differs from W_m by more than 1e-3
    imsim_real_params_t p;
    ASSERT_EQ(imsim_real_params(&d, &p), 0);
    const double x = t.back().psi_m_wb, r6 = std::pow(x / p.psi_n_wb, 6);
    const double wm = 0.5 * x * x / p.lm0_h * (1 + p.sat_a / 4 * r6);
    const double coen = x * x / p.lm0_h * (1 + p.sat_a * r6) - wm;
    EXPECT_GT(std::abs(coen - wm), 1e-3 * in);
  }
  // and the mechanical side: T_e w = load + friction power + d(kinetic)/dt
  const double e_load =
      simpson([&](const imsim_sample_t &x) { return (x.load_nm + c.b_nms * x.speed_rad_s) * x.speed_rad_s; });
  const double dkin =
      0.5 * c.j_kgm2 * (std::pow(s.back().speed_rad_s, 2) - std::pow(s.front().speed_rad_s, 2));
  EXPECT_NEAR((e_load + dkin) / e_mech, 1.0, 5e-3);
}

// Integration step: the default sub-steps against at least 4x finer ones, 4 kW drive preset
// (PWM, firmware timing) with all effects, 0.05 s from the steady state at rated load.
// The iron loss column is the loss over the sample period, not R_fe |i_fe|^2 at the sample
// instant: with PWM the EMF across R_fe carries the carrier's ripple, and a sample synchronous
// with the carrier always sees it at a zero vector, where the EMF is smallest. On an ideal
// inverter (no dead time, no drops: the fundamental is the commanded one) the loss is the
// fundamental's (the phasor solution's) plus the ripple's, so it cannot be below the phasor's
// (measured: 144 W against 135 W; the instant's value read 88 W).
TEST(SimRealMotor, IronLossIsThePeriodsLossWithPwm)
{
  imsim_config_t c = ideal("4kw");
  c.supply = IMSIM_SUPPLY_PWM;
  c.start = IMSIM_START_STEADY;
  c.iron_loss_fraction = 0.035;
  c.load_nm = 0.75 * c.rated_torque_nm;
  imsim_steady_t st;
  ASSERT_EQ(imsim_steady_state(&c, c.vll_v, c.freq_hz, c.load_nm, &st), 0);
  const long n = long(0.1 * c.fs_hz); // 5 periods of 50 Hz
  const auto s = run(c, n);
  ASSERT_EQ(s.size(), size_t(n + 1));
  double mean = 0;
  for (long k = 1; k <= n; ++k) mean += s[size_t(k)].p_fe_w / double(n);
  EXPECT_GT(st.p_fe_w, 10.0);
  EXPECT_GT(mean / st.p_fe_w, 1.0) << mean << " W against the fundamental's " << st.p_fe_w << " W";
  EXPECT_LT(mean / st.p_fe_w, 2.0) << mean << " W against the fundamental's " << st.p_fe_w << " W";
  std::printf("[ iron     ] 4 kW, 8 kHz PWM: %.2f W per period, fundamental %.2f W\n", mean, st.p_fe_w);
}

TEST(SimRealMotor, DefaultStepAgreesWithFinerStep)
{
  imsim_config_t c = ideal("4kw");
  imsim_config_real_motor(&c);
  imsim_real_params_t p;
  ASSERT_EQ(imsim_real_params(&c, &p), 0);
  const long n = static_cast<long>(0.05 * c.fs_hz);
  const auto a = run(c, n);
  imsim_config_t f = c;
  // pieces of a half carrier period are at most 62.5 us long: this forces h <= h_max / 4
  f.rk4_substeps = static_cast<int>(std::ceil(62.5e-6 / p.h_max_s)) * 4;
  const auto b = run(f, n);
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  double di = 0, ipk = 0, dw = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    di = std::max(di, std::abs(iab(a[k]) - iab(b[k])));
    ipk = std::max(ipk, std::abs(iab(b[k])));
    dw = std::max(dw, std::abs(a[k].speed_rad_s - b[k].speed_rad_s));
  }
  EXPECT_LT(di / ipk, 1e-6) << "current error " << di << " of " << ipk;
  EXPECT_LT(dw, 1e-8 * b.back().speed_rad_s) << "speed error " << dw;
  RecordProperty("current_rel_err", std::to_string(di / ipk));
}

// Effects off: the new truth is NaN and the CSV keeps its columns; on: finite.
TEST(SimRealMotor, TruthColumnsOnlyWithEffects)
{
  const auto off = run(ideal("4kw"), 4);
  ASSERT_FALSE(off.empty());
  EXPECT_TRUE(std::isnan(off.back().psi_m_wb));
  EXPECT_TRUE(std::isnan(off.back().p_fe_w));
  imsim_config_t c = ideal("4kw");
  imsim_config_real_motor(&c);
  const auto on = run(c, 4);
  ASSERT_FALSE(on.empty());
  EXPECT_GT(on.back().psi_m_wb, 1.0);
  EXPECT_GT(on.back().p_fe_w, 0.0);
  // T_R_true_s = (L_m(|psi_m|) + L_lr,eff) / R_R,eff at the slip frequency
  EXPECT_NEAR(on.back().tr_s, on.back().lr_eff_h / on.back().rr_eff_ohm, 1e-12);
  EXPECT_TRUE(std::isnan(off.back().tr_ifoc_s));
  EXPECT_TRUE(std::isfinite(on.back().tr_ifoc_s));
}

// T_R_ifoc_s: without iron loss it is T_R_true_s (saturation and the double cage change L_R
// and R_R, not the form of the slip relation); with iron loss it is the T_R for which an IFOC's
// slip relation omega_sl = i_q / (T_R i_d) holds, computed here from its definition on the
// simulated state: i_d, i_q the true stator current in the frame of the true rotor flux
// (psi_ab: for a single cage psi_R1 = psi_m + L_lr i_R, in which the rotor current is in
// quadrature), omega_sl that frame's rotation over a sample less n_p omega. On the ideal sine in
// the steady state, 4 kW at half its rated torque with saturation and iron loss. The iron loss
// makes it differ from L_R,eff / R_R,eff by several percent (asserted > 2 %: otherwise this
// test could not tell the two apart).
TEST(SimRealMotor, IfocTrHoldsTheSlipRelation)
{
  for (const double cage : {0.0, 1.3}) {
    const imsim_config_t c0 = real_sine("4kw", 0.25, 0.0, cage);
    const auto a = run(c0, 400);
    ASSERT_FALSE(a.empty());
    for (size_t k = 1; k < a.size(); ++k) EXPECT_DOUBLE_EQ(a[k].tr_ifoc_s, a[k].tr_s);
  }
  imsim_config_t c = real_sine("4kw", 0.25, 0.035, 0.0);
  c.load_nm = 0.5 * c.rated_torque_nm;
  const long n = 2000;
  const auto s = run(c, n);
  ASSERT_FALSE(s.empty());
  double def = 0, col = 0, tr = 0;
  for (long k = 1; k <= n; ++k) {
    const cd psi = psiab(s[static_cast<size_t>(k)]), prev = psiab(s[static_cast<size_t>(k - 1)]);
    const cd idq = iab(s[static_cast<size_t>(k)]) * std::conj(psi) / std::abs(psi);
    const double wsl = std::arg(psi / prev) * c.fs_hz - c.pole_pairs * s[static_cast<size_t>(k)].speed_rad_s;
    def += idq.imag() / (wsl * idq.real());
    col += s[static_cast<size_t>(k)].tr_ifoc_s;
    tr += s[static_cast<size_t>(k)].tr_s;
  }
  EXPECT_NEAR(col / def, 1.0, 1e-4) << "T_R_ifoc " << col / n << " s, from the definition " << def / n;
  EXPECT_GT(col / tr, 1.02) << "T_R_ifoc " << col / n << " s, L_R/R_R " << tr / n;
  RecordProperty("tr_ifoc_over_lr_rr", std::to_string(col / tr));
}

// The flags: --real-motor applies the preset's sizes and later flags override them; --rotor
// parses single|double-cage:RATIO; bad values are refused.
TEST(SimRealMotor, CliFlags)
{
  auto parse = [](std::vector<std::string> args, imsim_config_t &c) {
    std::vector<char *> argv;
    static std::string prog = "imest-sim";
    argv.push_back(prog.data());
    for (auto &a : args) argv.push_back(a.data());
    imsim_cli_opts_t o;
    char err[256];
    return imsim_cli_parse(static_cast<int>(argv.size()), argv.data(), &c, &o, err, sizeof err);
  };
  imsim_config_t c;
  ASSERT_EQ(parse({"--preset", "37kw", "--real-motor", "--iron-loss", "0.01"}, c), 0);
  EXPECT_EQ(c.sat_fraction, 0.18);
  EXPECT_EQ(c.iron_loss_fraction, 0.01);
  EXPECT_EQ(c.rotor_cage_ratio, 1.8);
  ASSERT_EQ(parse({"--preset", "4kw", "--rotor=double-cage:1.45", "--saturation", "0.2"}, c), 0);
  EXPECT_EQ(c.rotor_cage_ratio, 1.45);
  EXPECT_EQ(c.sat_fraction, 0.2);
  EXPECT_EQ(c.iron_loss_fraction, 0.0);
  ASSERT_EQ(parse({"--preset", "4kw", "--real-motor", "--rotor", "single"}, c), 0);
  EXPECT_EQ(c.rotor_cage_ratio, 0.0);
  EXPECT_NE(parse({"--rotor", "double-cage:1"}, c), 0);
  EXPECT_NE(parse({"--rotor", "deep-bar"}, c), 0);
  EXPECT_NE(parse({"--saturation", "0.6"}, c), 0);
  EXPECT_NE(parse({"--iron-loss", "-0.01"}, c), 0);
  // the paper's motor gets its rated point from --real-motor
  ASSERT_EQ(parse({"--preset", "exp1", "--real-motor"}, c), 0);
  EXPECT_EQ(c.rated_voltage_v, 230.0);
  EXPECT_EQ(c.rated_torque_nm, 2.064);
  EXPECT_EQ(std::string(imsim_cli_header_real()), ",psi_m_wb,lm_h,lr_eff_h,rr_eff_ohm,p_fe_w,T_R_ifoc_s");
}

#ifdef IMEST_SIM_EXE
// With an effect on, the CSV header and every row carry the six real-motor columns.
TEST(SimRealMotor, CsvHasRealColumnsWhenOn)
{
  const std::string out = ::testing::TempDir() + "imsim_real.csv";
  const std::string cmd =
      std::string(IMEST_SIM_EXE) + " --preset 4kw --real-motor --duration 0.002 --out " + out;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream f(out);
  std::string header, row;
  std::getline(f, header);
  EXPECT_EQ(header, std::string(imsim_cli_header()) + imsim_cli_header_real());
  const auto ncol = std::count(header.begin(), header.end(), ',');
  int rows = 0;
  while (std::getline(f, row)) {
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), ncol);
    ++rows;
  }
  EXPECT_EQ(rows, 17);
}
#endif
