/* SPDX-License-Identifier: Apache-2.0 */
// imest-replay --voltage duty: a drive without voltage sensors, fed with the
// duty cycles and the DC bus the simulator's 4 kW drive records with firmware
// timing (row k's duties applied from t_k to t_k+1, v_dc sampled at t_k).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tool_run.hpp"

using namespace tool_run;

namespace {
// The 4 kW preset's motor (sim/README.md, Presets): L_S = L_m + L_ls, sigma = 1 - L_m^2 / L_S^2.
const std::string kMotor4kw =
    " --pole-pairs 2 --ls 0.178039 --sigma 0.0645168 --ls-uncertainty 0 --sigma-uncertainty 0 ";

// 3 s steady at rated load, 50 Hz, 8 kHz, 12-bit sensors, 16384 counts.
const std::string &ideal()
{
  return sim_csv("4kw.csv", "--preset 4kw --duration 3");
}
// The same drive with 2 us of dead time (no device drops).
const std::string &dead_time()
{
  return sim_csv("4kw_dt2.csv", "--preset 4kw --duration 3 --dead-time 2e-6");
}

Out duty(const std::string &file, const std::string &extra = "")
{
  return run(std::string(REPLAY_BIN) + kMotor4kw + "--voltage duty " + extra + " " + file);
}

// Mean of a truth column over the rows of each window (t_end - window, t_end].
std::vector<double> truth_per_window(const std::string &csv, const std::string &name,
                                     const std::vector<double> &t_end, double window_s)
{
  const auto r = rows(slurp(csv));
  const int tc = col(r, "t"), vc = col(r, name);
  std::vector<double> mean;
  for (double te : t_end) {
    double s = 0;
    int n = 0;
    for (size_t k = 1; k < r.size(); ++k) {
      const double t = std::stod(r[k][tc]);
      if (t > te - window_s + 1e-9 && t <= te + 1e-9) {
        s += std::stod(r[k][vc]);
        n++;
      }
    }
    mean.push_back(n ? s / n : NAN);
  }
  return mean;
}

struct Windows {
  std::vector<double> t_end, tr, rs;
  std::vector<int> valid, tr_valid, rs_valid;
  std::vector<double> rs_bound;
};

Windows parse(const Out &o)
{
  const auto r = rows(o.out);
  Windows w;
  const int c_t = col(r, "t_end_s"), c_tr = col(r, "T_R_s"), c_rs = col(r, "R_S_ohm"), c_v = col(r, "valid"),
            c_tv = col(r, "tr_valid"), c_rv = col(r, "rs_valid"), c_rb = col(r, "rs_bound_rel");
  EXPECT_TRUE(c_t >= 0 && c_tr >= 0 && c_rs >= 0 && c_v >= 0 && c_tv >= 0 && c_rv >= 0 && c_rb >= 0)
      << o.out.substr(0, 400);
  for (size_t k = 1; k < r.size(); ++k) {
    w.t_end.push_back(std::stod(r[k][c_t]));
    w.tr.push_back(std::stod(r[k][c_tr]));
    w.rs.push_back(std::stod(r[k][c_rs]));
    w.valid.push_back(std::stoi(r[k][c_v]));
    w.tr_valid.push_back(std::stoi(r[k][c_tv]));
    w.rs_valid.push_back(std::stoi(r[k][c_rv]));
    w.rs_bound.push_back(std::stod(r[k][c_rb]));
  }
  return w;
}

// R_S error per window against the simulator's truth [relative].
std::vector<double> rs_error(const std::string &csv, const Windows &w)
{
  const std::vector<double> rs = truth_per_window(csv, "R_S_true_ohm", w.t_end, 1.0);
  std::vector<double> e;
  for (size_t k = 0; k < w.rs.size(); ++k) e.push_back(w.rs[k] / rs[k] - 1.0);
  return e;
}
} // namespace

// An ideal inverter: the duty-cycle voltage is the applied one, and T_R comes
// out within 1 % in every window whose T_R is valid (the first is warm-up).
TEST(ReplayDuty, IdealInverterGivesValidTrWithinOnePercent)
{
  const Out o = duty(ideal());
  ASSERT_EQ(o.code, 0) << o.err;
  const Windows w = parse(o);
  ASSERT_EQ(w.tr.size(), 3u) << o.out;
  const std::vector<double> tr = truth_per_window(ideal(), "T_R_true_s", w.t_end, 1.0);
  int n = 0;
  for (size_t k = 0; k < w.tr.size(); ++k) {
    if (!w.tr_valid[k]) continue;
    EXPECT_NEAR(w.tr[k], tr[k], 0.01 * tr[k]) << "window " << k;
    n++;
  }
  EXPECT_EQ(n, 2) << o.out;
}

// The duty columns are named when missing, and a file with the other input's
// columns says which --voltage reads it.
TEST(ReplayDuty, MissingDutyColumnIsNamed)
{
  const std::string p = write("no_vdc.csv", "t,d_a,d_b,d_c,i_a,i_b,i_c,theta\n0,0.5,0.5,0.5,0,0,0,0\n");
  Out o = duty(p);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find(":1: missing column 'v_dc' (the header needs t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta"),
            std::string::npos)
      << o.err;
  const std::string q = write("phase_only.csv", "t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n0,1,2,3,4,5,6,0\n");
  o = duty(q);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("missing column 'd_a'"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("it has the columns of --voltage phase"), std::string::npos) << o.err;
  const std::string d =
      write("duty_only.csv", "t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta\n0,0.5,0.5,0.5,560,0,0,0,0\n");
  o = replay(d);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("missing column 'u_a'"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("it has the columns of --voltage duty"), std::string::npos) << o.err;
}

// Duties on another scale would pass as a wrong voltage: refused with the conversion.
TEST(ReplayDuty, DutiesOutsideZeroToOneAreRefused)
{
  const auto scaled = [](const std::string &name, double gain, double offset) {
    return rewrite(ideal(), name, [=](std::vector<std::string> &f, long) {
      for (int j = 27; j <= 29; ++j) f[j] = fmt("%.9g", gain * std::stod(f[j]) + offset); // d_a,d_b,d_c
      return true;
    });
  };
  ASSERT_EQ(rows(slurp(ideal()))[0][27], "d_a");
  Out o = duty(scaled("percent.csv", 100.0, 0.0));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("In percent? Divide by 100."), std::string::npos) << o.err;
  o = duty(scaled("signed.csv", 2.0, -1.0));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("d = (m + 1) / 2"), std::string::npos) << o.err;
}

// The inverter flags reach the config: with 2 us of dead time in the drive,
// the model given gives R_S within 5 %, none gives R_S far off (+66 % measured),
// a dead time 50 % short lies between; T_R stays within 1 % in all three.
TEST(ReplayDuty, DeadTimeFlagMovesRs)
{
  const Out none = duty(dead_time()), right = duty(dead_time(), "--dead-time 2e-6"),
            half = duty(dead_time(), "--dead-time=1e-6");
  ASSERT_EQ(none.code, 0) << none.err;
  ASSERT_EQ(right.code, 0) << right.err;
  ASSERT_EQ(half.code, 0) << half.err;
  const Windows wn = parse(none), wr = parse(right), wh = parse(half);
  const std::vector<double> en = rs_error(dead_time(), wn), er = rs_error(dead_time(), wr),
                            eh = rs_error(dead_time(), wh);
  const std::vector<double> tr = truth_per_window(dead_time(), "T_R_true_s", wr.t_end, 1.0);
  for (size_t k = 1; k < wr.rs.size(); ++k) { // after the warm-up
    EXPECT_GT(en[k], 0.3) << "window " << k;
    EXPECT_LT(std::fabs(er[k]), 0.05) << "window " << k;
    EXPECT_GT(eh[k], er[k] + 0.1) << "window " << k;
    EXPECT_LT(eh[k], en[k] - 0.1) << "window " << k;
    for (const Windows *w : {&wn, &wr, &wh}) EXPECT_NEAR(w->tr[k], tr[k], 0.01 * tr[k]) << "window " << k;
  }
}

// The carrier and timing flags reach the config too: the dead-time error is
// t_d f_pwm V_dc, so 1 us at twice the carrier is close to 2 us at the sample
// rate (the zero-crossing band differs), and a wrong timing scheme moves R_S.
TEST(ReplayDuty, CarrierAndTimingFlagsReachTheConfig)
{
  const Windows a = parse(duty(dead_time(), "--dead-time 2e-6"));
  const Windows b = parse(duty(dead_time(), "--dead-time 1e-6 --pwm-hz 16000"));
  const Windows c = parse(duty(dead_time(), "--dead-time 2e-6 --pwm-timing centred"));
  ASSERT_EQ(a.rs.size(), 3u);
  ASSERT_EQ(b.rs.size(), 3u);
  ASSERT_EQ(c.rs.size(), 3u);
  for (size_t k = 1; k < a.rs.size(); ++k) {
    EXPECT_NEAR(b.rs[k], a.rs[k], 0.01 * a.rs[k]) << "window " << k;
    EXPECT_LT(c.rs[k], 0.8 * a.rs[k]) << "window " << k;
  }
}

// Without an inverter model the voltage error is unknown, so R_S must not be
// valid (include/imest/imest.h, imest_inverter_t.uncertainty). The library
// computes R_S's error bound (rs_bound_rel) once its R_S verdict exists; until
// then every bound is NaN and this test says so and skips.
TEST(ReplayDuty, NoInverterModelNeverGivesValidRs)
{
  const Out none = duty(ideal()), model = duty(ideal(), "--dead-time 0");
  ASSERT_EQ(none.code, 0) << none.err;
  ASSERT_EQ(model.code, 0) << model.err;
  const Windows wn = parse(none), wm = parse(model);
  bool verdict = false;
  for (const Windows *w : {&wn, &wm})
    for (double b : w->rs_bound) verdict |= !std::isnan(b);
  if (!verdict) GTEST_SKIP() << "the library computes no R_S error bound yet (rs_bound_rel is nan)";
  for (size_t k = 0; k < wn.rs_valid.size(); ++k) {
    EXPECT_EQ(wn.rs_valid[k], 0) << "window " << k;
    EXPECT_EQ(wn.valid[k], 0) << "window " << k;
  }
  int tr_valid = 0;
  for (int v : wn.tr_valid) tr_valid += v;
  EXPECT_EQ(tr_valid, 2) << none.out; // T_R keeps its verdict
}

// The phase-voltage input is the default and is left as it was: the same
// output with and without --voltage phase, and the duty-cycle input's flags
// refused with it.
TEST(ReplayDuty, PhaseInputIsTheDefaultAndUnchanged)
{
  const std::string &p = sim_csv("exp2_short.csv", "--preset exp2 --duration 3.2 --supply vf");
  const Out a = replay(p), b = replay(p, "--voltage phase"), c = replay(p, "--voltage=phase");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(a.err, b.err);
  EXPECT_EQ(a.out, c.out);
  for (const char *opt :
       {"--dead-time 1e-6", "--v-switch 1", "--r-switch 0.01", "--v-diode 0.8", "--r-diode 0.01",
        "--i-band 1", "--pwm-timing last", "--inverter-uncertainty 0.1"}) {
    const Out o = replay(p, opt);
    EXPECT_EQ(o.code, 2) << opt;
    EXPECT_NE(o.err.find("give --voltage duty"), std::string::npos) << opt << ": " << o.err;
  }
  const Out u = duty(ideal(), "--u-limit 400");
  EXPECT_EQ(u.code, 2);
  EXPECT_NE(u.err.find("--u-limit applies to measured phase voltages"), std::string::npos) << u.err;
  EXPECT_EQ(replay(p, "--voltage dc").code, 2);
  EXPECT_EQ(duty(ideal(), "--pwm-timing middle").code, 2);
}

// The conventions are checked in duty mode too: theta against the field is
// refused, an inverted current sign is a note (power from the duty voltage).
TEST(ReplayDuty, ConventionChecksWorkWithDuties)
{
  const std::string neg_i = rewrite(ideal(), "4kw_neg_i.csv", [](std::vector<std::string> &f, long) {
    for (int j = 4; j <= 6; ++j) f[j] = fmt("%.9g", -std::stod(f[j]));
    return true;
  });
  Out o = duty(neg_i);
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.err.find("the current sign is inverted"), std::string::npos) << o.err;
  const std::string neg_th = rewrite(ideal(), "4kw_neg_th.csv", [](std::vector<std::string> &f, long) {
    f[7] = fmt("%.12g", -std::stod(f[7]));
    return true;
  });
  o = duty(neg_th);
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("theta must increase with the a-b-c field"), std::string::npos) << o.err;
}

// A drive started from rest is recognised as such in duty mode (no warm-up),
// though a 16384-count encoder steps by one count at the first sample.
TEST(ReplayDuty, StartFromRestIsRecognised)
{
  const std::string &p = sim_csv("4kw_rest.csv", "--preset 4kw --start rest --duration 2");
  const Out o = duty(p);
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.err.find("started at rest"), std::string::npos) << o.err;
}

// The inverter model 10 % or 20 % off must never give a valid estimate that is wrong (T_R more
// than 2 % off, R_S more than 5 %), with either model. The point is the dead-time table's hardest
// (docs/METHOD.md §17.1, §18.1): the 2.2 kW motor with drops only (1 V + 0.5 V at the rated peak
// current), 10 Hz, 25 % load, where the switching-instant model (--edge-band, the band the
// dead-time study fits: a tenth of the ripple's peak V_dc / (8 sigma L_S f_pwm)) with its numbers
// 20 % high gave T_R valid and 5 % off, R_S 5 %, before the harmonics' share of the bounds was
// derived from the fit; a wrong verdict fails this.
TEST(ReplayDuty, ModelTwentyPercentOffIsNeverValidAndWrong)
{
  const std::string drive =
      " --dead-time 0 --v-switch 1 --r-switch 0.0727117 --v-diode 1 --r-diode 0.0727117";
  const std::string &csv = sim_csv(
      "2k2_drops_10hz.csv", "--preset 4kw --pole-pairs 2 --ls 0.245 --lr 0.224 --sigma 0.085714 --rs 3.7 "
                            "--tr 0.106667 --j 0.015 --b 9.7e-4 --i-range 18 --no-thermal --start steady "
                            "--vdc 560 --freq 10 --vll 81.5191 --load-nm 3.65 --duration 5 --seed 5001 "
                            "--encoder-counts 16384 --no-progress" +
                                drive);
  const std::string est = std::string(REPLAY_BIN) + " --pole-pairs 2 --ls 0.245 --sigma 0.085714 "
                                                    "--ls-uncertainty 0 --sigma-uncertainty 0 --from-rest no "
                                                    "--quiet --voltage duty --dead-time 0 --v-switch %V "
                                                    "--r-switch %R --v-diode %V --r-diode %R ";
  const std::string edges = " --edge-band " + std::to_string(0.1 * 560.0 / (8.0 * 0.085714 * 0.245 * 8000.0));
  for (const std::string &model : {std::string(), edges})
    for (double scale : {0.8, 0.9, 1.1, 1.2}) {
      std::string cmd = est + model + " ";
      for (const auto &[key, v] :
           {std::pair<std::string, double>{"%V", 1.0 * scale}, {"%R", 0.0727117 * scale}})
        for (size_t at; (at = cmd.find(key)) != std::string::npos;) cmd.replace(at, 2, std::to_string(v));
      const Out o = run(cmd + csv);
      ASSERT_EQ(o.code, 0) << o.err;
      const Windows w = parse(o);
      ASSERT_GE(w.tr.size(), 4u) << o.out;
      const std::vector<double> tr = truth_per_window(csv, "T_R_true_s", w.t_end, 1.0);
      const std::vector<double> ers = rs_error(csv, w);
      for (size_t k = 0; k < w.tr.size(); ++k) {
        if (w.tr_valid[k])
          EXPECT_LT(std::fabs(w.tr[k] / tr[k] - 1.0), 0.02) << model << " scale " << scale << " window " << k;
        if (w.rs_valid[k])
          EXPECT_LT(std::fabs(ers[k]), 0.05) << model << " scale " << scale << " window " << k;
      }
    }
}

// A deep-bar rotor (the 4 kW real motor: saturation, iron loss, a double cage) on an inverter with
// 2 us of dead time, its phase voltages measured through an 800 Hz anti-alias filter, 50 % speed,
// rated load: the envelope's real_all_vmeas point where T_R was published valid and 2.4 % off
// (bound 1.4 %). With the rotor described as commissioning measured it (--rotor-hf-rr,
// --rotor-hf-sigma, imest_comm_apply()) and the commissioned inverter with its bus, the harmonics'
// move through the fit is in the bounds (docs/METHOD.md §18.1): no window valid and wrong. Without
// the inverter the bound is infinite; without the rotor's description the old failure stands.
TEST(ReplayDuty, DeepBarRotorMeasuredVoltagesNeverValidAndWrong)
{
  const std::string &csv = sim_csv(
      "4kw_real_vmeas_f25.csv",
      "--preset 4kw --real-motor --no-thermal --start steady --vdc 560 --freq 25 --vll 216.351 "
      "--load-nm 26.5 --duration 5 --seed 5044 --encoder-counts 16384 --no-progress --dead-time 2e-06 "
      "--v-switch 1 --r-switch 0.02 --v-diode 0.8 --r-diode 0.01 --vmeas aa --aa-hz 800");
  // imest-commission --preset 4kw --real-motor (the drive's inverter) --apply-args
  const std::string est =
      std::string(REPLAY_BIN) +
      " --from-rest no --quiet --aa-hz 800 --pole-pairs 2 --ls 0.167565927 --sigma 0.068522729 "
      "--sigma-uncertainty 0.0138292052 --ls-uncertainty 0.00315177627 --rs 1.38299799 --tr-nominal "
      "0.0956817642 "
      "--ls-curve 2.3309145:0.235574916,3.46625662:0.2294994,5.19619131:0.205098614,7.58910799:0.167565927 ";
  const std::string rotor = " --rotor-hf-rr 5.65854836 --rotor-hf-sigma 0.557284176 ";
  const std::string inverter =
      " --dead-time 2.03393506e-06 --v-switch 0.867962182 --r-switch 0.0202209409 "
      "--v-diode 0.867962182 --r-diode 0 --i-band 0 --inverter-uncertainty 0.0785724744 "
      "--inverter-vdc 559.993347 ";
  struct Case {
    std::string args;
    int wrong_min, valid_max; // at least this many valid-and-wrong windows, at most this many valid
  };
  const Case cases[] = {{"", 1, 99}, {rotor + inverter, 0, 99}, {rotor, 0, 0}};
  for (const Case &c : cases) {
    SCOPED_TRACE(c.args);
    const Out o = run(est + c.args + csv);
    ASSERT_EQ(o.code, 0) << o.err;
    const Windows w = parse(o);
    ASSERT_GE(w.tr.size(), 4u) << o.out;
    const std::vector<double> tr = truth_per_window(csv, "T_R_ifoc_s", w.t_end, 1.0);
    int wrong = 0, valid = 0;
    for (size_t k = 0; k < w.tr.size(); ++k) {
      valid += w.tr_valid[k];
      if (w.tr_valid[k] && std::fabs(w.tr[k] / tr[k] - 1.0) > 0.02) wrong++;
    }
    if (c.wrong_min > 0)
      EXPECT_GE(wrong, c.wrong_min) << "the point no longer shows the failure it guards";
    else
      EXPECT_EQ(wrong, 0);
    EXPECT_LE(valid, c.valid_max);
  }
}

// The 11 kW motor on V/f at 30 Hz, 25 % load, 2 us dead time hunts: its speed swings 5 % at
// about 12 Hz, inside the angle observer's band (25 Hz), where the type-3 tracker's angle lags by
// 8 % of the swing and its speed by half of it. The observer engaged (from the third window),
// that lag read as R_S +65 %; with the encoder's counts the tracker's correction beyond one count
// shows the lag and the encoder is used instead (isr_angle.h): R_S +2.5 %, as with the observer
// off; the swing at a steady mean is not the steady state the bounds assume: `transient`. The
// 1024-count paper motor keeps the observer (R_S +0.2 %, off +7 %).
TEST(ReplayDuty, ObserverLeavesAHuntingRotorToTheEncoder)
{
  const std::string &csv = sim_csv(
      "11kw_hunting.csv", "--preset 11kw --no-thermal --start steady --vdc 560 --freq 30 --vll 237.419 "
                          "--load-nm 18 --duration 4 --seed 5092 --encoder-counts 16384 --no-progress "
                          "--dead-time 2e-06 --v-switch 1 --r-switch 0.0172926 --v-diode 1 "
                          "--r-diode 0.0172926");
  const std::string est = std::string(REPLAY_BIN) + " --pole-pairs 2 --ls 0.078331 --sigma 0.05515971 "
                                                    "--ls-uncertainty 0 --sigma-uncertainty 0 --from-rest no "
                                                    "--quiet --voltage duty --dead-time 2e-06 --v-switch 1 "
                                                    "--r-switch 0.0172926 --v-diode 1 --r-diode 0.0172926 "
                                                    "--encoder-counts 16384 ";
  const Out o = run(est + csv);
  ASSERT_EQ(o.code, 0) << o.err;
  const Windows w = parse(o);
  ASSERT_GE(w.rs.size(), 4u) << o.out;
  const std::vector<double> ers = rs_error(csv, w);
  for (size_t k = 2; k < w.rs.size(); ++k) {
    EXPECT_LT(std::fabs(ers[k]), 0.1) << "window " << k;
    EXPECT_FALSE(w.tr_valid[k] || w.rs_valid[k]) << "window " << k;
  }
}

// A swing at a steady mean is judged by the steady-state bounds at the least slip it visits, the
// mean slip less sqrt(2) x the speed's rms spread (bg_validity.c, bounds()). The 4 kW motor on V/f
// with 2 us dead time hunts at 30 Hz, 25 % load: the spread (12 rad/s electrical) exceeds the slip,
// and without the check windows 2 and 3 were T_R valid +1.35 % off; they are `transient`. At 50 Hz,
// 50 % load its swing is 0.1 rad/s against a slip of 7 rad/s: the windows the tracker flags keep
// their verdict (T_R valid, +0.6 %), where the blanket rule refused them.
TEST(ReplayDuty, ASwingIsJudgedAtTheLeastSlipItVisits)
{
  const std::string inv =
      " --dead-time 2e-06 --v-switch 1 --r-switch 0.0443738 --v-diode 1 --r-diode 0.0443738 ";
  const std::string &hunting = sim_csv(
      "4kw_hunting.csv", "--preset 4kw --no-thermal --start steady --vdc 560 --freq 30 --vll 234.477 "
                         "--load-nm 6.625 --duration 4 --seed 5056 --encoder-counts 16384 --no-progress" +
                             inv);
  const std::string &small = sim_csv(
      "4kw_small_swing.csv", "--preset 4kw --no-thermal --start steady --vdc 569.9 --freq 50 --vll 390.865 "
                             "--load-nm 13.25 --duration 4 --seed 5060 --encoder-counts 16384 --no-progress" +
                                 inv);
  const std::string est = "--from-rest no --quiet --encoder-counts 16384" + inv;
  const Out oh = duty(hunting, est), os = duty(small, est);
  ASSERT_EQ(oh.code, 0) << oh.err;
  ASSERT_EQ(os.code, 0) << os.err;
  const Windows wh = parse(oh), ws = parse(os);
  ASSERT_EQ(wh.tr.size(), 4u) << oh.out;
  ASSERT_EQ(ws.tr.size(), 4u) << os.out;
  const std::vector<double> tr = truth_per_window(small, "T_R_true_s", ws.t_end, 1.0);
  for (size_t k = 2; k < 4u; ++k) { // flagged from the third window (the engagement's test needs two means)
    EXPECT_FALSE(wh.tr_valid[k] || wh.rs_valid[k]) << "window " << k << "\n" << oh.out;
    EXPECT_TRUE(ws.tr_valid[k]) << "window " << k << "\n" << os.out;
    EXPECT_NEAR(ws.tr[k], tr[k], 0.01 * tr[k]) << "window " << k;
  }
}

TEST(ReplayDuty, ObserverKeepsACoarseEncodersQuantisationOut)
{
  const std::string &csv =
      sim_csv("exp2_1024.csv", "--preset exp2 --duration 4 --encoder-counts 1024 --start "
                               "steady --no-thermal --no-progress --seed 7");
  const std::string est = std::string(REPLAY_BIN) +
                          " --pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 "
                          "--sigma-uncertainty 0 --from-rest no --quiet ";
  const Out on = run(est + "--encoder-counts 1024 " + csv), off = run(est + "--angle-observer-hz -1 " + csv);
  ASSERT_EQ(on.code, 0) << on.err;
  ASSERT_EQ(off.code, 0) << off.err;
  const Windows w_on = parse(on), w_off = parse(off);
  ASSERT_GE(w_on.rs.size(), 4u) << on.out;
  const std::vector<double> e_on = rs_error(csv, w_on), e_off = rs_error(csv, w_off);
  for (size_t k = 2; k < w_on.rs.size(); ++k) { // engaged from the third window
    EXPECT_LT(std::fabs(e_on[k]), 0.01) << "window " << k;
    EXPECT_GT(std::fabs(e_off[k]), 0.03) << "window " << k; // what the observer is there for
  }
}
