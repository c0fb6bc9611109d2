/* SPDX-License-Identifier: Apache-2.0 */
// imest-replay with the inputs users really have: each bad input gets a message
// that says what is wrong and what to do, and the exit code of the convention
// (0 ok, 1 unusable data, 2 bad option). One test per row of the matrix.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <regex>
#include <set>
#include <string>

#include "tool_run.hpp"

using namespace tool_run;

namespace {
// 3.2 s of the paper's exp2 at 4 kHz, t printed in full.
const std::string &base()
{
  return sim_csv("exp2_short.csv", "--preset exp2 --duration 3.2 --supply vf");
}
// 8 s, more valid windows (for the conventions).
const std::string &base8()
{
  return sim_csv("exp2_8s.csv", "--preset exp2 --duration 8 --supply vf --seed 5");
}

bool has(const Out &o, const std::string &phrase)
{
  return o.err.find(phrase) != std::string::npos;
}

std::string with_t(const std::string &name, const std::function<std::string(double t, long k)> &t_of)
{
  return rewrite(base(), name, [&](std::vector<std::string> &f, long k) {
    f[0] = t_of(std::stod(f[0]), k);
    return true;
  });
}

int valid_windows(const Out &o)
{
  int n = 0;
  for (const auto &r : rows(o.out))
    if (r.size() > 4 && r[4] == "1") n++;
  return n;
}

// windows whose T_R is valid (column tr_valid, the 22nd)
int tr_valid_windows(const Out &o)
{
  int n = 0;
  for (const auto &r : rows(o.out))
    if (r.size() > 21 && r[21] == "1") n++;
  return n;
}
} // namespace

TEST(ReplayInput, TimeInMillisecondsIsNamedWithTheRateItWouldBe)
{
  const Out o = replay(with_t("ms.csv", [](double t, long) { return fmt("%.9g", t * 1e3); }));
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "If t is in milliseconds (4000 Hz)")) << o.err;
  EXPECT_TRUE(has(o, "--fs 4000")) << o.err;
  EXPECT_FALSE(has(o, "invalid setting")) << o.err;
}

TEST(ReplayInput, TimeAsSampleIndexAsksForFs)
{
  const Out o = replay(with_t("idx.csv", [](double, long k) { return std::to_string(k); }));
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "t counts samples")) << o.err;
  EXPECT_TRUE(has(o, "--fs HZ")) << o.err;
}

// With --fs, t only orders the rows: ms and a sample index give the same
// windows as t in seconds, dated in seconds.
TEST(ReplayInput, FsTakesMillisecondAndIndexTime)
{
  const Out ref = replay(base());
  ASSERT_EQ(ref.code, 0) << ref.err;
  const Out ms = replay(with_t("ms.csv", [](double t, long) { return fmt("%.9g", t * 1e3); }), "--fs 4000");
  const Out idx = replay(with_t("idx.csv", [](double, long k) { return std::to_string(k); }), "--fs=4000");
  ASSERT_EQ(ms.code, 0) << ms.err;
  ASSERT_EQ(idx.code, 0) << idx.err;
  EXPECT_EQ(ms.out, ref.out);
  EXPECT_EQ(idx.out, ref.out);
}

// 1 kHz was refused by the default speed limit (3000 rad/s >= 3 fs); the
// default now follows the rate.
TEST(ReplayInput, OneKilohertzLogIsEstimated)
{
  const Out o = replay(sim_csv("exp2_1k.csv", "--preset exp2 --duration 3.2 --supply vf --fs 1000"));
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(rows(o.out).size(), 4u);
  // T_R; R_S is refused (rs_uncertain): a 1 kHz PWM staircase could move it
  // by about 20 % (docs/METHOD.md §18)
  EXPECT_GE(tr_valid_windows(o), 1) << o.out;
  EXPECT_TRUE(has(o, "at 1000 Hz")) << o.err;
}

TEST(ReplayInput, SpeedLimitBeyondPiPerSampleIsAUsageError)
{
  const Out o = replay(sim_csv("exp2_1k.csv", "--preset exp2 --duration 3.2 --supply vf --fs 1000"),
                       "--speed-limit 5000");
  EXPECT_EQ(o.code, 2);
  EXPECT_TRUE(has(o, "below 3 x fs = 3000 rad/s")) << o.err;
}

TEST(ReplayInput, Log250HzNamesTheFilterLimitAndTheLowestRate)
{
  const std::string &p = sim_csv("exp2_250.csv", "--preset exp2 --duration 3.2 --supply vf --fs 250");
  Out o = replay(p);
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "needs fs above 2.5 x its cut-off (250 Hz)")) << o.err;
  EXPECT_TRUE(has(o, "about 1 kHz")) << o.err;
  EXPECT_TRUE(has(o, "--filter-hz 50 works")) << o.err;
  // the cut-off the message suggests does work at constant speed
  o = replay(p, "--filter-hz 50");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_GE(tr_valid_windows(o), 1) << o.out;
  // the user's own cut-off that the rate cannot carry is a usage error
  EXPECT_EQ(replay(p, "--filter-hz 100").code, 2);
}

// t printed with 4 decimals at 4 kHz steps by 0.0002 or 0.0003: rounding, not
// irregular sampling. The windows are those of the full-precision t.
TEST(ReplayInput, FourDecimalTimeIsReadAsRounding)
{
  const Out ref = replay(base());
  const std::string p = with_t("d4.csv", [](double t, long) { return fmt("%.4f", t); });
  Out o = replay(p);
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(has(o, "printed with 4 decimals")) << o.err;
  EXPECT_EQ(estimates(o.out), estimates(ref.out));
  o = replay(p, "--fs 4000");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out, ref.out);
}

// Rounding is tolerated, a gap is not: one missing sample is still named.
TEST(ReplayInput, MissingSampleIsRefusedDespiteRounding)
{
  const std::string p = rewrite(base(), "gap.csv", [](std::vector<std::string> &f, long k) {
    f[0] = fmt("%.4f", std::stod(f[0]));
    return k != 5000;
  });
  const Out o = replay(p);
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, ":5002: irregular sampling")) << o.err;
  EXPECT_TRUE(has(o, "samples are missing")) << o.err;
  EXPECT_TRUE(has(o, "give --fs HZ")) << o.err;
}

// t with fewer decimals than the sample period needs repeats itself: named,
// and --fs reads the file.
TEST(ReplayInput, TooCoarseTimeAsksForFs)
{
  const std::string p = with_t("d3.csv", [](double t, long) { return fmt("%.3f", t); });
  Out o = replay(p);
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "t is printed with 3 decimals, too few for its mean step of 0.00025 s")) << o.err;
  EXPECT_TRUE(has(o, "give --fs HZ")) << o.err;
  o = replay(p, "--fs 4000");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out, replay(base()).out);
}

// A recording cut off mid-write: the last line is left out with a warning.
TEST(ReplayInput, TruncatedLastLineIsLeftOut)
{
  std::string text = slurp(base());
  const Out ref = replay(base());
  const std::string whole = text;
  text.resize(text.size() - 30); // cut inside the last line
  const Out o = replay(write("cut.csv", text));
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(has(o, "the last line looks cut off")) << o.err;
  EXPECT_TRUE(has(o, ":12802:")) << o.err;
  EXPECT_EQ(rows(o.out).size(), rows(ref.out).size());
  // a short line that is not the last is an error
  const size_t mid = whole.find('\n', whole.size() / 2);
  std::string bad = whole.substr(0, mid) + "\n0.5,1,2" + whole.substr(mid);
  EXPECT_EQ(replay(write("short_mid.csv", bad)).code, 1);
}

TEST(ReplayInput, OptionEqualsValueAndStdin)
{
  const Out ref = replay(base(), "--window 1 --filter-hz 100");
  ASSERT_EQ(ref.code, 0) << ref.err;
  const Out eq =
      run(std::string(REPLAY_BIN) +
          " --pole-pairs=2 --ls=0.2908 --sigma=0.096 --ls-uncertainty=0 --sigma-uncertainty=0 --window=1 "
          "--filter-hz=100 " +
          base());
  EXPECT_EQ(eq.code, 0) << eq.err;
  EXPECT_EQ(eq.out, ref.out);
  const Out in = replay("- < " + base());
  EXPECT_EQ(in.code, 0) << in.err;
  EXPECT_EQ(in.out, ref.out);
  const Out pipe = run("cat " + base() + " | " + REPLAY_BIN + kMotor + " -");
  EXPECT_EQ(pipe.code, 0) << pipe.err;
  EXPECT_EQ(pipe.out, ref.out);
}

TEST(ReplayInput, ExitCodes)
{
  Out o = replay(base(), "--no-such-option");
  EXPECT_EQ(o.code, 2);
  EXPECT_TRUE(has(o, "unknown option '--no-such-option'")) << o.err;
  o = run(std::string(REPLAY_BIN) + kMotor + base() + " --window");
  EXPECT_EQ(o.code, 2);
  EXPECT_TRUE(has(o, "--window needs a value")) << o.err;
  o = replay(base(), "--quiet=1");
  EXPECT_EQ(o.code, 2);
  EXPECT_TRUE(has(o, "--quiet takes no value")) << o.err;
  o = replay(base(), "--window abc");
  EXPECT_EQ(o.code, 2);
  o = replay(tmpdir() + "/no-such-file.csv");
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "cannot open")) << o.err;
  o = replay(tmpdir());
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "cannot read: Is a directory")) << o.err;
  o = replay("- < /dev/null");
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "stdin: empty file")) << o.err;
  o = run(std::string(REPLAY_BIN) + " --help");
  EXPECT_EQ(o.code, 0);
  EXPECT_EQ(replay(base()).code, 0);
}

// Every option the parser knows (each "--name" literal of
// tools/replay/replay_options.c) is in --help and in the README's entry.
TEST(ReplayInput, HelpAndReadmeNameEveryOption)
{
  const Out o = run(std::string(REPLAY_BIN) + " --help");
  ASSERT_EQ(o.code, 0);
  const std::string src = slurp(std::string(SOURCE_DIR) + "/tools/replay/replay_options.c");
  const std::string readme = slurp(std::string(SOURCE_DIR) + "/README.md");
  const size_t a = readme.find("* `imest-replay`"), b = readme.find("* `imest-sim`");
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  const std::string entry = readme.substr(a, b - a);
  const std::regex lit("\"(--[a-z0-9-]+)\"");
  std::set<std::string> opts;
  for (auto it = std::sregex_iterator(src.begin(), src.end(), lit); it != std::sregex_iterator(); ++it)
    opts.insert((*it)[1]);
  EXPECT_GE(opts.size(), 35u); // the parser's options were found
  for (const std::string &opt : opts) {
    EXPECT_NE(o.out.find(opt), std::string::npos) << opt << " not in --help";
    if (opt != "--help") EXPECT_NE(entry.find("`" + opt), std::string::npos) << opt << " not in README.md";
  }
  for (const char *s : {"--opt=VALUE", "\"-\" = stdin", "-h, --help"})
    EXPECT_NE(o.out.find(s), std::string::npos) << s;
}

// theta wrapped to [0, 2 pi) gives the estimates of the unwrapped angle.
TEST(ReplayInput, WrappedThetaGivesTheSameEstimates)
{
  const Out ref = replay(base8());
  const std::string p = rewrite(base8(), "wrapped.csv", [](std::vector<std::string> &f, long) {
    const double th = std::stod(f[7]);
    f[7] = fmt("%.12g", th - 2 * M_PI * std::floor(th / (2 * M_PI)));
    return true;
  });
  const Out o = replay(p);
  ASSERT_EQ(o.code, 0) << o.err;
  const auto a = rows(ref.out), b = rows(o.out);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 1; k < a.size(); ++k) {
    EXPECT_EQ(a[k][4], b[k][4]) << "window " << k; // same verdict
    EXPECT_NEAR(std::stod(a[k][1]), std::stod(b[k][1]), 1e-4 * std::stod(a[k][1])) << "window " << k;
  }
}

// theta against the field fits a motor with a tiny T_R and looks valid:
// refused with the fix.
TEST(ReplayInput, ThetaAgainstTheFieldIsRefused)
{
  const std::string p = rewrite(base8(), "neg_theta.csv", [](std::vector<std::string> &f, long) {
    f[7] = fmt("%.12g", -std::stod(f[7]));
    return true;
  });
  const Out o = replay(p);
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o, "theta must increase with the a-b-c field")) << o.err;
  EXPECT_TRUE(has(o, "Negate theta")) << o.err;
}

TEST(ReplayInput, InvertedCurrentSignIsNamed)
{
  const std::string p = rewrite(base8(), "neg_i.csv", [](std::vector<std::string> &f, long) {
    for (int j = 4; j <= 6; ++j) f[j] = fmt("%.9g", -std::stod(f[j]));
    return true;
  });
  const Out o = replay(p);
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(valid_windows(o), 0);
  EXPECT_TRUE(has(o, "the current sign is inverted")) << o.err;
  EXPECT_TRUE(has(o, "most are wiring_mismatch: the data contradict the conventions: the current sign"))
      << o.err;
}

TEST(ReplayInput, ThetaInDegreesIsNamed)
{
  const std::string p = rewrite(base8(), "deg.csv", [](std::vector<std::string> &f, long) {
    const double d = std::stod(f[7]) * 180 / M_PI;
    f[7] = fmt("%.9g", d - 360 * std::floor(d / 360));
    return true;
  });
  const Out o = replay(p);
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(has(o, "theta wraps around at about 360")) << o.err;
  EXPECT_TRUE(has(o, "most are encoder_fault")) << o.err;
}

// As imest-monitor's --base-id: an identifier above 0x7FF is a 29-bit one.
TEST(ReplayInput, ExtendedCanIdIsAccepted)
{
  const std::string log = tmpdir() + "/ext.log";
  const Out o = replay(base(), "--can-id 0x18FF5000 --candump " + log);
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(slurp(log).find(" 18FF5000#"), std::string::npos) << slurp(log).substr(0, 200);
}

// The first-day mistakes (encoder backwards, phases b and c swapped, the
// electrical angle, n_p 1 for 2, currents in mA, line-to-line voltages, the
// current sign): never a valid window. Either replay refuses the record with
// the cause, or every window is refused (wiring_mismatch for most).
TEST(ReplayInput, WiringMistakesNeverGiveAValidWindow)
{
  const std::string m = " --pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0 ";
  struct Case {
    const char *name;
    std::function<bool(std::vector<std::string> &, long)> edit;
    std::string motor;
  };
  auto scale = [](std::vector<std::string> &f, int j, double k) { f[j] = fmt("%.12g", k * std::stod(f[j])); };
  const std::vector<Case> cases = {
      {"encoder_backwards.csv", [&](std::vector<std::string> &f, long) { return scale(f, 7, -1), true; }, m},
      {"swap_bc.csv",
       [](std::vector<std::string> &f, long) {
         std::swap(f[2], f[3]);
         std::swap(f[5], f[6]);
         return true;
       },
       m},
      {"electrical.csv", [&](std::vector<std::string> &f, long) { return scale(f, 7, 2), true; }, m},
      {"milliamps.csv",
       [&](std::vector<std::string> &f, long) {
         for (int j = 4; j <= 6; ++j) scale(f, j, 1000);
         return true;
       },
       m},
      {"line_to_line.csv",
       [](std::vector<std::string> &f, long) {
         const double a = std::stod(f[1]), b = std::stod(f[2]), c = std::stod(f[3]);
         f[1] = fmt("%.9g", a - b);
         f[2] = fmt("%.9g", b - c);
         f[3] = fmt("%.9g", c - a);
         return true;
       },
       m},
      {"current_sign.csv",
       [&](std::vector<std::string> &f, long) {
         for (int j = 4; j <= 6; ++j) scale(f, j, -1);
         return true;
       },
       m},
      {"pole_pairs_1.csv", [](std::vector<std::string> &, long) { return true; },
       " --pole-pairs 1 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0 "},
  };
  for (const Case &c : cases) {
    SCOPED_TRACE(c.name);
    const std::string p = rewrite(base8(), c.name, c.edit);
    const Out o = run(std::string(REPLAY_BIN) + c.motor + p);
    EXPECT_TRUE(o.code == 0 || o.code == 1) << o.err;
    EXPECT_EQ(valid_windows(o), 0) << o.out;
    EXPECT_EQ(tr_valid_windows(o), 0) << o.out;
    if (o.code == 1) EXPECT_TRUE(has(o, "theta")) << o.err; // refused, naming the angle against the field
  }
}

// L_S 10 % high fits a loaded motor as well as the true one (T_R +11 %,
// R_S -42 %: a consistent family of constants); the nominal R_S (data sheet or
// commissioning) tells them apart.
TEST(ReplayInput, LsTenPercentHighIsConstantsMismatchGivenTheNominalRs)
{
  const Out o =
      run(std::string(REPLAY_BIN) +
          " --pole-pairs 2 --ls 0.3199 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0 --rs 5.04 " +
          base8());
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(tr_valid_windows(o), 0) << o.out;
  EXPECT_TRUE(has(o, "most are constants_mismatch")) << o.err;
}
