/* SPDX-License-Identifier: Apache-2.0 */
// imest-replay's command line reaches the estimator's config: each option of
// the duty-cycle input sets its field, the inverter model's default
// uncertainty, and the options refused with the phase-voltage input
// (tools/replay/replay_options.c, linked directly).
#include <gtest/gtest.h>

#include <string>
#include <vector>

extern "C" {
#include "replay_options.h"
#include "tool_args.h"
}

namespace {
struct Parsed {
  int rc;
  replay_opts_t o;
};

Parsed parse(const std::vector<std::string> &extra)
{
  std::vector<std::string> args = {"imest-replay", "--pole-pairs", "2", "--ls", "0.2", "--sigma", "0.07"};
  args.insert(args.end(), extra.begin(), extra.end());
  args.push_back("x.csv");
  std::vector<char *> argv;
  argv.reserve(args.size());
  for (auto &a : args) argv.push_back(a.data());
  Parsed p;
  p.rc = replay_parse((int)argv.size(), argv.data(), &p.o);
  return p;
}
} // namespace

TEST(ReplayOptions, DutyInputFlagsSetTheirFields)
{
  const Parsed p = parse({"--voltage",
                          "duty",
                          "--dead-time",
                          "2e-6",
                          "--v-switch=1",
                          "--r-switch",
                          "0.02",
                          "--v-diode",
                          "0.8",
                          "--r-diode",
                          "0.01",
                          "--i-band",
                          "0.5",
                          "--pwm-hz",
                          "16000",
                          "--pwm-timing",
                          "centred",
                          "--rs",
                          "1.4",
                          "--rs-tolerance",
                          "0.1",
                          "--timing-uncertainty",
                          "1e-6",
                          "--u-delay",
                          "-30e-6",
                          "--angle-observer-hz",
                          "-1"});
  ASSERT_EQ(p.rc, -1);
  const imest_config_t &c = p.o.cfg;
  EXPECT_EQ(p.o.voltage, REPLAY_VOLTAGE_DUTY);
  EXPECT_FLOAT_EQ(c.inverter.dead_time_s, 2e-6f);
  EXPECT_FLOAT_EQ(c.inverter.v_switch_v, 1.0f);
  EXPECT_FLOAT_EQ(c.inverter.r_switch_ohm, 0.02f);
  EXPECT_FLOAT_EQ(c.inverter.v_diode_v, 0.8f);
  EXPECT_FLOAT_EQ(c.inverter.r_diode_ohm, 0.01f);
  EXPECT_FLOAT_EQ(c.inverter.i_band_a, 0.5f);
  EXPECT_FLOAT_EQ(c.inverter.uncertainty, 0.2f); // a model given, its quality not: data-sheet numbers
  EXPECT_FLOAT_EQ(c.pwm_hz, 16000.0f);
  EXPECT_EQ(c.pwm_timing, IMEST_PWM_CENTRED);
  EXPECT_FLOAT_EQ(c.rs_nominal_ohm, 1.4f);
  EXPECT_FLOAT_EQ(c.rs_tolerance, 0.1f);
  EXPECT_FLOAT_EQ(c.timing_uncertainty_s, 1e-6f);
  EXPECT_FLOAT_EQ(c.u_delay_s, -30e-6f);
  EXPECT_FLOAT_EQ(c.angle_observer_hz, -1.0f);
}

TEST(ReplayOptions, InverterUncertaintyDefaults)
{
  imest_config_t lib;
  imest_config_default(&lib);
  // no model: the library's default (unknown)
  Parsed p = parse({"--voltage", "duty"});
  ASSERT_EQ(p.rc, -1);
  EXPECT_FLOAT_EQ(p.o.cfg.inverter.uncertainty, lib.inverter.uncertainty);
  EXPECT_LT(p.o.cfg.inverter.uncertainty, 0.0f);
  // the carrier or the timing alone is no model of the error
  p = parse({"--voltage", "duty", "--pwm-hz", "16000", "--pwm-timing", "last"});
  ASSERT_EQ(p.rc, -1);
  EXPECT_LT(p.o.cfg.inverter.uncertainty, 0.0f);
  EXPECT_EQ(p.o.cfg.pwm_timing, IMEST_PWM_LAST_PERIOD);
  // any one number of the model, e.g. a compensated inverter's --dead-time 0
  for (const char *flag : {"--dead-time", "--v-switch", "--r-switch", "--v-diode", "--r-diode", "--i-band"}) {
    p = parse({"--voltage", "duty", flag, "0"});
    ASSERT_EQ(p.rc, -1) << flag;
    EXPECT_FLOAT_EQ(p.o.cfg.inverter.uncertainty, 0.2f) << flag;
  }
  // stated, it stands (also a negative one: unknown)
  p = parse({"--voltage", "duty", "--dead-time", "1e-6", "--inverter-uncertainty", "0.05"});
  EXPECT_FLOAT_EQ(p.o.cfg.inverter.uncertainty, 0.05f);
  p = parse({"--voltage", "duty", "--dead-time", "1e-6", "--inverter-uncertainty", "-1"});
  EXPECT_FLOAT_EQ(p.o.cfg.inverter.uncertainty, -1.0f);
}

TEST(ReplayOptions, PhaseInputKeepsTheLibraryDefaults)
{
  imest_config_t lib;
  imest_config_default(&lib);
  const Parsed p = parse({});
  ASSERT_EQ(p.rc, -1);
  EXPECT_EQ(p.o.voltage, REPLAY_VOLTAGE_PHASE);
  EXPECT_EQ(p.o.cfg.pwm_timing, lib.pwm_timing);
  EXPECT_FLOAT_EQ(p.o.cfg.pwm_hz, lib.pwm_hz);
  EXPECT_FLOAT_EQ(p.o.cfg.inverter.dead_time_s, lib.inverter.dead_time_s);
  EXPECT_FLOAT_EQ(p.o.cfg.inverter.uncertainty, lib.inverter.uncertainty);
  EXPECT_FLOAT_EQ(p.o.cfg.rs_tolerance, lib.rs_tolerance);
  EXPECT_FLOAT_EQ(p.o.cfg.timing_uncertainty_s, lib.timing_uncertainty_s);
  EXPECT_FLOAT_EQ(p.o.cfg.rs_nominal_ohm, lib.rs_nominal_ohm);
  EXPECT_EQ(parse({"--pwm-timing", "next"}).rc, TOOL_EXIT_USAGE);
  EXPECT_EQ(p.o.cfg.voltage_kind, lib.voltage_kind);
  EXPECT_EQ(parse({"--voltage-kind", "smooth"}).o.cfg.voltage_kind, IMEST_VOLTAGE_SMOOTH);
  EXPECT_EQ(parse({"--voltage-kind=staircase"}).o.cfg.voltage_kind, IMEST_VOLTAGE_STAIRCASE);
  EXPECT_EQ(parse({"--voltage-kind", "sine"}).rc, TOOL_EXIT_USAGE);
  EXPECT_EQ(parse({"--voltage", "duty", "--voltage-kind", "smooth"}).rc, TOOL_EXIT_USAGE);
  EXPECT_EQ(parse({"--voltage", "duty", "--voltage-kind", "staircase"}).rc, -1);
  EXPECT_EQ(parse({"--inverter-uncertainty", "0.1"}).rc, TOOL_EXIT_USAGE);
  EXPECT_EQ(parse({"--voltage", "duty", "--u-limit", "auto"}).rc, -1); // the default: nothing to refuse
  EXPECT_EQ(parse({"--voltage", "duty", "--u-limit", "400"}).rc, TOOL_EXIT_USAGE);
}

// --temperatures: three references into the temperature module's config, L_R from --ls; a
// malformed or out-of-range value is a usage error; without it no temperature columns.
TEST(ReplayOptions, TemperaturesReferences)
{
  const Parsed none = parse({});
  ASSERT_EQ(none.rc, -1);
  EXPECT_EQ(none.o.temperatures, 0);
  const Parsed p = parse({"--temperatures", "21.5,3.2,0.121"});
  ASSERT_EQ(p.rc, -1);
  EXPECT_EQ(p.o.temperatures, 1);
  EXPECT_FLOAT_EQ(p.o.temp_cfg.t_ref_c, 21.5f);
  EXPECT_FLOAT_EQ(p.o.temp_cfg.rs_ref_ohm, 3.2f);
  EXPECT_FLOAT_EQ(p.o.temp_cfg.tr_ref_s, 0.121f);
  EXPECT_FLOAT_EQ(p.o.temp_cfg.lr_h, 0.2f);
  EXPECT_EQ(p.o.temp_cfg.stator_k_c, 234.5f);
  EXPECT_EQ(parse({"--temperatures=20,3,0.1"}).rc, -1);
  for (const char *bad :
       {"20,3", "20,3,0.1,4", "20,x,0.1", "20,0,0.1", "20,3,-0.1", "300,3,0.1", "20,3,0.1x"})
    EXPECT_EQ(parse({"--temperatures", bad}).rc, 2) << bad;
}

TEST(ReplayOptions, EncoderCountsSetTheirField)
{
  const Parsed p = parse({"--encoder-counts", "4096"});
  ASSERT_EQ(p.rc, -1);
  EXPECT_FLOAT_EQ(p.o.cfg.encoder_counts_per_rev, 4096.0f);
  EXPECT_FLOAT_EQ(parse({}).o.cfg.encoder_counts_per_rev, 0.0f); // unknown: the observer as before
}
