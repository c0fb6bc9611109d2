/* SPDX-License-Identifier: Apache-2.0 */
// ISR stages against float64 references, with stated tolerances.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

extern "C" {
#include "imest/imest.h"
#include "isr_accumulate.h"
#include "isr_duty.h"
#include "isr_regressor.h"
#include "isr_transform.h"
}

TEST(IsrTransform, SinCosWithin1p5e6OverSeveralTurns)
{
  double worst = 0;
  for (int k = -200000; k <= 200000; ++k) {
    const float x = (float)(k * 1.0e-4); // -20 .. 20 rad
    float s, c;
    isr_sincos(x, &s, &c);
    worst = std::max(worst, std::fabs((double)s - std::sin((double)x)));
    worst = std::max(worst, std::fabs((double)c - std::cos((double)x)));
  }
  EXPECT_LT(worst, 1.5e-6); // far below any encoder resolution (2^16 counts: 1e-4 rad)
}

TEST(IsrTransform, WrapPiKeepsAngleModulo2Pi)
{
  for (double x : {-100.0, -7.0, -3.2, -0.1, 0.0, 0.1, 3.2, 7.0, 100.0, 1000.0}) {
    const double w = imest__wrap_pi((float)x);
    EXPECT_LE(std::fabs(w), M_PI + 1e-5) << x;
    EXPECT_NEAR(std::remainder(w - x, 2 * M_PI), 0.0, 1e-4) << x;
  }
}

TEST(IsrTransform, ClarkeIsPowerInvariant)
{
  // balanced set with line-to-line rms 230 V -> alpha/beta amplitude 230
  for (int k = 0; k < 50; ++k) {
    const double ph = k * 0.3, a = std::sqrt(2.0 / 3.0) * 230;
    const float x[3] = {(float)(a * std::cos(ph)), (float)(a * std::cos(ph - 2 * M_PI / 3)),
                        (float)(a * std::cos(ph + 2 * M_PI / 3))};
    float xa, xb;
    imest__clarke(x, &xa, &xb);
    EXPECT_NEAR(xa, 230 * std::cos(ph), 1e-3);
    EXPECT_NEAR(xb, 230 * std::sin(ph), 1e-3);
  }
}

// Product of the two sections vs the direct-form coefficients of docs/METHOD.md §8.
static void check_design(double fc, const double b[4], const double a[4])
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.filter_hz = (float)fc;
  static imest_t s;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  // the sections' numerators are binomial: b0 (1 + z^-1), c0 (1 + 2 z^-1 + z^-2)
  const double n1[2] = {s.bw.b0, s.bw.b0}, d1[2] = {1, s.bw.a1};
  const double n2[3] = {s.bw.c0, 2.0 * s.bw.c0, s.bw.c0}, d2[3] = {1, s.bw.d1, s.bw.d2};
  double nb[4] = {0}, da[4] = {0};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) {
      nb[i + j] += n1[i] * n2[j];
      da[i + j] += d1[i] * d2[j];
    }
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(nb[k], b[k], 2e-7 * std::fabs(b[k]) + 1e-12) << fc << " b" << k;
    EXPECT_NEAR(da[k], a[k], 2e-7) << fc << " a" << k;
  }
}

TEST(IsrFilter, DesignMatchesMathMdCoefficients)
{
  const double b500[4] = {0.03168934384971104, 0.09506803154913313, 0.09506803154913313, 0.03168934384971104};
  const double a500[4] = {1, -1.459029062228061, 0.9103690002900687, -0.19782518726431944};
  const double b100[4] = {4.1654613907575e-4, 1.24963841722724e-3, 1.24963841722724e-3, 4.1654613907575e-4};
  const double a100[4] = {1, -2.686157396548143, 2.4196551109664717, -0.7301653453057226};
  const double b25[4] = {7.28117247505e-6, 2.18435174251502e-5, 2.18435174251502e-5, 7.28117247505e-6};
  const double a25[4] = {1, -2.9214652231948923, 2.8459840557611136, -0.9244605831864209};
  check_design(500, b500, a500);
  check_design(100, b100, a100);
  check_design(25, b25, a25);
}

// Central differences of the filtered signal against a float64 filter run.
TEST(IsrFilter, DerivativesAreTimeAlignedCentralDifferences)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  static imest_t s;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  imest_chan_t c = {};
  // float64 reference of the same cascade
  double s1 = 0, s2a = 0, s2b = 0;
  std::vector<double> xf;
  const double T = 1.0 / 4000;
  double worst_x = 0, worst_dx = 0, worst_d2 = 0;
  for (int n = 0; n < 4000; ++n) {
    const double x = 2.0 * std::sin(2 * M_PI * 9 * n * T) + 0.5;
    const double v = (double)s.bw.b0 * x + s1;
    s1 = (double)s.bw.b0 * x - (double)s.bw.a1 * v;
    const double w = (double)s.bw.c0 * v + s2a;
    s2a = 2.0 * (double)s.bw.c0 * v - (double)s.bw.d1 * w + s2b;
    s2b = (double)s.bw.c0 * v - (double)s.bw.d2 * w;
    xf.push_back(w);
    const isr_deriv_t d = isr_filter_deriv(&s, &c, (float)x);
    if (n >= 2) {
      const double rx = xf[n - 1], rdx = (xf[n] - xf[n - 2]) / (2 * T),
                   rd2 = (xf[n] - 2 * xf[n - 1] + xf[n - 2]) / (T * T);
      worst_x = std::max(worst_x, std::fabs(d.x - rx));
      worst_dx = std::max(worst_dx, std::fabs(d.dx - rdx));
      worst_d2 = std::max(worst_d2, std::fabs(d.d2x - rd2));
    }
  }
  // signal: |x| ~ 2.5, |dx| ~ 113 /s, |d2x| ~ 6400 /s^2
  EXPECT_LT(worst_x, 2e-5); // float32 SOS rounding, ~1e-5 relative
  EXPECT_LT(worst_dx, 1.5e-2);
  EXPECT_LT(worst_d2, 40.0); // float32 rounding of x_f times 1/T^2 = 1.6e7
}

// The 7 regressor columns and y against docs/METHOD.md §2 written out in float64.
TEST(IsrRegressor, MatchesMathMdFormulas)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  static imest_t s;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  const double n = 2, m = (1 - 0.096) / 0.096, sl = (double)(0.096f * 0.2908f);
  for (int trial = 0; trial < 200; ++trial) {
    isr_signals_t g;
    g.ix = {(float)(2 * U(rng)), (float)(300 * U(rng)), (float)(2e4 * U(rng))};
    g.iy = {(float)(2 * U(rng)), (float)(300 * U(rng)), (float)(2e4 * U(rng))};
    g.ux = {(float)(200 * U(rng)), (float)(2e4 * U(rng)), 0};
    g.uy = {(float)(200 * U(rng)), (float)(2e4 * U(rng)), 0};
    g.w = (float)(180 * U(rng));
    g.dw = (float)(1000 * U(rng));
    const double ix = g.ix.x, iy = g.iy.x, dix = g.ix.dx, diy = g.iy.dx, d2ix = g.ix.d2x, d2iy = g.iy.d2x;
    const double ux = g.ux.x, uy = g.uy.x, dux = g.ux.dx, duy = g.uy.dx, w = g.w, wp = g.dw;
    const double vs = 1.0 / (double)s.inv_s;
    (void)sl;
    double W[2][8], y[2];
    y[0] = d2ix - n * w * diy - n * wp * iy - n * n * m * w * w * ix - dux / vs;
    y[1] = d2iy + n * w * dix + n * wp * ix - n * n * m * w * w * iy - duy / vs;
    W[0][0] = -dix;
    W[1][0] = -diy;
    W[0][1] = -dix + n * (1 + m) * w * iy + ux / vs;
    W[1][1] = -diy - n * (1 + m) * w * ix + uy / vs;
    W[0][2] = m * ix;
    W[1][2] = m * iy;
    W[0][3] = -ix;
    W[1][3] = -iy;
    W[0][4] = n * wp * (diy - uy / vs) + n * n * (w * wp * ix - w * w * dix + w * w * ux / vs) +
              n * n * n * (1 + m) * w * w * w * iy;
    W[1][4] = -n * wp * (dix - ux / vs) + n * n * (w * wp * iy - w * w * diy + w * w * uy / vs) -
              n * n * n * (1 + m) * w * w * w * ix;
    W[0][5] = n * wp * iy - n * n * w * w * ix;
    W[1][5] = -n * wp * ix - n * n * w * w * iy;
    W[0][6] = n * n * (w * wp * ix - w * w * dix);
    W[1][6] = n * n * (w * wp * iy - w * w * diy);
    W[0][7] = n * n * (w * wp * dix - w * w * d2ix + (w * w * dux - w * wp * ux) / vs) +
              n * n * n * w * w * w * diy;
    W[1][7] = n * n * (w * wp * diy - w * w * d2iy + (w * w * duy - w * wp * uy) / vs) -
              n * n * n * w * w * w * dix;
    const float c0[7] = {0, 0, 0, 0, 0, 0, 0};
    float zx[8], zy[8];
    isr_regressor(&s, &g, c0, zx, zy);
    const int k_of[7] = {0, 1, 3, 4, 5, 6, 7};
    for (int r = 0; r < 2; ++r) {
      const float *z = r ? zy : zx;
      for (int j = 0; j < 7; ++j) {
        const double ref = W[r][k_of[j]];
        // float32 rounding relative to the column's typical term size
        static const double scale[7] = {300, 1e4, 2, 1e9, 3e5, 4e7, 3e9};
        EXPECT_NEAR(z[j], ref, 1e-5 * scale[j]) << "row " << r << " col " << j;
      }
      EXPECT_NEAR(z[7], y[r], 1e-5 * 3e6) << "y row " << r;
      // column 3 is exactly -m x column 4
      EXPECT_DOUBLE_EQ(W[r][2], -m * W[r][3]);
    }
  }
}

TEST(IsrAccumulate, FoldedBlocksEqualFloat64SumsToFewUlps)
{
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0, 1);
  imest_window_t w = {};
  double ref[IMEST_NACC] = {0};
  uint32_t fold = 0;
  for (int n = 0; n < 4000; ++n) {
    float zx[8], zy[8];
    for (int i = 0; i < 8; ++i) {
      zx[i] = (float)(N(rng) * (1 + i));
      zy[i] = (float)(N(rng) + 3.0);
    }
    isr_extra_t x;
    x.cross = 0.5f;
    x.noise_i = 0.25f;
    x.noise_u = 2.0f;
    x.i0 = 0.5f;
    x.ia = 2.0f;
    x.ib = -1.0f;
    // the two halves of one sample's sums, as the ISR's even and odd calls do them
    isr_accumulate_a(&w, zx, zy, &x);
    isr_fold(&w, fold);
    fold = (fold + 1 == IMEST_NACC) ? 0 : fold + 1;
    isr_accumulate_b(&w, zx, zy);
    isr_fold(&w, fold);
    fold = (fold + 1 == IMEST_NACC) ? 0 : fold + 1;
    unsigned p = 0;
    for (int i = 0; i < 8; ++i)
      for (int j = i; j < 8; ++j) ref[p++] += (double)zx[i] * zx[j] + (double)zy[i] * zy[j];
  }
  for (int i = 0; i < 8; ++i)
    for (int j = i; j < 8; ++j) {
      const unsigned p = IMEST_ACC_INDEX((unsigned)i, (unsigned)j);
      const double got = (double)w.sum[p] + (double)w.blk[p];
      // scale: sum of |products|, ~ 4000 * (1+i)(1+j) + 4000*10
      const double scale = 4000.0 * ((1 + i) * (1 + j) + 10.0);
      EXPECT_NEAR(got, ref[p], 2e-6 * scale) << i << "," << j;
    }
  // the window's other evidence is summed the same way
  auto entry = [&](unsigned p) { return (double)w.sum[p] + (double)w.blk[p]; };
  EXPECT_EQ(w.nreg, 4000u);
  EXPECT_NEAR(entry(IMEST_ACC_ROT), 2000.0, 1e-3);
  EXPECT_NEAR(entry(IMEST_ACC_NOISE_I), 1000.0, 1e-3);
  EXPECT_NEAR(entry(IMEST_ACC_NOISE_U), 8000.0, 1e-3);
  EXPECT_NEAR(entry(IMEST_ACC_I0A), 4000.0, 1e-3);
  EXPECT_NEAR(entry(IMEST_ACC_I0B), -2000.0, 1e-3);
}

// The duty-cycle input's inverter model (isr_duty.h, docs/METHOD.md §17.1).
namespace {
// A 4 kW-like drive: 560 V, 8 kHz, sigma L_S = 11.5 mH (ripple scale 3 A), devices of
// different threshold and slope, so every term of the model counts.
struct DutyDrive {
  imest_t s;
  double vdc = 560.0, fpwm = 8000.0, sl = 0.0645168 * 0.178039;
  double td = 2e-6, vsw = 1.2, rsw = 0.03, vd = 0.9, rd = 0.02;
  double edge_band = 0.075; // the devices' band, about a tenth of the ripple's peak kr / 4
  explicit DutyDrive(bool edges = true, bool drops = true)
  {
    if (!edges) edge_band = 0.0;
    if (!drops) vsw = rsw = vd = rd = 0.0;
    imest_config_t cfg;
    imest_config_default(&cfg);
    cfg.pole_pairs = 2;
    cfg.ls_h = 0.178039f;
    cfg.sigma = 0.0645168f;
    cfg.fs_hz = (float)fpwm;
    cfg.inverter.dead_time_s = (float)td;
    cfg.inverter.v_switch_v = (float)vsw;
    cfg.inverter.r_switch_ohm = (float)rsw;
    cfg.inverter.v_diode_v = (float)vd;
    cfg.inverter.r_diode_ohm = (float)rd;
    cfg.inverter.uncertainty = 0.2f;
    cfg.inverter.edge_band_a = (float)edge_band;
    EXPECT_EQ(imest_init(&s, &cfg), IMEST_OK);
  }
  double kr() const { return vdc / (2.0 * sl * fpwm); } // V_dc T / (2 sigma L_S)
  // the formulas of METHOD §17.1 in float64, in their defining form
  double ripple(const double d[3], int x) const
  {
    const double mean = (d[0] + d[1] + d[2]) / 3.0;
    const int y = (x + 1) % 3, z = (x + 2) % 3;
    return kr() * ((d[x] - mean) * (d[x] - 0.5) - (std::fabs(d[x] - d[y]) + std::fabs(d[x] - d[z])) / 6.0);
  }
  double error(double dbar, double i, double r) const
  {
    const double b = edge_band;
    auto sgn = [b](double x) { return x / std::sqrt(x * x + b * b); };
    const double se = 0.5 * (sgn(i + r) + sgn(i - r));
    // the smooth sign's mean over the ramp i - r .. i + r: its integral is sqrt(x^2 + b^2)
    const double m =
        std::fabs(r) > 1e-9
            ? (std::sqrt((i + r) * (i + r) + b * b) - std::sqrt((i - r) * (i - r) + b * b)) / (2.0 * r)
            : sgn(i);
    return td * fpwm * vdc * se + 0.5 * (vsw + vd) * m + 0.5 * (rsw + rd) * i +
           (dbar - 0.5) * ((vsw - vd) + (rsw - rd) * std::fabs(i));
  }
  // the floor of the smooth sign's band (imest_init.c): the current's change within the dead
  // time, 1/3 V_dc t_d / (sigma L_S) per other leg in the opposite state, halved, over the edges
  double floor() const { return vdc * td / (6.0 * sl); }
  // the smooth sign's model (edge_band_a 0, the default), as imest.h writes it, with the band the
  // leg's ripple r at its edges plus the floor
  double error_smooth(double dbar, double i, double r) const
  {
    const double b = std::fabs(r) + floor();
    const double sg = i / std::sqrt(i * i + b * b), a = std::fabs(i);
    const double dc = 0.5 + sg * (dbar - 0.5);
    return sg * (td * fpwm * vdc + vd + rd * a + dc * ((vsw - vd) + (rsw - rd) * a));
  }
  double ref_scale(double i) const { return td * fpwm * vdc + vsw + vd + (rsw + rd) * std::fabs(i); }
};
} // namespace

// The closed-form ripple against the phase current integrated over one period of
// centre-aligned PWM with a floating neutral (every leg high at the period's ends).
TEST(IsrDuty, RippleIsThePhaseCurrentsAtTheEdges)
{
  const DutyDrive dd;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.02, 0.98);
  const int n = 20000; // steps per period
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const double d[3] = {u(rng), u(rng), u(rng)};
    auto high = [&](int x, double t) { return t < 0.5 * d[x] || t >= 1.0 - 0.5 * d[x]; }; // t in periods
    for (int x = 0; x < 3; ++x) {
      // ripple = integral of (v_x - its mean) / (sigma L_S); at the falling edge -D, rising +D
      double acc = 0, at_fall = 0, at_rise = 0;
      for (int k = 0; k < n; ++k) {
        const double t = (k + 0.5) / n;
        const double h = (high(0, t) + high(1, t) + high(2, t)) / 3.0;
        const double vx = dd.vdc * (high(x, t) - h) - dd.vdc * (d[x] - (d[0] + d[1] + d[2]) / 3.0);
        acc += vx / (dd.sl * dd.fpwm * n);
        if (t < 0.5 * d[x]) at_fall = acc;
        if (t < 1.0 - 0.5 * d[x]) at_rise = acc;
      }
      const double r = dd.ripple(d, x);
      worst = std::max({worst, std::fabs(at_fall + r), std::fabs(at_rise - r)});
    }
  }
  EXPECT_LT(worst, 0.002 * dd.kr()); // the integration's step: V_dc / (sigma L_S f n) = kr / 10^4
}

// The largest difference of the ISR's error (float32, the constants as the ISR forms them)
// from the float64 formula over random duties and currents from deep inside the ripple to ten
// times it, relative to the error's scale; the ripple checked on the way.
static double worst_against_float64(const DutyDrive &dd, unsigned seed, bool smooth)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.02, 0.98), cur(-1.0, 1.0);
  isr_duty_k_t k{};
  const float kr = isr_duty_constants(&dd.s.duty, (float)dd.vdc, (float)dd.vdc, &k);
  double worst = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double d[3] = {u(rng), u(rng), u(rng)};
    const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    float rf[3];
    isr_duty_ripple(kr, df, rf);
    const double scale = (trial % 3 == 0) ? 0.5 : (trial % 3 == 1 ? 3.0 : 30.0);
    for (int x = 0; x < 3; ++x) {
      const double i = scale * cur(rng);
      const double r = dd.ripple(d, x);
      const double e = smooth ? dd.error_smooth(d[x], i, r) : dd.error(d[x], i, r);
      const float ef = smooth ? isr_duty_error_smooth(&dd.s.duty, &k, df[x], (float)i, rf[x])
                              : isr_duty_error(&dd.s.duty, &k, df[x], (float)i, rf[x]);
      worst = std::max(worst, std::fabs((double)ef - e) / dd.ref_scale(i));
      EXPECT_NEAR(rf[x], r, 1e-5 * dd.kr()) << trial;
    }
  }
  return worst;
}

// isr_duty_ripple and isr_duty_error in float32 against the same formulas in float64,
// the drops' mean sign in its defining (subtractive) form: within 2e-6 of the error's
// scale t_d f V_dc + V_sw0 + V_d0 + (r_sw + r_d) |i| (float32 rounding of about ten
// operations, 6e-8 each, and of the currents near the ripple).
TEST(IsrDuty, ErrorMatchesFloat64Formula)
{
  const DutyDrive dd;
  EXPECT_LT(worst_against_float64(dd, 3, false), 2e-6);
}

// The default (smooth-sign) form in float32 against imest.h's formula in float64, each leg's
// band its own ripple at the edges with the floor, the same tolerance.
TEST(IsrDuty, SmoothErrorMatchesFloat64Formula)
{
  const DutyDrive dd(false);
  EXPECT_LT(worst_against_float64(dd, 4, true), 2e-6);
}

// A user-set i_band_a is the smooth sign's band alone: no ripple term, no floor.
TEST(IsrDuty, SmoothFixedBandIsIBandA)
{
  imest_t s;
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.178039f;
  cfg.sigma = 0.0645168f;
  cfg.fs_hz = 8000.0f;
  cfg.inverter.dead_time_s = 2e-6f;
  cfg.inverter.i_band_a = 0.4f;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  isr_duty_k_t k{};
  EXPECT_EQ(isr_duty_constants(&s.duty, 560.0f, 560.0f, &k), 0.0f);
  EXPECT_FLOAT_EQ(k.band2, 0.4f * 0.4f);
}

// The dead time's error of a leg at its current's zero crossing, the ISR's constants and
// smooth sign against a float64 reference of the switching instants: the current at the leg's
// rising edge is i + D, at its falling edge i - D (D its ripple, for duties of a sinusoidal
// modulation where the leg's current crosses zero); a positive current at the rising edge (a
// negative one at the falling edge) freewheels through a diode for t_d and, while its leg keeps
// the state before the edge, changes towards 0 by n/3 V_dc t_d / (sigma L_S), n the other legs
// in the opposite state (those of larger duty at the rising edge, of smaller at the falling
// edge): the edge loses t_d V_dc in full if the current stays on its side, in proportion if it
// reaches 0 first. What the fit reads from the error's shape near the crossing is its area
// against the full sign (its odd part's; the harmonics' amplitudes are its moments): the smooth
// sign's is b = |D| + b_0, the reference's |D| + (the two changes' sum) / 4, equal; within 2 % of D
// (the integration's range and step, the float32 sign). The default band before, the ripple's
// peak at 50 % duty (kr / 4), was 2.3 to 7 times |D| here.
TEST(IsrDuty, SmoothSignAtAZeroCrossingFollowsTheLegsRipple)
{
  DutyDrive dd(false, false);
  isr_duty_k_t k{};
  const float kr = isr_duty_constants(&dd.s.duty, (float)dd.vdc, (float)dd.vdc, &k);
  const double per_leg = dd.vdc * dd.td / (3.0 * dd.sl), full = dd.td * dd.fpwm * dd.vdc;
  auto ramp01 = [](double x) { return std::max(0.0, std::min(1.0, x)); };
  for (double mi : {0.3, 0.6, 0.9}) {                 // modulation index
    for (double phi : {0.3, 0.6, 1.0}) {              // the current's lag behind the voltage [rad]
      const double th = 0.5 * 3.14159265358979 + phi; // leg a's current crosses zero here
      const double d[3] = {0.5 + 0.5 * mi * std::cos(th), 0.5 + 0.5 * mi * std::cos(th - 2.0943951023932),
                           0.5 + 0.5 * mi * std::cos(th + 2.0943951023932)};
      const float df[3] = {(float)d[0], (float)d[1], (float)d[2]};
      float rf[3];
      isr_duty_ripple(kr, df, rf);
      const double D = dd.ripple(d, 0);
      ASSERT_LT(D, 0.0); // the current at its lowest at the rising edge: both ramps off 0
      const double n_hi = (d[1] > d[0]) + (d[2] > d[0]), n_lo = 2.0 - n_hi;
      const double dr = n_hi * per_leg, dfall = n_lo * per_leg; // the change within the dead time
      // the error per t_d f V_dc: the rising edge's loss minus the falling edge's gain
      auto ref = [&](double i) {
        const double rise = dr > 0 ? ramp01((i + D) / dr) : (i + D > 0 ? 1.0 : 0.0);
        const double fall = dfall > 0 ? ramp01(-(i - D) / dfall) : (i - D < 0 ? 1.0 : 0.0);
        return rise - fall;
      };
      // out to where the reference is full and the model's tail b^2 / 2 i is below 1e-3 |D|
      const int n = 400000;
      const double top = 500.0 * (std::fabs(D) + per_leg), h = top / n;
      double area_ref = 0, area_model = 0;
      for (int q = 0; q < n; ++q) {
        const double i = (q + 0.5) * h;
        const double mp = isr_duty_error_smooth(&dd.s.duty, &k, df[0], (float)i, rf[0]) / full;
        const double mm = isr_duty_error_smooth(&dd.s.duty, &k, df[0], (float)-i, rf[0]) / full;
        area_ref += 0.5 * ((1.0 - ref(i)) + (1.0 + ref(-i))) * h;
        area_model += 0.5 * ((1.0 - mp) + (1.0 + mm)) * h;
      }
      EXPECT_NEAR(area_model, area_ref, 0.02 * std::fabs(D)) << mi << " " << phi;
    }
  }
}
