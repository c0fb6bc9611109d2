/* SPDX-License-Identifier: Apache-2.0 */
// imest-replay as a user runs it: bad input, column order, float32 vs float64.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "tool_run.hpp"

using namespace tool_run;

TEST(Replay, MissingColumnIsNamed)
{
  const Out o = replay(write("m.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c\n0,1,2,3,4,5,6\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":1: missing column 'theta'"), std::string::npos) << o.err;
}

TEST(Replay, NonNumericFieldNamesTheLine)
{
  const Out o = replay(write("n.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n0,1,2,3,4,5,6,0\n"
                                      "0.00025,1,2,x3,4,5,6,0\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":3: column 'u_c': 'x3' is not a number"), std::string::npos) << o.err;
}

TEST(Replay, NanIsRejectedWithItsLine)
{
  const Out o = replay(write("nan.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n0,1,2,3,4,5,6,0\n"
                                        "0.00025,1,2,3,nan,5,6,0\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":3: column 'i_a': non-finite value"), std::string::npos) << o.err;
}

TEST(Replay, NonMonotonicTimeNamesTheLine)
{
  const Out o = replay(write("t.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n0,1,2,3,4,5,6,0\n"
                                      "0.00025,1,2,3,4,5,6,0\n0.0002,1,2,3,4,5,6,0\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":4: t = 0.0002 does not increase"), std::string::npos) << o.err;
}

TEST(Replay, EmptyFileAndHeaderOnly)
{
  Out o = replay(write("e.csv", ""));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("empty file"), std::string::npos) << o.err;
  o = replay(write("h.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("no data rows"), std::string::npos) << o.err;
}

TEST(Replay, WrongFieldCountNamesTheLine)
{
  const Out o = replay(write("f.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n0,1,2,3,4,5,6,0\n0.00025,1,2\n"
                                      "0.0005,1,2,3,4,5,6,0\n"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":3:"), std::string::npos) << o.err;
}

TEST(Replay, MissingMotorConstantsAreAnError)
{
  const Out o = run(std::string(REPLAY_BIN) + " --pole-pairs 2 x.csv");
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--ls"), std::string::npos);
}

TEST(Replay, IrregularSamplingIsAnError)
{
  std::string csv = "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n";
  double t = 0;
  for (int k = 0; k < 100; ++k) {
    t += (k == 50) ? 0.001 : 0.00025;
    csv += std::to_string(t) + ",1,2,3,4,5,6,0\n";
  }
  const Out o = replay(write("irr.csv", csv));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("irregular sampling"), std::string::npos) << o.err;
}

// Column order and extra columns do not matter; the header is the documented one.
TEST(Replay, ColumnsInAnyOrderGiveIdenticalOutput)
{
  const std::string &p = sim_csv("exp2_short.csv", "--preset exp2 --duration 3.2 --supply vf");
  const Out a = replay(p);
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(a.out.substr(0, a.out.find('\n')),
            "t_end_s,T_R_s,R_S_ohm,E_I,valid,status,seq,K1,K2,pe_k1_rel,pe_k2_rel,H11,H12,H22,"
            "hessian_pd,n_roots,n_admissible,slip_ratio,i_rms_a,used_samples,flags,"
            "tr_valid,rs_valid,tr_reason,rs_reason,span_s,windows,tr_bound_rel,rs_bound_rel");
  // reverse the column order with awk
  const std::string q = tmpdir() + "/reversed.csv";
  ASSERT_EQ(std::system(("awk -F, 'BEGIN{OFS=\",\"} {s=$NF; for(i=NF-1;i>=1;i--) s=s \",\" $i; print s}' " +
                         p + " > " + q)
                            .c_str()),
            0);
  const Out b = replay(q);
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(rows(a.out).size(), 4u); // header + 3 windows
}

// The float32 path (the firmware's) against the same code with a float64 ISR,
// on 12-bit / 4096-count data from the simulator: T_R within 0.01 %.
TEST(Replay, Float32PathWithinOneBasisPointOfFloat64)
{
  const std::string &p = sim_csv("exp2_12bit.csv", "--preset exp2 --duration 8 --supply vf --seed 5");
  const Out a = replay(p), b = run(std::string(REPLAY64_BIN) + kMotor + p);
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const auto ra = rows(a.out), rb = rows(b.out);
  ASSERT_EQ(ra.size(), rb.size());
  int compared = 0;
  for (size_t k = 1; k < ra.size(); ++k) {
    if (ra[k][4] != "1") continue;
    const double t32 = std::stod(ra[k][1]), t64 = std::stod(rb[k][1]);
    EXPECT_NEAR(t32, t64, 1e-4 * t64) << "window " << k; // 0.01 %
    ++compared;
  }
  EXPECT_GE(compared, 4);
}

// A record shorter than a window is estimated as one shorter window; a last
// partial window of at least half the length is estimated too.
TEST(Replay, ShortRecordsAndPartialLastWindows)
{
  const std::string &p = sim_csv("exp1_short.csv", "--preset exp1 --duration 0.3");
  Out a = replay(p);
  ASSERT_EQ(a.code, 0) << a.err;
  auto r = rows(a.out);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1][4], "1") << a.out; // the run-up is valid
  EXPECT_NEAR(std::stod(r[1][1]), 0.12, 0.12 * 0.02);
  EXPECT_EQ(r[1][19], "1201");
  const std::string &q = sim_csv("exp1_1p6.csv", "--preset exp1 --duration 1.6");
  a = replay(q);
  ASSERT_EQ(a.code, 0) << a.err;
  r = rows(a.out);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[2][19], "2401");
  EXPECT_NEAR(std::stod(r[2][0]), 1.6, 1e-6);
}

TEST(Replay, CandumpLogHasOneLineGroupPerWindow)
{
  const std::string &p = sim_csv("exp2_short.csv", "--preset exp2 --duration 3.2 --supply vf");
  const std::string log = tmpdir() + "/frames.log";
  const Out a = replay(p, "--candump " + log);
  ASSERT_EQ(a.code, 0) << a.err;
  const std::string text = slurp(log);
  EXPECT_NE(text.find(") vcan0 "), std::string::npos) << text;
  EXPECT_GE(std::count(text.begin(), text.end(), '\n'), 3);
}
