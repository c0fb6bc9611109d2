/* SPDX-License-Identifier: Apache-2.0 */
// Model checks: steady state against an independent equivalent circuit, docs/METHOD.md §9
// figures, DOL start, energy balance.
#include <gtest/gtest.h>

#include "common.hpp"

using namespace simtest;

namespace {
// Classic per-phase T-equivalent circuit, written independently of the simulator.
struct Ec {
  double speed_rpm, i_rms, torque;
};
Ec equivalent_circuit(const imsim_config_t &c, double vll, double f, double load)
{
  const double m = std::sqrt((1 - c.sigma) * c.ls_h * c.lr_h);
  const double lls = c.ls_h - m, llr = c.lr_h - m, rr = c.lr_h / c.tr_s;
  const double we = 2 * kPi * f, ws = we / c.pole_pairs;
  const double vph = vll / std::sqrt(3.0);
  auto eval = [&](double slip, double &irms, double &te) {
    const cd zr = rr / slip + cd(0, we * llr), zm = cd(0, we * m);
    const cd z = c.rs_ohm + cd(0, we * lls) + zm * zr / (zm + zr);
    const cd is = vph / z, ir = is * zm / (zm + zr);
    irms = std::abs(is);
    te = 3 * std::norm(ir) * rr / slip / ws;
  };
  // bisection on the stable branch: torque - load - friction = 0, slip in (0, s_breakdown)
  double lo = 1e-9, hi = 0.3, irms = 0, te = 0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    eval(mid, irms, te);
    const double w = ws * (1 - mid);
    if (te - load - c.b_nms * w > 0)
      hi = mid;
    else
      lo = mid;
  }
  const double slip = 0.5 * (lo + hi);
  eval(slip, irms, te);
  return {ws * (1 - slip) * 60 / (2 * kPi), irms, te};
}
} // namespace

TEST(SimModel, SteadyStateMatchesEquivalentCircuit)
{
  const imsim_config_t c = ideal();
  struct Case {
    double vll, f, load;
  } cases[] = {{230, 60, 2.064}, {115, 30, 2.064}, {230, 60, 0.5}, {200, 50, 1.5}};
  for (const auto &k : cases) {
    imsim_steady_t st;
    ASSERT_EQ(imsim_steady_state(&c, k.vll, k.f, k.load, &st), 0);
    const Ec ec = equivalent_circuit(c, k.vll, k.f, k.load);
    EXPECT_NEAR(st.speed_rpm, ec.speed_rpm, 1e-6 * ec.speed_rpm) << k.f << " Hz";
    EXPECT_NEAR(st.i_rms_phase, ec.i_rms, 1e-8) << k.f << " Hz";
    EXPECT_NEAR(st.torque_nm, ec.torque, 1e-8) << k.f << " Hz";
  }
}

TEST(SimModel, NameplateFiguresOfMathSection9)
{
  const imsim_config_t c = ideal();
  imsim_steady_t st;
  ASSERT_EQ(imsim_steady_state(&c, 230, 60, 2.064, &st), 0);
  EXPECT_NEAR(st.speed_rpm, 1760.8, 0.05);
  EXPECT_NEAR(st.i_rms_phase, 1.625, 0.0005);
  ASSERT_EQ(imsim_steady_state(&c, 115, 30, 2.064, &st), 0);
  EXPECT_NEAR(st.speed_rpm, 856.9, 0.05);
  EXPECT_NEAR(st.i_rms_phase, 1.624, 0.0005);
}

// Time domain: started in the phasor steady state, the simulation must stay there (slip,
// current amplitude and torque), which checks integrator and steady-state solver together.
TEST(SimModel, TimeDomainHoldsEquivalentCircuitSteadyState)
{
  imsim_config_t c = ideal();
  c.load_nm = 2.064;
  c.start = IMSIM_START_STEADY;
  const Ec ec = equivalent_circuit(c, 230, 60, 2.064);
  const auto s = run(c, 4000); // 1 s
  ASSERT_FALSE(s.empty());
  for (size_t k = 0; k < s.size(); k += 97) {
    EXPECT_NEAR(s[k].speed_rad_s * 30 / kPi, ec.speed_rpm, 1e-5);
    EXPECT_NEAR(std::abs(iab(s[k])) / std::sqrt(3.0), ec.i_rms, 1e-7);
    EXPECT_NEAR(s[k].torque_nm, ec.torque, 1e-6);
  }
}

TEST(SimModel, DirectOnLineStartOfExp1)
{
  const imsim_config_t c = ideal("exp1");
  const auto s = run(c, 8000); // 2 s
  ASSERT_FALSE(s.empty());
  double peak = 0;
  double t_at_speed = -1;
  for (const auto &x : s) {
    for (double i : x.i_abc_true) peak = std::max(peak, std::fabs(i));
    if (t_at_speed < 0 && x.speed_rad_s > 0.95 * 2 * kPi * 30) t_at_speed = x.t;
  }
  EXPECT_NEAR(peak, 16.4, 0.05); // docs/METHOD.md §9
  EXPECT_GT(t_at_speed, 0.03);
  EXPECT_LT(t_at_speed, 0.08); // "at speed in about 50 ms"
  imsim_steady_t st;
  ASSERT_EQ(imsim_steady_state(&c, 230, 60, 0, &st), 0);
  EXPECT_NEAR(s.back().speed_rad_s, st.speed_rad_s, 1e-6);
  EXPECT_DOUBLE_EQ(s[0].t, 0.0);
  EXPECT_EQ(s[0].speed_rad_s, 0.0);
  EXPECT_EQ(s[0].psi_r_wb, 0.0);
}

// Energy balance: input energy = magnetic + kinetic energy change + copper losses + friction
// + load work. Densely sampled smooth supply, Simpson quadrature.
TEST(SimModel, EnergyBalance)
{
  imsim_config_t c = ideal("exp1");
  c.fs_hz = 40000;
  c.steps_per_sample = 1;
  c.load_nm = 0.8;
  c.load_on_s = 0.1;
  c.load_ramp_s = 0.0;
  const long n = 12000; // 0.3 s, even number of intervals
  const auto s = run(c, n);
  ASSERT_FALSE(s.empty());
  const double m = std::sqrt((1 - c.sigma) * c.ls_h * c.lr_h);
  const double sl = c.sigma * c.ls_h;
  auto p_in = [](const imsim_sample_t &x) {
    return x.u_ab_true[0] * x.i_ab_true[0] + x.u_ab_true[1] * x.i_ab_true[1];
  };
  auto p_out = [&](const imsim_sample_t &x) {
    return x.p_cu_stator_w + x.p_cu_rotor_w + c.b_nms * x.speed_rad_s * x.speed_rad_s +
           x.load_nm * x.speed_rad_s;
  };
  auto stored = [&](const imsim_sample_t &x) {
    return 0.5 * sl * std::norm(iab(x)) + 0.5 * std::norm(psiab(x)) / c.lr_h +
           0.5 * c.j_kgm2 * x.speed_rad_s * x.speed_rad_s;
  };
  (void)m;
  // The load steps at t = 0.1 s (a sample instant, 4000): integrate the two parts separately.
  auto simpson = [&](auto f, long a, long b) {
    double acc = f(s[size_t(a)]) + f(s[size_t(b)]);
    for (long k = a + 1; k < b; ++k) acc += (k - a) % 2 ? 4 * f(s[size_t(k)]) : 2 * f(s[size_t(k)]);
    return acc / c.fs_hz / 3;
  };
  // Load torque is held over each sample period at its mid-interval value, so at the step
  // sample the recorded load_nm is the new value; integrate piecewise around it.
  const double e_in = simpson(p_in, 0, 4000) + simpson(p_in, 4000, n);
  auto p_out_before = [&](const imsim_sample_t &x) {
    return p_out(x) - (x.t >= 0.1 - 1e-12 ? x.load_nm * x.speed_rad_s : 0.0);
  };
  const double e_out = simpson(p_out_before, 0, 4000) + simpson(p_out, 4000, n);
  const double de = stored(s.back()) - stored(s.front());
  EXPECT_GT(e_in, 50.0);
  EXPECT_NEAR(e_in, e_out + de, 2e-6 * e_in) << "e_in " << e_in << " e_out " << e_out << " dE " << de;
}
