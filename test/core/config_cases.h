/* SPDX-License-Identifier: Apache-2.0 */
// Config cases shared by the config tests of the full core (test_config.cpp) and of the least a
// firmware links (test_minimal_build.cpp): a motor, and the field a config is refused for.
#ifndef IMEST_TEST_CONFIG_CASES_H
#define IMEST_TEST_CONFIG_CASES_H

#include <gtest/gtest.h>

#include "imest/imest.h"

namespace config_cases {
// the 4 kW motor's constants, everything else the defaults
inline imest_config_t motor()
{
  imest_config_t c;
  imest_config_default(&c);
  c.pole_pairs = 2;
  c.ls_h = 0.1735f;
  c.sigma = 0.066f;
  return c;
}

// "" if the config passes, else the field imest_config_check() names; imest_init() must agree
inline const char *refused_field(const imest_config_t &c)
{
  const char *field = nullptr;
  const int rc = imest_config_check(&c, &field);
  static imest_t s;
  EXPECT_EQ(imest_init(&s, &c), rc) << "imest_init() agrees with imest_config_check()";
  return rc == IMEST_OK ? "" : field;
}
} // namespace config_cases

#endif
