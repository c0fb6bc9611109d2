/* SPDX-License-Identifier: Apache-2.0 */
// The config defaults write every field: a config on the stack (garbage in
// it) and a zeroed one come out of imest_config_default() byte for byte the
// same. tr_nominal_known was once left as it was, and T_R was then judged
// against the default nominal at random.
#include <gtest/gtest.h>

#include <cstring>

extern "C" {
#include "imest/imest.h"
#include "imest/imest_commission.h"
}

template <typename T, typename F> static void expect_every_field_written(F fill_default)
{
  T a, b;
  std::memset(&a, 0xA5, sizeof a);
  std::memset(&b, 0x00, sizeof b);
  fill_default(&a);
  fill_default(&b);
  EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
}

TEST(ConfigDefault, EstimatorWritesEveryField)
{
  expect_every_field_written<imest_config_t>(imest_config_default);
  imest_config_t cfg;
  std::memset(&cfg, 0xFF, sizeof cfg);
  imest_config_default(&cfg);
  EXPECT_EQ(cfg.tr_nominal_known, 0);
}

TEST(ConfigDefault, CommissioningWritesEveryField)
{
  expect_every_field_written<imest_comm_config_t>(imest_comm_config_default);
}
