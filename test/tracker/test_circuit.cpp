/* SPDX-License-Identifier: Apache-2.0 */
// Equivalent circuit -> the estimator's constants (include/imest/imest_circuit.h), against values
// worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "imest/imest_circuit.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

// L_m = 0.1 H, L_ls = 4 mH, L_lr = 6 mH, R_R = 0.5 ohm, R_S = 0.3 ohm:
// L_S = 0.104 H, L_R = 0.106 H, sigma = 1 - 0.01 / 0.011024 = 0.0928882438, T_R = 0.212 s.
constexpr double kLs = 0.104, kLr = 0.106, kSigma = 1.0 - 0.01 / (0.104 * 0.106), kTr = 0.212;

imest_circuit_t hand()
{
  imest_circuit_t c;
  c.lm_h = 0.1f;
  c.lls_h = 0.004f;
  c.llr_h = 0.006f;
  c.rr_ohm = 0.5f;
  c.rs_ohm = 0.3f;
  return c;
}

void expect_hand(const imest_circuit_constants_t &k)
{
  EXPECT_NEAR(k.ls_h, kLs, 1e-6 * kLs);
  EXPECT_NEAR(k.sigma, kSigma, 1e-6 * kSigma);
  EXPECT_NEAR(k.tr_s, kTr, 1e-6 * kTr);
  EXPECT_FLOAT_EQ(k.rs_ohm, 0.3f);
}

TEST(Circuit, TFormHandValues)
{
  const imest_circuit_t c = hand();
  imest_circuit_constants_t k;
  ASSERT_EQ(imest_circuit_from_t(&c, &k), IMEST_OK);
  expect_hand(k);
  EXPECT_NEAR(k.lr_h, kLr, 1e-6 * kLr);
  EXPECT_FLOAT_EQ(k.lm_h, 0.1f);
}

TEST(Circuit, PaperMotor)
{
  // L_S = L_R = 0.2908 H, sigma = 0.096, T_R = 0.12 s: L_m = sqrt(0.904) L_S, R_R = L_R / T_R
  const double ls = 0.2908, lm = std::sqrt(1.0 - 0.096) * ls;
  imest_circuit_t c;
  c.lm_h = static_cast<float>(lm);
  c.lls_h = c.llr_h = static_cast<float>(ls - lm);
  c.rr_ohm = static_cast<float>(ls / 0.12);
  c.rs_ohm = 5.04f;
  imest_circuit_constants_t k;
  ASSERT_EQ(imest_circuit_from_t(&c, &k), IMEST_OK);
  EXPECT_NEAR(k.ls_h, 0.2908, 1e-6);
  EXPECT_NEAR(k.sigma, 0.096, 2e-6);
  EXPECT_NEAR(k.tr_s, 0.12, 1e-6);
}

TEST(Circuit, ReactancesAt50And60Hz)
{
  for (double f : {50.0, 60.0}) {
    const double w = 2.0 * kPi * f;
    imest_circuit_x_t x;
    x.f_hz = static_cast<float>(f);
    x.xm_ohm = static_cast<float>(w * 0.1); // 31.416 ohm at 50 Hz
    x.xls_ohm = static_cast<float>(w * 0.004);
    x.xlr_ohm = static_cast<float>(w * 0.006);
    x.rr_ohm = 0.5f;
    x.rs_ohm = 0.3f;
    imest_circuit_constants_t k;
    ASSERT_EQ(imest_circuit_from_x(&x, &k), IMEST_OK);
    expect_hand(k);
  }
}

TEST(Circuit, InverseGammaGivesTheSameConstants)
{
  // the hand circuit referred by L_m / L_R: L_M = L_m^2 / L_R, L_sigma = sigma L_S, R_R' = (L_m/L_R)^2 R_R
  imest_circuit_inv_gamma_t g;
  g.lm_h = static_cast<float>(0.01 / kLr);
  g.lsig_h = static_cast<float>(kSigma * kLs);
  g.rr_ohm = static_cast<float>(0.5 * (0.1 / kLr) * (0.1 / kLr));
  g.rs_ohm = 0.3f;
  imest_circuit_constants_t k;
  ASSERT_EQ(imest_circuit_from_inv_gamma(&g, &k), IMEST_OK);
  expect_hand(k);
  EXPECT_FLOAT_EQ(k.lr_h, g.lm_h);
  EXPECT_FLOAT_EQ(k.lm_h, g.lm_h);
}

TEST(Circuit, SmallSigmaWithoutCancellation)
{
  // L_m = 1 H, leakages 0.1 mH: sigma = (2e-4 + 1e-8) / (1.0001^2) = 1.99970006e-4
  imest_circuit_t c;
  c.lm_h = 1.0f;
  c.lls_h = c.llr_h = 1e-4f;
  c.rr_ohm = 1.0f;
  c.rs_ohm = 0.0f;
  imest_circuit_constants_t k;
  ASSERT_EQ(imest_circuit_from_t(&c, &k), IMEST_OK);
  const double l = static_cast<double>(1e-4f), exact = (2.0 * l + l * l) / ((1.0 + l) * (1.0 + l));
  EXPECT_NEAR(k.sigma, exact, 1e-6 * exact); // 1 - L_m^2/(L_S L_R) in float32 is ~1e-3 off here
  EXPECT_EQ(k.rs_ohm, 0.0f);
}

TEST(Circuit, BadInputsRejected)
{
  const float bad[] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity()};
  imest_circuit_constants_t k, before;
  std::memset(&k, 0x5a, sizeof k);
  before = k;
  for (int field = 0; field < 4; ++field) {
    for (float v : bad) {
      imest_circuit_t c = hand();
      float *p[] = {&c.lm_h, &c.lls_h, &c.llr_h, &c.rr_ohm};
      *p[field] = v;
      EXPECT_EQ(imest_circuit_from_t(&c, &k), IMEST_ERR_ARG) << field << " " << v;
      imest_circuit_inv_gamma_t g = {0.1f, 0.01f, 0.5f, 0.3f};
      float *q[] = {&g.lm_h, &g.lsig_h, &g.rr_ohm, &g.lm_h};
      *q[field] = v;
      EXPECT_EQ(imest_circuit_from_inv_gamma(&g, &k), IMEST_ERR_ARG) << field << " " << v;
    }
  }
  for (float v : {-0.1f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    imest_circuit_t c = hand();
    c.rs_ohm = v;
    EXPECT_EQ(imest_circuit_from_t(&c, &k), IMEST_ERR_ARG) << v;
  }
  imest_circuit_x_t x = {50.0f, 31.4f, 1.2f, 1.9f, 0.5f, 0.3f};
  for (float v : bad) {
    imest_circuit_x_t y = x;
    y.f_hz = v;
    EXPECT_EQ(imest_circuit_from_x(&y, &k), IMEST_ERR_ARG) << v;
    y = x;
    y.xls_ohm = v;
    EXPECT_EQ(imest_circuit_from_x(&y, &k), IMEST_ERR_ARG) << v;
  }
  // results that overflow float32
  imest_circuit_t huge = hand();
  huge.lm_h = huge.lls_h = huge.llr_h = 3e38f;
  EXPECT_EQ(imest_circuit_from_t(&huge, &k), IMEST_ERR_ARG);
  EXPECT_EQ(std::memcmp(&k, &before, sizeof k), 0) << "a refused input wrote the output";

  const imest_circuit_t c = hand();
  EXPECT_EQ(imest_circuit_from_t(nullptr, &k), IMEST_ERR_NULL);
  EXPECT_EQ(imest_circuit_from_t(&c, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_circuit_from_x(nullptr, &k), IMEST_ERR_NULL);
  EXPECT_EQ(imest_circuit_from_x(&x, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_circuit_from_inv_gamma(nullptr, &k), IMEST_ERR_NULL);
}

TEST(Circuit, ApplyFillsTheConfig)
{
  const imest_circuit_t c = hand();
  imest_circuit_constants_t k;
  ASSERT_EQ(imest_circuit_from_t(&c, &k), IMEST_OK);
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  ASSERT_EQ(imest_circuit_apply(&k, &cfg), IMEST_OK);
  EXPECT_EQ(cfg.ls_h, k.ls_h);
  EXPECT_EQ(cfg.sigma, k.sigma);
  EXPECT_EQ(cfg.tr_nominal_s, k.tr_s);
  EXPECT_EQ(cfg.tr_nominal_known, 1);
  EXPECT_EQ(cfg.rs_nominal_ohm, 0.3f);
  EXPECT_EQ(imest_config_check(&cfg, nullptr), IMEST_OK);

  k.rs_ohm = 0.0f; // not given: the config's stays
  cfg.rs_nominal_ohm = 1.5f;
  ASSERT_EQ(imest_circuit_apply(&k, &cfg), IMEST_OK);
  EXPECT_EQ(cfg.rs_nominal_ohm, 1.5f);

  const imest_config_t before = cfg;
  imest_circuit_constants_t b = k;
  b.sigma = 1.0f;
  EXPECT_EQ(imest_circuit_apply(&b, &cfg), IMEST_ERR_ARG);
  b = k;
  b.tr_s = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(imest_circuit_apply(&b, &cfg), IMEST_ERR_ARG);
  b = k;
  b.ls_h = 0.0f;
  EXPECT_EQ(imest_circuit_apply(&b, &cfg), IMEST_ERR_ARG);
  EXPECT_EQ(std::memcmp(&cfg, &before, sizeof cfg), 0);
  EXPECT_EQ(imest_circuit_apply(nullptr, &cfg), IMEST_ERR_NULL);
  EXPECT_EQ(imest_circuit_apply(&k, nullptr), IMEST_ERR_NULL);
}

} // namespace
