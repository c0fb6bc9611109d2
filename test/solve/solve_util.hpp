/* SPDX-License-Identifier: Apache-2.0 */
// Helpers shared by the background-solve tests: the testvector, a float64
// reference of the regressor (docs/METHOD.md §2) for realistic random sums, an
// independent long-double evaluation of E_p^2, and Eigen's companion-matrix roots.
// The testvector's JSON (solve_testvector.cpp, testvector.hpp) and Eigen's
// polynomial solver (solve_ref.cpp) are compiled once: instantiated in every test
// file they were most of the solve tests' build time.
#pragma once

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "bg_quality.h"
#include "bg_resultant.h"
#include "bg_roots.h"
#include "bg_select.h"
#include "bg_tables.h"

namespace solvetest {

// The Sturm chain of the library this binary links: true float32 (the
// default), false float64 (BG_ROOTS_DOUBLE). Defined in solve_chain.cpp, the
// only file compiled once per chain (test/solve/CMakeLists.txt).
bool chain_f32();

// The testvector's sums R_W, R_Wy, R_y (test/data/testvector.json).
bg_sums_t tv_sums();

// Every root of c[0] + c[1] x + ... + c[n-1] x^(n-1) (c[n-1] != 0), from Eigen's
// PolynomialSolver (balanced companion matrix, QR eigenvalues).
std::vector<std::complex<double>> companion_roots(const double *c, int n);

inline bg_solve_cfg_t default_cfg(double sigma = 0.096, double ls = 0.2908)
{
  bg_solve_cfg_t c{};
  c.sigma = sigma;
  c.ls_h = ls;
  c.tr_nominal_s = 0.1;
  c.tr_min_s = 1e-3;
  c.tr_max_s = 10.0;
  return c;
}

// K = [K1..K8] from (K1, K2)
inline void kvec(long double k1, long double k2, long double K[8])
{
  K[0] = k1;
  K[1] = k2;
  K[2] = k2 * k2;
  K[3] = k1 * k2;
  K[4] = 1 / k2;
  K[5] = k1 / k2;
  K[6] = k1 / (k2 * k2);
  K[7] = 1 / (k2 * k2);
}

// E_p^2 = R_y - 2 R_Wy'K + K'R_W K in long double (independent of the e-tables).
inline long double e_ref(const bg_sums_t &s, long double k1, long double k2)
{
  long double K[8];
  kvec(k1, k2, K);
  long double e = s.ry;
  for (int i = 0; i < 8; ++i) {
    e -= 2 * (long double)s.rwy[i] * K[i];
    for (int j = 0; j < 8; ++j) e += K[i] * (long double)s.rw[i][j] * K[j];
  }
  return e;
}

// Exact K1 minimiser of E for fixed K2: E = A K1^2 + B K1 + C.
inline long double k1_opt_ref(const bg_sums_t &s, long double k2, long double *profile = nullptr)
{
  const long double u[8] = {0, k2, k2 * k2, 0, 1 / k2, 0, 0, 1 / (k2 * k2)};
  const long double v[8] = {1, 0, 0, k2, 0, 1 / k2, 1 / (k2 * k2), 0};
  long double vRv = 0, vRu = 0, gv = 0;
  for (int i = 0; i < 8; ++i) {
    gv += (long double)s.rwy[i] * v[i];
    for (int j = 0; j < 8; ++j) {
      vRv += v[i] * (long double)s.rw[i][j] * v[j];
      vRu += v[i] * (long double)s.rw[i][j] * u[j];
    }
  }
  const long double k1 = (gv - vRu) / vRv;
  if (profile) *profile = e_ref(s, k1, k2);
  return k1;
}

// Motor / regressor parameters for the synthetic windows.
struct Motor {
  double np = 2, sigma = 0.096, ls = 0.2908;
  double tr = 0.12, rs = 5.04;
  double m() const { return (1 - sigma) / sigma; }
  double s() const { return sigma * ls; }
  double k1() const { return rs / (sigma * ls) + (1 - sigma) / (sigma * tr); }
  double k2() const { return 1 / tr; }
};

// One rotor-frame sample of the signals needed by W and y.
struct Sample {
  double ix, iy, dix, diy, d2ix, d2iy, ux, uy, dux, duy, w, dw;
};

// W (2x8) and, with y := W K_true + noise, the sums. Formulas of docs/METHOD.md §2.
inline void regressor(const Motor &mo, const Sample &q, double W[2][8])
{
  const double n = mo.np, m = mo.m(), s = mo.s(), w = q.w, wp = q.dw;
  W[0][0] = -q.dix;
  W[1][0] = -q.diy;
  W[0][1] = -q.dix + n * (1 + m) * w * q.iy + q.ux / s;
  W[1][1] = -q.diy - n * (1 + m) * w * q.ix + q.uy / s;
  W[0][2] = m * q.ix;
  W[1][2] = m * q.iy;
  W[0][3] = -q.ix;
  W[1][3] = -q.iy;
  W[0][4] = n * wp * (q.diy - q.uy / s) + n * n * (w * wp * q.ix - w * w * q.dix + w * w * q.ux / s) +
            n * n * n * (1 + m) * w * w * w * q.iy;
  W[1][4] = -n * wp * (q.dix - q.ux / s) + n * n * (w * wp * q.iy - w * w * q.diy + w * w * q.uy / s) -
            n * n * n * (1 + m) * w * w * w * q.ix;
  W[0][5] = n * wp * q.iy - n * n * w * w * q.ix;
  W[1][5] = -n * wp * q.ix - n * n * w * w * q.iy;
  W[0][6] = n * n * (w * wp * q.ix - w * w * q.dix);
  W[1][6] = n * n * (w * wp * q.iy - w * w * q.diy);
  W[0][7] = n * n * (w * wp * q.dix - w * w * q.d2ix + (w * w * q.dux - w * wp * q.ux) / s) +
            n * n * n * w * w * w * q.diy;
  W[1][7] = n * n * (w * wp * q.diy - w * w * q.d2iy + (w * w * q.duy - w * wp * q.uy) / s) -
            n * n * n * w * w * w * q.dix;
}

// Random but realistic window: signals are sums of a few random sinusoids with
// amplitudes typical of a 30..60 Hz drive (currents ~2 A, voltages ~150 V,
// speed ~100..180 rad/s); y = W K_true + relative noise. Sums in float64.
inline bg_sums_t synthetic_sums(std::mt19937_64 &rng, const Motor &mo, double noise_rel, int nsamp = 2000)
{
  std::uniform_real_distribution<double> U(0, 1);
  const double fs = 4000.0;
  struct Sin {
    double a, f, ph;
  };
  auto mk = [&](double amp, double fmax) {
    std::vector<Sin> v;
    v.reserve(3);
    for (int k = 0; k < 3; ++k) v.push_back({amp * (0.2 + U(rng)), fmax * (0.05 + U(rng)), 6.283 * U(rng)});
    return v;
  };
  const auto six = mk(2.0, 20), siy = mk(2.0, 20), sux = mk(150.0, 20), suy = mk(150.0, 20), sw = mk(10.0, 5);
  const double w0 = 100 + 80 * U(rng);
  auto ev = [](const std::vector<Sin> &v, double t, int d) {
    double r = 0;
    for (const auto &s : v) {
      const double om = 6.283185307179586 * s.f, ph = om * t + s.ph;
      const double c = std::cos(ph), sn = std::sin(ph);
      r += (d == 0) ? s.a * sn : (d == 1) ? s.a * om * c : -s.a * om * om * sn;
    }
    return r;
  };
  long double K[8];
  kvec(mo.k1(), mo.k2(), K);
  bg_sums_t S{};
  std::normal_distribution<double> N(0, 1);
  for (int n = 0; n < nsamp; ++n) {
    const double t = n / fs;
    Sample q{ev(six, t, 0), ev(siy, t, 0), ev(six, t, 1), ev(siy, t, 1), ev(six, t, 2),     ev(siy, t, 2),
             ev(sux, t, 0), ev(suy, t, 0), ev(sux, t, 1), ev(suy, t, 1), w0 + ev(sw, t, 0), ev(sw, t, 1)};
    double W[2][8];
    regressor(mo, q, W);
    for (int r = 0; r < 2; ++r) {
      double y = 0, scale = 0;
      for (int i = 0; i < 8; ++i) {
        y += W[r][i] * (double)K[i];
        scale += std::fabs(W[r][i] * (double)K[i]);
      }
      y += noise_rel * scale * N(rng);
      for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) S.rw[i][j] += W[r][i] * W[r][j];
        S.rwy[i] += W[r][i] * y;
      }
      S.ry += y * y;
    }
  }
  // structure fix (docs/METHOD.md §2): row/column 3 := -m row/column 4
  const double m = mo.m();
  for (int i = 0; i < 8; ++i) {
    S.rw[2][i] = -m * S.rw[3][i];
    S.rw[i][2] = -m * S.rw[i][3];
  }
  S.rw[2][2] = m * m * S.rw[3][3];
  S.rwy[2] = -m * S.rwy[3];
  return S;
}

// Errors in variables: the same random signals, but white noise (rms
// d2_noise_rel x rms of d2i/dt2) on the measured d2i/dt2, which enters y with
// coefficient 1 and W.8 with -n^2 w^2 (docs/METHOD.md §9: the cause of the paper's
// spurious minimum at K2 ~ n_p w). steady: nearly constant speed and slowly
// varying rotor-frame currents (a loaded steady state), else synthetic_sums'.
inline bg_sums_t eiv_sums(std::mt19937_64 &rng, const Motor &mo, double d2_noise_rel, int nsamp = 2000,
                          bool steady = false)
{
  std::uniform_real_distribution<double> U(0, 1);
  const double fs = 4000.0;
  struct Sin {
    double a, f, ph;
  };
  auto mk = [&](double amp, double fmax) {
    std::vector<Sin> v;
    v.reserve(3);
    for (int k = 0; k < 3; ++k) v.push_back({amp * (0.2 + U(rng)), fmax * (0.05 + U(rng)), 6.283 * U(rng)});
    return v;
  };
  const double fmax = steady ? 3.0 : 20.0;
  const auto six = mk(2.0, fmax), siy = mk(2.0, fmax), sux = mk(150.0, fmax), suy = mk(150.0, fmax),
             sw = mk(steady ? 0.5 : 10.0, 5);
  const double w0 = 100 + 80 * U(rng);
  auto ev = [](const std::vector<Sin> &v, double t, int d) {
    double r = 0;
    for (const auto &s : v) {
      const double om = 6.283185307179586 * s.f, ph = om * t + s.ph;
      const double c = std::cos(ph), sn = std::sin(ph);
      r += (d == 0) ? s.a * sn : (d == 1) ? s.a * om * c : -s.a * om * om * sn;
    }
    return r;
  };
  // rms of d2i over the window, for the noise level
  double d2rms = 0;
  for (int n = 0; n < nsamp; ++n) {
    const double t = n / fs, a = ev(six, t, 2), b = ev(siy, t, 2);
    d2rms += a * a + b * b;
  }
  d2rms = std::sqrt(d2rms / (2.0 * nsamp));
  long double K[8];
  kvec(mo.k1(), mo.k2(), K);
  bg_sums_t S{};
  std::normal_distribution<double> N(0, 1);
  for (int n = 0; n < nsamp; ++n) {
    const double t = n / fs;
    Sample q{ev(six, t, 0), ev(siy, t, 0), ev(six, t, 1), ev(siy, t, 1), ev(six, t, 2),     ev(siy, t, 2),
             ev(sux, t, 0), ev(suy, t, 0), ev(sux, t, 1), ev(suy, t, 1), w0 + ev(sw, t, 0), ev(sw, t, 1)};
    double W[2][8];
    regressor(mo, q, W);
    double y[2];
    for (int r = 0; r < 2; ++r) {
      y[r] = 0;
      for (int i = 0; i < 8; ++i) y[r] += W[r][i] * (double)K[i];
    }
    const double dx = d2_noise_rel * d2rms * N(rng), dy = d2_noise_rel * d2rms * N(rng);
    q.d2ix += dx;
    q.d2iy += dy;
    regressor(mo, q, W);
    y[0] += dx;
    y[1] += dy;
    for (int r = 0; r < 2; ++r) {
      for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) S.rw[i][j] += W[r][i] * W[r][j];
        S.rwy[i] += W[r][i] * y[r];
      }
      S.ry += y[r] * y[r];
    }
  }
  const double m = mo.m();
  for (int i = 0; i < 8; ++i) {
    S.rw[2][i] = -m * S.rw[3][i];
    S.rw[i][2] = -m * S.rw[i][3];
  }
  S.rw[2][2] = m * m * S.rw[3][3];
  S.rwy[2] = -m * S.rwy[3];
  return S;
}

} // namespace solvetest
