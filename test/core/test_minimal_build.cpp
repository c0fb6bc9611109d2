/* SPDX-License-Identifier: Apache-2.0 */
// The least a firmware links (src/CMakeLists.txt, imest_minimal: IMEST_WITH_COMBINE=0,
// IMEST_WITH_FLUX=0, IMEST_WITH_ROTOR_HF=0): a config with what the build leaves out is refused
// naming the field, never estimated as if it were not there; the rest of a config passes.
#include <gtest/gtest.h>

#include "config_cases.h"

using config_cases::motor;
using config_cases::refused_field;

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
