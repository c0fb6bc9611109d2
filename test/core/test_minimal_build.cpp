/* SPDX-License-Identifier: Apache-2.0 */
// The least a firmware links (src/CMakeLists.txt, imest_minimal: IMEST_WITH_COMBINE=0,
// IMEST_WITH_FLUX=0, IMEST_WITH_ROTOR_HF=0): a config with what the build leaves out is refused
// naming the field, never estimated as if it were not there; the rest of a config passes.
#include <gtest/gtest.h>

#include "imest/imest.h"

namespace {
imest_config_t motor()
{
  imest_config_t c;
  imest_config_default(&c);
  c.pole_pairs = 2;
  c.ls_h = 0.1735f;
  c.sigma = 0.066f;
  return c;
}

const char *refused_field(const imest_config_t &c)
{
  const char *field = nullptr;
  const int rc = imest_config_check(&c, &field);
  static imest_t s;
  EXPECT_EQ(imest_init(&s, &c), rc) << "imest_init() agrees with imest_config_check()";
  return rc == IMEST_OK ? "" : field;
}
} // namespace

TEST(MinimalBuild, PlainConfigPasses)
{
  EXPECT_STREQ(refused_field(motor()), "");
}

TEST(MinimalBuild, DeepBarRotorIsRefused)
{
  imest_config_t c = motor();
  c.rotor_hf_rr_ratio = 5.66f;
  c.rotor_hf_sigma_ratio = 0.557f;
  EXPECT_STREQ(refused_field(c), "rotor_hf_rr_ratio");
}

TEST(MinimalBuild, MagnetisingCurveIsRefused)
{
  imest_config_t c = motor();
  const float i_a[2] = {3.3f, 8.1f}, l_h[2] = {0.230f, 0.160f};
  for (int k = 0; k < 2; ++k) {
    c.ls_curve_i_a[k] = i_a[k];
    c.ls_curve_h[k] = l_h[k];
  }
  c.ls_curve_points = 2u;
  EXPECT_STREQ(refused_field(c), "ls_curve_points");
}
