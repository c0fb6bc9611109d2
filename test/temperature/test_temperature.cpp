/* SPDX-License-Identifier: Apache-2.0 */
// The stator and rotor temperatures (include/imest/imest_temperature.h): the resistance method on
// hand values, the uncertainty's propagation, the verdicts, unusable inputs and bad configs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "imest/imest_temperature.h"

namespace {

constexpr float kTref = 20.0f;  // degC
constexpr float kRsRef = 3.0f;  // ohm
constexpr float kTrRef = 0.12f; // s
constexpr float kLs = 0.29f;    // H
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

imest_result_t result(double rs, double rs_b, int rs_valid, double tr, double tr_b, int tr_valid)
{
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  r.t_end_s = 7.0;
  r.rs_ohm = rs;
  r.rs_bound_rel = rs_b;
  r.rs_valid = rs_valid;
  r.tr_s = tr;
  r.tr_bound_rel = tr_b;
  r.tr_valid = tr_valid;
  r.valid = rs_valid && tr_valid;
  return r;
}

struct Temperature : ::testing::Test {
  imest_temperature_config_t cfg{};
  imest_temperature_t t{};
  void SetUp() override
  {
    imest_temperature_config_default(&cfg, kTref, kRsRef, kTrRef, kLs);
    ASSERT_EQ(imest_temperature_init(&t, &cfg), IMEST_OK);
  }
};

TEST_F(Temperature, DefaultsAreTheDocumentedOnes)
{
  EXPECT_EQ(cfg.t_ref_c, kTref);
  EXPECT_EQ(cfg.rs_ref_ohm, kRsRef);
  EXPECT_EQ(cfg.tr_ref_s, kTrRef);
  EXPECT_EQ(cfg.lr_h, kLs); // equal leakages: L_R = L_S
  EXPECT_EQ(cfg.stator_k_c, 234.5f);
  EXPECT_EQ(cfg.rotor_k_c, 225.0f);
  EXPECT_EQ(cfg.t_ref_uncert_k, 1.0f);
  EXPECT_EQ(cfg.rs_ref_bound_rel, 0.003f);
  EXPECT_EQ(cfg.tr_ref_bound_rel, 0.005f);
  EXPECT_EQ(cfg.stator_tol_k, 3.0f);
  EXPECT_EQ(cfg.rotor_tol_k, 5.0f);
  EXPECT_TRUE(std::isnan(t.stator_c));
  EXPECT_TRUE(std::isnan(t.rotor_c));
  EXPECT_EQ(t.stator_valid, 0);
  EXPECT_EQ(t.rotor_valid, 0);
  EXPECT_EQ(t.updates, 0u);
}

// R_S +39.3 % in copper from 20 degC: 1.393 x 254.5 - 234.5 = 120.0 degC, a 100 K rise.
TEST_F(Temperature, StatorCopperHandValue)
{
  const imest_result_t r = result(kRsRef * 1.393, 0.0, 1, kTrRef, 0.0, 1);
  EXPECT_EQ(imest_temperature_update(&t, &r), 3);
  EXPECT_NEAR(t.stator_c, 120.0, 0.05);
  EXPECT_EQ(t.stator_valid, 1);
  // the reference itself reads the reference temperature
  const imest_result_t r0 = result(kRsRef, 0.0, 1, kTrRef, 0.0, 1);
  (void)imest_temperature_update(&t, &r0);
  EXPECT_NEAR(t.stator_c, kTref, 1e-4);
  EXPECT_NEAR(t.rotor_c, kTref, 1e-4);
  EXPECT_EQ(t.t_end_s, 7.0);
  EXPECT_EQ(t.updates, 2u);
}

// The rotor: T_R falls as R_R rises; aluminium (k 225) from 20 degC: R_R +40.8 % is +100 K,
// i.e. T_R = T_R,ref / 1.408. rr_ohm = L_R / T_R.
TEST_F(Temperature, RotorAluminiumHandValue)
{
  const double ratio = (100.0 + 20.0 + 225.0) / (20.0 + 225.0); // 1.40816
  const imest_result_t r = result(kRsRef, 0.0, 1, kTrRef / ratio, 0.0, 1);
  EXPECT_EQ(imest_temperature_update(&t, &r), 3);
  EXPECT_NEAR(t.rotor_c, 120.0, 0.01);
  EXPECT_NEAR(t.rr_ohm, kLs / (kTrRef / ratio), 1e-5);
  // a copper cage (k 234.5) reads the same T_R ratio as a slightly warmer rotor
  cfg.rotor_k_c = 234.5f;
  ASSERT_EQ(imest_temperature_init(&t, &cfg), IMEST_OK);
  (void)imest_temperature_update(&t, &r);
  EXPECT_NEAR(t.rotor_c, ratio * 254.5 - 234.5, 0.01); // 123.9 degC
  // L_R given (unequal leakages) changes R_R, not the temperature
  cfg.lr_h = 0.3f;
  ASSERT_EQ(imest_temperature_init(&t, &cfg), IMEST_OK);
  (void)imest_temperature_update(&t, &r);
  EXPECT_NEAR(t.rr_ohm, 0.3 / (kTrRef / ratio), 1e-5);
  EXPECT_NEAR(t.rotor_c, ratio * 254.5 - 234.5, 0.01);
}

// stator_uncert_k = (T + k)(b + b_ref) + (R/R_ref) u_ref; rotor with b / (1 - b) for the T_R bound.
TEST_F(Temperature, UncertaintyPropagation)
{
  const double b_rs = 0.002, b_tr = 0.004;
  const double rs_ratio = 1.2, tr_ratio = 1.3; // R/R_ref and T_R,ref/T_R
  const imest_result_t r = result(kRsRef * rs_ratio, b_rs, 1, kTrRef / tr_ratio, b_tr, 1);
  (void)imest_temperature_update(&t, &r);
  const double ts = rs_ratio * (20.0 + 234.5) - 234.5;
  const double tr = tr_ratio * (20.0 + 225.0) - 225.0;
  EXPECT_NEAR(t.stator_c, ts, 1e-3);
  EXPECT_NEAR(t.rotor_c, tr, 1e-3);
  EXPECT_NEAR(t.stator_uncert_k, (ts + 234.5) * (b_rs + 0.003) + rs_ratio * 1.0, 1e-3);
  EXPECT_NEAR(t.rotor_uncert_k, (tr + 225.0) * (b_tr / (1.0 - b_tr) + 0.005) + tr_ratio * 1.0, 1e-3);
  // with exact references and no bound, nothing is left
  cfg.t_ref_uncert_k = 0.0f;
  cfg.rs_ref_bound_rel = 0.0f;
  cfg.tr_ref_bound_rel = 0.0f;
  ASSERT_EQ(imest_temperature_init(&t, &cfg), IMEST_OK);
  const imest_result_t r0 = result(kRsRef * rs_ratio, 0.0, 1, kTrRef / tr_ratio, 0.0, 1);
  (void)imest_temperature_update(&t, &r0);
  EXPECT_EQ(t.stator_uncert_k, 0.0f);
  EXPECT_EQ(t.rotor_uncert_k, 0.0f);
}

// The verdicts: the estimate's own, and the uncertainty within the tolerance.
TEST_F(Temperature, VerdictsFollowEstimateAndTolerance)
{
  // at 100 degC the stator's 3 K allow (3 - 1.31)/334.5 - 0.003 = 0.2 % of R_S bound
  const double rs_ratio = 334.5 / 254.5;
  imest_result_t r = result(kRsRef * rs_ratio, 0.002, 1, kTrRef, 0.0, 1);
  EXPECT_EQ(imest_temperature_update(&t, &r), 3);
  EXPECT_LE(t.stator_uncert_k, 3.0f);
  r.rs_bound_rel = 0.003;
  EXPECT_EQ(imest_temperature_update(&t, &r), 2);
  EXPECT_GT(t.stator_uncert_k, 3.0f);
  EXPECT_NEAR(t.stator_c, 100.0, 0.01); // the number stays
  // the estimator's verdict rules, whatever the bound
  r = result(kRsRef * rs_ratio, 0.0, 0, kTrRef, 0.0, 0);
  EXPECT_EQ(imest_temperature_update(&t, &r), 0);
  EXPECT_EQ(t.stator_valid, 0);
  EXPECT_EQ(t.rotor_valid, 0);
  EXPECT_NEAR(t.stator_c, 100.0, 0.01);
  EXPECT_NEAR(t.rotor_c, kTref, 1e-4);
  // the rotor's 5 K at 20 degC: (5 - 1)/245 - 0.005 = 1.13 % of T_R bound
  r = result(kRsRef, 0.0, 1, kTrRef, 0.011, 1);
  EXPECT_EQ(imest_temperature_update(&t, &r), 3);
  r.tr_bound_rel = 0.012;
  EXPECT_EQ(imest_temperature_update(&t, &r), 1);
  // a wider tolerance lets it through
  cfg.rotor_tol_k = 6.0f;
  ASSERT_EQ(imest_temperature_init(&t, &cfg), IMEST_OK);
  EXPECT_EQ(imest_temperature_update(&t, &r), 3);
}

TEST_F(Temperature, UnusableInputsGiveNaNAndNotValid)
{
  const double bad_rs[][2] = {{kNan, 0.0}, {0.0, 0.0},  {-1.0, 0.0},
                              {3.0, kNan}, {3.0, -0.1}, {std::numeric_limits<double>::infinity(), 0.0}};
  for (const auto &b : bad_rs) {
    const imest_result_t r = result(b[0], b[1], 1, kTrRef, 0.0, 1);
    EXPECT_EQ(imest_temperature_update(&t, &r), 2) << b[0] << " " << b[1];
    EXPECT_TRUE(std::isnan(t.stator_c));
    EXPECT_TRUE(std::isnan(t.stator_uncert_k));
    EXPECT_EQ(t.stator_valid, 0);
    EXPECT_EQ(t.rotor_valid, 1);
  }
  const double bad_tr[][2] = {{kNan, 0.0}, {0.0, 0.0}, {-0.1, 0.0}, {0.1, kNan}, {0.1, 1.0}, {0.1, -0.01}};
  for (const auto &b : bad_tr) {
    const imest_result_t r = result(kRsRef, 0.0, 1, b[0], b[1], 1);
    EXPECT_EQ(imest_temperature_update(&t, &r), 1) << b[0] << " " << b[1];
    EXPECT_TRUE(std::isnan(t.rotor_c));
    EXPECT_TRUE(std::isnan(t.rr_ohm));
    EXPECT_TRUE(std::isnan(t.rotor_uncert_k));
    EXPECT_EQ(t.rotor_valid, 0);
  }
  // a valid window after an unusable one is computed again (no state across windows)
  const imest_result_t ok = result(kRsRef, 0.0, 1, kTrRef, 0.0, 1);
  EXPECT_EQ(imest_temperature_update(&t, &ok), 3);
  EXPECT_NEAR(t.rotor_c, kTref, 1e-4);
}

TEST_F(Temperature, NullArguments)
{
  const imest_result_t r = result(kRsRef, 0.0, 1, kTrRef, 0.0, 1);
  EXPECT_EQ(imest_temperature_update(nullptr, &r), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_update(&t, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(t.updates, 0u);
  EXPECT_EQ(imest_temperature_init(nullptr, &cfg), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_init(&t, nullptr), IMEST_ERR_NULL);
  const char *field = "x";
  EXPECT_EQ(imest_temperature_config_check(nullptr, &field), IMEST_ERR_NULL);
  imest_temperature_config_default(nullptr, 1.0f, 1.0f, 1.0f, 1.0f); // does nothing
}

TEST_F(Temperature, BadConfigRejectedAndNamed)
{
  struct Case {
    float imest_temperature_config_t::*f;
    float v;
    const char *name;
  };
  const float nanf = std::numeric_limits<float>::quiet_NaN();
  const Case cases[] = {
      {&imest_temperature_config_t::t_ref_c, nanf, "t_ref_c"},
      {&imest_temperature_config_t::t_ref_c, 250.0f, "t_ref_c"},
      {&imest_temperature_config_t::t_ref_uncert_k, -1.0f, "t_ref_uncert_k"},
      {&imest_temperature_config_t::rs_ref_ohm, 0.0f, "rs_ref_ohm"},
      {&imest_temperature_config_t::rs_ref_bound_rel, 0.6f, "rs_ref_bound_rel"},
      {&imest_temperature_config_t::tr_ref_s, -0.1f, "tr_ref_s"},
      {&imest_temperature_config_t::tr_ref_bound_rel, nanf, "tr_ref_bound_rel"},
      {&imest_temperature_config_t::lr_h, 0.0f, "lr_h"},
      {&imest_temperature_config_t::stator_k_c, 50.0f, "stator_k_c"},
      {&imest_temperature_config_t::rotor_k_c, 2000.0f, "rotor_k_c"},
      {&imest_temperature_config_t::stator_tol_k, 0.0f, "stator_tol_k"},
      {&imest_temperature_config_t::rotor_tol_k, std::numeric_limits<float>::infinity(), "rotor_tol_k"},
  };
  const char *field = "x";
  ASSERT_EQ(imest_temperature_config_check(&cfg, &field), IMEST_OK);
  EXPECT_EQ(field, nullptr);
  const imest_result_t r = result(kRsRef, 0.0, 1, kTrRef, 0.0, 1);
  (void)imest_temperature_update(&t, &r);
  for (const Case &c : cases) {
    imest_temperature_config_t bad = cfg;
    bad.*c.f = c.v;
    EXPECT_EQ(imest_temperature_config_check(&bad, &field), IMEST_ERR_CONFIG) << c.name;
    EXPECT_STREQ(field, c.name);
    EXPECT_EQ(imest_temperature_init(&t, &bad), IMEST_ERR_CONFIG) << c.name;
    EXPECT_EQ(t.updates, 1u); // unchanged
  }
}

} // namespace
