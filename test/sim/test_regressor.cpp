/* SPDX-License-Identifier: Apache-2.0 */
// y = W K (docs/METHOD.md §2) on simulated trajectories, with an independent double-precision
// implementation of W and y written here from docs/METHOD.md.
#include <gtest/gtest.h>

#include <array>

#include "common.hpp"

using namespace simtest;

namespace {
struct Rot { // rotor-frame signals and derivatives
  cd i, di, d2i, u, du;
  double w, dw;
};

// rms(y - W K) / rms(y) over the records, K built from (gamma, tr).
double residual_ratio(const std::vector<Rot> &r, double np, double s, double m, double gamma, double tr)
{
  const std::array<double, 8> K = {gamma, 1 / tr,     1 / (tr * tr),   gamma / tr,
                                   tr,    gamma * tr, gamma * tr * tr, tr * tr};
  const double n = np;
  double e2 = 0, y2 = 0;
  for (const Rot &q : r) {
    const double w = q.w, wd = q.dw;
    const double ix = q.i.real(), iy = q.i.imag(), dix = q.di.real(), diy = q.di.imag();
    const double d2ix = q.d2i.real(), d2iy = q.d2i.imag(), ux = q.u.real(), uy = q.u.imag();
    const double dux = q.du.real(), duy = q.du.imag();
    const double y1 = d2ix - n * w * diy - n * wd * iy - n * n * m * w * w * ix - dux / s;
    const double y2v = d2iy + n * w * dix + n * wd * ix - n * n * m * w * w * iy - duy / s;
    std::array<double, 8> W1 = {-dix,
                                -dix + n * (1 + m) * w * iy + ux / s,
                                m * ix,
                                -ix,
                                n * wd * (diy - uy / s) +
                                    n * n * (w * wd * ix - w * w * dix + w * w * ux / s) +
                                    n * n * n * (1 + m) * w * w * w * iy,
                                n * wd * iy - n * n * w * w * ix,
                                n * n * (w * wd * ix - w * w * dix),
                                n * n * (w * wd * dix - w * w * d2ix + (w * w * dux - w * wd * ux) / s) +
                                    n * n * n * w * w * w * diy};
    std::array<double, 8> W2 = {-diy,
                                -diy - n * (1 + m) * w * ix + uy / s,
                                m * iy,
                                -iy,
                                -n * wd * (dix - ux / s) +
                                    n * n * (w * wd * iy - w * w * diy + w * w * uy / s) -
                                    n * n * n * (1 + m) * w * w * w * ix,
                                -n * wd * ix - n * n * w * w * iy,
                                n * n * (w * wd * iy - w * w * diy),
                                n * n * (w * wd * diy - w * w * d2iy + (w * w * duy - w * wd * uy) / s) -
                                    n * n * n * w * w * w * dix};
    double r1 = y1, r2 = y2v;
    for (int k = 0; k < 8; ++k) {
      r1 -= W1[size_t(k)] * K[size_t(k)];
      r2 -= W2[size_t(k)] * K[size_t(k)];
    }
    e2 += r1 * r1 + r2 * r2;
    y2 += y1 * y1 + y2v * y2v;
  }
  return std::sqrt(e2 / y2);
}
} // namespace

// Model-exact derivatives from the simulated state (eq. (1) differentiated here, independently),
// rotated with the exact derivative of the rotation.
TEST(SimRegressor, ExactDerivativesSatisfyYEqualsWK)
{
  imsim_config_t c = ideal("exp1");
  c.fs_hz = 20000;
  const auto smp = run(c, 4000); // 0.2 s DOL start
  ASSERT_FALSE(smp.empty());
  const double np = c.pole_pairs, sl = c.sigma * c.ls_h;
  const double M = std::sqrt((1 - c.sigma) * c.ls_h * c.lr_h);
  const double tr = c.tr_s, beta = M / (c.sigma * c.ls_h * c.lr_h);
  const double gamma = c.rs_ohm / sl + (1 - c.sigma) / (c.sigma * tr);
  const double we = 2 * kPi * c.freq_hz;
  std::vector<Rot> rec;
  for (size_t k = 1; k < smp.size(); ++k) {
    const imsim_sample_t &s = smp[k];
    const cd i = iab(s), psi = psiab(s), u(s.u_ab_true[0], s.u_ab_true[1]);
    const double w = s.speed_rad_s, wd = s.accel_rad_s2, th = s.theta_true;
    const cd j(0, 1);
    const cd du = j * we * u;
    const cd di = u / sl - gamma * i + beta * (1 / tr - j * np * w) * psi;
    const cd dpsi = (M / tr) * i + (-1 / tr + j * np * w) * psi;
    const cd d2i = du / sl - gamma * di + beta * (1 / tr - j * np * w) * dpsi - j * np * wd * beta * psi;
    const cd r = std::exp(-j * np * th); // x_xy = r x_ab
    const double ph = np * w, phd = np * wd;
    Rot q;
    q.i = r * i;
    q.di = r * (di - j * ph * i);
    q.d2i = r * (d2i - 2.0 * j * ph * di - j * phd * i - ph * ph * i);
    q.u = r * u;
    q.du = r * (du - j * ph * u);
    q.w = w;
    q.dw = wd;
    rec.push_back(q);
  }
  const double m = (1 - c.sigma) / c.sigma;
  const double exact = residual_ratio(rec, np, sl, m, gamma, tr);
  EXPECT_LT(exact, 1e-10);
  // for scale: a 1 % error in T_R (gamma consistent with it) gives a large residual
  const double tr2 = tr * 1.01, gamma2 = c.rs_ohm / sl + (1 - c.sigma) / (c.sigma * tr2);
  EXPECT_GT(residual_ratio(rec, np, sl, m, gamma2, tr2), 0.05);
}

// The same with derivatives taken by finite differences of the simulated (sampled) currents
// and angle: checks that the simulator's trajectory itself obeys the model to the accuracy
// the estimator can see.
TEST(SimRegressor, FiniteDifferenceDerivativesOfSimulatedTrajectory)
{
  imsim_config_t c = ideal("exp1");
  c.fs_hz = 100000;
  c.steps_per_sample = 1;
  const auto smp = run(c, 20000); // 0.2 s
  ASSERT_FALSE(smp.empty());
  const double np = c.pole_pairs, sl = c.sigma * c.ls_h;
  const double tr = c.tr_s, gamma = c.rs_ohm / sl + (1 - c.sigma) / (c.sigma * tr);
  const double T = 1 / c.fs_hz, we = 2 * kPi * c.freq_hz;
  const cd j(0, 1);
  std::vector<Rot> rec;
  // rotor-frame signals, then 4th-order central differences
  std::vector<cd> ixy(smp.size()), uxy(smp.size());
  std::vector<double> th(smp.size());
  for (size_t k = 0; k < smp.size(); ++k) {
    const cd r = std::exp(-j * np * smp[k].theta_true);
    ixy[k] = r * iab(smp[k]);
    uxy[k] = r * cd(smp[k].u_ab_true[0], smp[k].u_ab_true[1]);
    th[k] = smp[k].theta_true;
  }
  (void)we;
  for (size_t k = 400; k + 3 < smp.size(); ++k) {
    auto d1 = [&](auto &v) { return (v[k - 2] - 8.0 * v[k - 1] + 8.0 * v[k + 1] - v[k + 2]) / (12 * T); };
    auto d2 = [&](auto &v) {
      return (-v[k - 2] + 16.0 * v[k - 1] - 30.0 * v[k] + 16.0 * v[k + 1] - v[k + 2]) / (12 * T * T);
    };
    Rot q;
    q.i = ixy[k];
    q.di = d1(ixy);
    q.d2i = d2(ixy);
    q.u = uxy[k];
    q.du = d1(uxy);
    q.w = d1(th);
    q.dw = d2(th);
    rec.push_back(q);
  }
  const double m = (1 - c.sigma) / c.sigma;
  const double ratio = residual_ratio(rec, np, sl, m, gamma, tr);
  EXPECT_LT(ratio, 1e-4);
  const double tr2 = tr * 1.01, gamma2 = c.rs_ohm / sl + (1 - c.sigma) / (c.sigma * tr2);
  EXPECT_GT(residual_ratio(rec, np, sl, m, gamma2, tr2), 100 * ratio);
}
