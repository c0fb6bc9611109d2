/* SPDX-License-Identifier: Apache-2.0 */
// A small, independent float64 induction-motor model (docs/METHOD.md eq. (1)) for the
// core tests: RK4 with substeps, sinusoidal supply, constant load. The full
// simulator lives in sim/; this one only needs to be obviously right.
#pragma once
#include <cmath>

struct MotorRef {
  // paper's motor
  double np = 2, ls = 0.2908, lr = 0.2908, sigma = 0.096, tr = 0.12, rs = 5.04;
  double j = 1.2e-3, b = 1e-4, load = 0.0;
  double vll = 230.0, f = 60.0;
  // state: i_a, i_b, psi_a, psi_b, omega, theta
  double x[6] = {0, 0, 0, 0, 0, 0};
  double t = 0;

  double M() const { return std::sqrt((1 - sigma) * ls * lr); }
  void u_ab(double tt, double &ua, double &ub) const
  {
    const double a = std::sqrt(2.0 / 3.0) * vll, w = 2 * M_PI * f * tt;
    const double u1 = a * std::cos(w), u2 = a * std::cos(w - 2 * M_PI / 3),
                 u3 = a * std::cos(w + 2 * M_PI / 3);
    ua = std::sqrt(2.0 / 3.0) * (u1 - 0.5 * u2 - 0.5 * u3);
    ub = std::sqrt(2.0 / 3.0) * (std::sqrt(3.0) / 2) * (u2 - u3);
  }
  void deriv(double tt, const double *s, double *d) const
  {
    const double m = M(), beta = m / (sigma * ls * lr);
    const double gamma = rs / (sigma * ls) + (1 - sigma) / (sigma * tr);
    double ua, ub;
    u_ab(tt, ua, ub);
    const double w = s[4];
    d[0] = beta / tr * s[2] + beta * np * w * s[3] - gamma * s[0] + ua / (sigma * ls);
    d[1] = beta / tr * s[3] - beta * np * w * s[2] - gamma * s[1] + ub / (sigma * ls);
    d[2] = -s[2] / tr - np * w * s[3] + m / tr * s[0];
    d[3] = -s[3] / tr + np * w * s[2] + m / tr * s[1];
    const double torque = np * m / lr * (s[1] * s[2] - s[0] * s[3]);
    d[4] = (torque - load - b * w) / j;
    d[5] = w;
  }
  void step(double h)
  {
    double k1[6], k2[6], k3[6], k4[6], y[6];
    deriv(t, x, k1);
    for (int i = 0; i < 6; ++i) y[i] = x[i] + 0.5 * h * k1[i];
    deriv(t + 0.5 * h, y, k2);
    for (int i = 0; i < 6; ++i) y[i] = x[i] + 0.5 * h * k2[i];
    deriv(t + 0.5 * h, y, k3);
    for (int i = 0; i < 6; ++i) y[i] = x[i] + h * k3[i];
    deriv(t + h, y, k4);
    for (int i = 0; i < 6; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    t += h;
  }
  // phase quantities of the current state
  void phases(double u[3], double i[3]) const
  {
    double ua, ub;
    u_ab(t, ua, ub);
    const double k = std::sqrt(2.0 / 3.0);
    u[0] = k * ua;
    u[1] = k * (-0.5 * ua + std::sqrt(3.0) / 2 * ub);
    u[2] = k * (-0.5 * ua - std::sqrt(3.0) / 2 * ub);
    i[0] = k * x[0];
    i[1] = k * (-0.5 * x[0] + std::sqrt(3.0) / 2 * x[1]);
    i[2] = k * (-0.5 * x[0] - std::sqrt(3.0) / 2 * x[1]);
  }
};
