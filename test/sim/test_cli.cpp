/* SPDX-License-Identifier: Apache-2.0 */
// imest-sim command line: flag parsing, errors, CSV header and first row.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <sys/wait.h>
#include <string>
#include <unistd.h>
#include <vector>

#include "imsim_cli.h"

namespace {
int parse(std::vector<std::string> in, imsim_config_t &c, imsim_cli_opts_t &o, std::string *err = nullptr)
{
  // the parsed options point into argv (as with a real main): keep it alive
  static std::vector<std::string> args;
  args = std::move(in);
  args.insert(args.begin(), "imest-sim");
  std::vector<char *> argv;
  argv.reserve(args.size());
  for (auto &a : args) argv.push_back(a.data());
  char e[256];
  const int r = imsim_cli_parse(int(argv.size()), argv.data(), &c, &o, e, sizeof e);
  if (err) *err = e;
  return r;
}
} // namespace

TEST(SimCli, FlagsSetTheConfig)
{
  imsim_config_t c;
  imsim_cli_opts_t o;
  ASSERT_EQ(parse({"--duration", "3.5",  "--fs",   "8000",  "--out",     "x.csv",  "--pole-pairs",   "3",
                   "--ls",       "0.3",  "--lr",   "0.31",  "--sigma",   "0.1",    "--rs",           "4.5",
                   "--tr",       "0.11", "--j",    "0.002", "--b",       "0.0002", "--supply",       "pwm",
                   "--vll",      "220",  "--freq", "50",    "--load-nm", "1.5",    "--ideal-sensors"},
                  c, o),
            0);
  EXPECT_EQ(c.duration_s, 3.5);
  EXPECT_EQ(c.fs_hz, 8000);
  EXPECT_STREQ(o.out, "x.csv");
  EXPECT_EQ(c.pole_pairs, 3);
  EXPECT_EQ(c.ls_h, 0.3);
  EXPECT_EQ(c.lr_h, 0.31);
  EXPECT_EQ(c.sigma, 0.1);
  EXPECT_EQ(c.rs_ohm, 4.5);
  EXPECT_EQ(c.tr_s, 0.11);
  EXPECT_EQ(c.j_kgm2, 0.002);
  EXPECT_EQ(c.b_nms, 0.0002);
  EXPECT_EQ(c.supply, IMSIM_SUPPLY_PWM);
  EXPECT_EQ(c.vll_v, 220);
  EXPECT_EQ(c.freq_hz, 50);
  EXPECT_EQ(c.load_nm, 1.5);
  EXPECT_TRUE(c.ideal_sensors);
  ASSERT_EQ(parse({"--modulation", "svpwm", "--timing=firmware", "--dead-time", "2e-6", "--v-switch", "1.1",
                   "--r-switch", "0.01", "--v-diode", "0.8", "--r-diode", "0.02", "--vdc-range", "900"},
                  c, o),
            0);
  EXPECT_EQ(c.modulation, IMSIM_MOD_SVPWM);
  EXPECT_EQ(c.timing, IMSIM_TIMING_FIRMWARE);
  EXPECT_EQ(c.dead_time_s, 2e-6);
  EXPECT_EQ(c.v_switch_v, 1.1);
  EXPECT_EQ(c.r_switch_ohm, 0.01);
  EXPECT_EQ(c.v_diode_v, 0.8);
  EXPECT_EQ(c.r_diode_ohm, 0.02);
  EXPECT_EQ(c.vdc_range_v, 900);
  std::string e;
  EXPECT_NE(parse({"--v-diode", "-1"}, c, o, &e), 0);
  EXPECT_NE(parse({"--timing", "late"}, c, o, &e), 0);
  EXPECT_NE(e.find("ideal|firmware"), std::string::npos) << e;
  EXPECT_NE(parse({"--preset", "55kw"}, c, o, &e), 0);
  EXPECT_NE(e.find("exp1|exp2|4kw|11kw|15kw|37kw|75kw"), std::string::npos) << e;
}

TEST(SimCli, PresetAppliesFirstWhateverItsPosition)
{
  imsim_config_t c;
  imsim_cli_opts_t o;
  ASSERT_EQ(
      parse({"--vll", "100", "--preset", "exp2", "--seed=7", "--supply=ifoc", "--ifoc-tr", "0.1"}, c, o), 0);
  EXPECT_EQ(c.vll_v, 100);  // explicit flag wins over the preset
  EXPECT_EQ(c.freq_hz, 30); // from exp2
  EXPECT_EQ(c.load_nm, 2.064);
  EXPECT_EQ(c.duration_s, 3600);
  EXPECT_EQ(c.seed, 7u);
  EXPECT_EQ(c.supply, IMSIM_SUPPLY_IFOC);
  EXPECT_EQ(c.ifoc_tr_s, 0.1);
  ASSERT_EQ(parse({"--preset", "exp1"}, c, o), 0);
  EXPECT_EQ(c.freq_hz, 60);
  EXPECT_EQ(c.vll_v, 230);
  EXPECT_EQ(c.duration_s, 2);
}

TEST(SimCli, BadFlagsAreRejectedWithAMessage)
{
  imsim_config_t c;
  imsim_cli_opts_t o;
  std::string e;
  const std::vector<std::vector<std::string>> bad = {
      {"--bogus"},           {"--fs"},          {"--fs", "abc"},      {"--fs", "-5"}, {"--sigma", "1.2"},
      {"--supply", "dc"},    {"--preset", "x"}, {"--duration", "1x"}, {"positional"}, {"--pole-pairs", "2.5"},
      {"--ideal-sensors=1"}, {"--tr", "nan"},   {"--adc-bits", "40"}};
  for (const auto &b : bad) {
    EXPECT_NE(parse(b, c, o, &e), 0) << b[0];
    EXPECT_FALSE(e.empty()) << b[0];
  }
}

TEST(SimCli, HeaderStartsWithTheContractColumns)
{
  const std::string h = imsim_cli_header();
  EXPECT_EQ(h.rfind("t,u_a,u_b,u_c,i_a,i_b,i_c,theta,T_R_true_s,R_S_true_ohm,speed_rad_s,torque_nm", 0), 0u);
}

#ifdef IMEST_SIM_EXE
TEST(SimCli, ExecutableWritesCsvAndFailsOnBadFlags)
{
  const std::string out = ::testing::TempDir() + "imsim_cli_test.csv";
  const std::string cmd =
      std::string(IMEST_SIM_EXE) + " --preset exp1 --duration 0.01 --ideal-sensors --out " + out;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream f(out);
  std::string header, row;
  std::getline(f, header);
  std::getline(f, row);
  EXPECT_EQ(header, imsim_cli_header());
  double t, ua;
  ASSERT_EQ(std::sscanf(row.c_str(), "%lf,%lf", &t, &ua), 2);
  EXPECT_EQ(t, 0.0);
  EXPECT_NEAR(ua, std::sqrt(2.0 / 3.0) * 230, 1e-6);
  int rows = 1;
  while (std::getline(f, row)) ++rows;
  EXPECT_EQ(rows, 41); // t = 0 .. 0.01 at 4 kHz
  const std::string badcmd = std::string(IMEST_SIM_EXE) + " --fs nope > /dev/null 2>&1";
  EXPECT_NE(std::system(badcmd.c_str()), 0);
  const std::string badcfg =
      std::string(IMEST_SIM_EXE) + " --supply pwm --carrier-hz 9999 --duration 0.01 > /dev/null 2>&1";
  EXPECT_NE(std::system(badcfg.c_str()), 0);
  std::remove(out.c_str());
}
#endif

namespace {
std::set<std::string> flags_in(const std::string &text)
{
  std::set<std::string> out;
  const std::regex re("--[a-z0-9][a-z0-9-]*");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it)
    if (it->str() != "--opt") out.insert(it->str()); // "--opt value and --opt=value"
  return out;
}
} // namespace

// The parser, --help and sim/README.md's CLI section name the same flags.
TEST(SimCli, HelpAndReadmeListEveryFlag)
{
  const char *names[256];
  const size_t n = imsim_cli_flags(names, 256);
  ASSERT_LE(n, 256u);
  const std::set<std::string> parser(names, names + n);
  EXPECT_EQ(parser.size(), n) << "a flag is listed twice";
  EXPECT_EQ(flags_in(imsim_cli_usage()), parser);
#ifdef IMSIM_README
  std::ifstream f(IMSIM_README);
  ASSERT_TRUE(f.good());
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string md = ss.str();
  const size_t a = md.find("\n## CLI");
  ASSERT_NE(a, std::string::npos);
  const size_t b = md.find("\n## ", a + 1);
  EXPECT_EQ(flags_in(md.substr(a, b - a)), parser);
#endif
  // every flag the parser lists is accepted by it
  for (const auto &fl : parser) {
    imsim_config_t c;
    imsim_cli_opts_t o;
    std::string e;
    const char *argv[] = {"imest-sim", fl.c_str(), "1"};
    char err[256];
    imsim_cli_parse(3, const_cast<char **>(argv), &c, &o, err, sizeof err);
    EXPECT_EQ(std::string(err).find("unknown option"), std::string::npos) << fl << ": " << err;
  }
}

#ifdef IMEST_SIM_EXE
namespace {
int run_capture(const std::string &args, std::string &err_text)
{
  // one file per process and call: CTest runs the cases of this file in parallel
  static int calls = 0;
  const std::string errf = ::testing::TempDir() + "imsim_cli_stderr_" + std::to_string(getpid()) + "_" +
                           std::to_string(++calls) + ".txt";
  const int st = std::system((std::string(IMEST_SIM_EXE) + " " + args + " > /dev/null 2> " + errf).c_str());
  std::ifstream f(errf);
  std::stringstream ss;
  ss << f.rdbuf();
  err_text = ss.str();
  std::remove(errf.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
} // namespace

// Exit status 2 for a configuration refused with an explanation; 0 with a warning for a clipped
// modulation; 1 for an output that cannot be written.
TEST(SimCli, SaysWhatIsWrong)
{
  std::string e;
  EXPECT_EQ(run_capture("--supply pwm --vmeas inst --duration 0.01 --out -", e), 2);
  EXPECT_NE(e.find("zero vector"), std::string::npos) << e;
  EXPECT_NE(e.find("'avg'"), std::string::npos) << e;
  EXPECT_EQ(run_capture("--supply pwm --vdc 300 --duration 0.05 --out -", e), 0);
  EXPECT_NE(e.find("in 100 % of the half carrier periods (1000 of 1000)"), std::string::npos) << e;
  EXPECT_NE(e.find("needs Vdc >= 375.6 V, given --vdc 300.0 V"), std::string::npos) << e;
  EXPECT_EQ(run_capture("--supply pwm --duration 0.05 --out -", e), 0);
  EXPECT_EQ(e, "");
  EXPECT_EQ(run_capture("--duration 0.01 --out /nonexistent-dir/x.csv", e), 1);
  EXPECT_NE(e.find("cannot open"), std::string::npos) << e;
  EXPECT_EQ(run_capture("--fs nope", e), 2);
}
#endif

#ifdef IMEST_SIM_EXE
// A drive preset writes the duty and bus columns: duties in [0, 1] from this row to the next,
// the bus through its 12-bit ADC.
TEST(SimCli, DrivePresetWritesDutyAndBusColumns)
{
  const std::string out = ::testing::TempDir() + "imsim_cli_drive.csv";
  std::string e;
  ASSERT_EQ(run_capture("--preset 4kw --duration 0.01 --out " + out, e), 0) << e;
  std::ifstream f(out);
  std::string header, row;
  std::getline(f, header);
  EXPECT_EQ(header.substr(header.size() - 17), ",d_a,d_b,d_c,v_dc");
  int rows = 0;
  while (std::getline(f, row)) {
    std::vector<double> v;
    std::stringstream ss(row);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(std::strtod(cell.c_str(), nullptr));
    ASSERT_EQ(v.size(), 31u);
    for (int k = 27; k < 30; ++k) {
      EXPECT_GE(v[k], 0.0);
      EXPECT_LE(v[k], 1.0);
    }
    EXPECT_NEAR(v[30], 560.0, 2.0);
    ++rows;
  }
  EXPECT_EQ(rows, 81); // 8 kHz
  std::remove(out.c_str());
  EXPECT_EQ(run_capture("--supply pwm --timing firmware --duration 0.01 --out -", e), 2);
  EXPECT_NE(e.find("integer multiple"), std::string::npos) << e;
}
#endif
