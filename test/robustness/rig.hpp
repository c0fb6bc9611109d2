/* SPDX-License-Identifier: Apache-2.0 */
// Test rig for the robustness tests: the simulator (imsim) in a loaded steady
// state feeding imest through its public API, with a hook that lets a test
// corrupt any sample on its way into the ISR call.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

extern "C" {
#include "imest/imest.h"
#include "imsim/imsim.h"
}

namespace rob {

// What reaches imest_isr_abc for one sample; a hook may change any field.
struct Sample {
  long n;     // sample index since the rig started
  int window; // index of the window this sample belongs to
  int pos;    // position in that window (0 .. window_n-1)
  float u[3], i[3];
  float theta;                 // wrapped to [0, 2 pi)
  bool call_background = true; // false: the background is "starved" after this sample
};
using Hook = std::function<void(Sample &)>;

// Every result must satisfy this, whatever the input: valid implies finite
// numbers inside the configured bands.
inline void expect_sane(const imest_result_t &r, const imest_config_t &cfg, const std::string &what)
{
  // a reported T_R (valid or not) is always a candidate from inside the band
  if (std::isfinite(r.tr_s)) {
    EXPECT_GE(r.tr_s, (double)cfg.tr_min_s) << what;
    EXPECT_LE(r.tr_s, (double)cfg.tr_max_s) << what;
  }
  if (!r.valid) {
    EXPECT_NE(r.status, IMEST_OK) << what;
    return;
  }
  EXPECT_EQ(r.status, IMEST_OK) << what;
  EXPECT_TRUE(std::isfinite(r.tr_s)) << what;
  EXPECT_TRUE(std::isfinite(r.rs_ohm)) << what;
  EXPECT_TRUE(std::isfinite(r.e_i)) << what;
  EXPECT_TRUE(std::isfinite(r.k1) && std::isfinite(r.k2)) << what;
  EXPECT_GE(r.tr_s, (double)cfg.tr_min_s) << what;
  EXPECT_LE(r.tr_s, (double)cfg.tr_max_s) << what;
  EXPECT_GE(r.rs_ohm, (double)cfg.rs_min_ohm) << what;
  EXPECT_LE(r.rs_ohm, (double)cfg.rs_max_ohm) << what;
  EXPECT_LE(r.pe_k2_rel, (double)cfg.max_pe_k2_rel) << what;
  EXPECT_LE(r.e_i, (double)cfg.max_ei) << what;
}

struct Rig {
  imsim_config_t sc{};
  imsim_t sim{};
  imsim_sample_t smp{};
  imest_config_t cfg{};
  imest_t est{};
  std::vector<imest_result_t> res; // in the order the background produced them
  long n = 0;
  unsigned int window_n = 0;

  // exp2 operating point (30 Hz V/f, 115 V, rated load 2.064 N m), started in
  // steady state, 12-bit sensors with 1 LSB noise, 4096-count encoder, no
  // heating (T_R and R_S constant: 0.12 s, 5.04 ohm). Default estimator
  // config: the first start waits 0.83 s (filters and offset tracker), so
  // windows 0 and 1 of 0.5 s are warm-up; after a fault only the filters
  // wait (31 ms).
  explicit Rig(float window_s = 0.5f, double load_nm = 2.064)
  {
    imsim_config_preset(&sc, "exp2");
    sc.start = IMSIM_START_STEADY;
    sc.thermal = false;
    sc.load_nm = load_nm;
    sc.supply = IMSIM_SUPPLY_VF;
    imest_config_default(&cfg);
    cfg.pole_pairs = (unsigned)sc.pole_pairs;
    cfg.ls_h = (float)sc.ls_h;
    cfg.sigma = (float)sc.sigma;
    cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
    cfg.sigma_uncertainty = 0.0f;
    cfg.fs_hz = (float)sc.fs_hz;
    cfg.window_s = window_s;
  }
  // call after changing sc / cfg
  void start()
  {
    ASSERT_EQ(imsim_init(&sim, &sc, &smp), 0) << imsim_error(&sim);
    const char *field = nullptr;
    ASSERT_EQ(imest_config_check(&cfg, &field), IMEST_OK) << (field ? field : "");
    ASSERT_EQ(imest_init(&est, &cfg), IMEST_OK);
    window_n = (unsigned)std::lround((double)cfg.window_s * (double)cfg.fs_hz);
  }
  // Runs `windows` more windows; every sample passes through hook (if any).
  void run(int windows, const Hook &hook = nullptr, const std::function<void(long)> &plant = nullptr)
  {
    const long end = n + (long)windows * (long)window_n;
    for (; n < end; ++n) {
      if (plant) plant(n);
      Sample s;
      s.n = n;
      s.window = (int)(n / (long)window_n);
      s.pos = (int)(n % (long)window_n);
      for (int k = 0; k < 3; ++k) {
        s.u[k] = (float)smp.u_abc[k];
        s.i[k] = (float)smp.i_abc[k];
      }
      s.theta = (float)std::fmod(smp.theta, 2.0 * M_PI);
      if (hook) hook(s);
      // The background runs whenever it is allowed to (a woken task that was
      // starved catches up as soon as it gets the CPU).
      (void)imest_isr_abc(&est, s.u, s.i, s.theta);
      if (s.call_background) drain();
      imsim_step(&sim, &smp);
    }
  }
  void drain()
  {
    imest_result_t r;
    while (imest_background(&est, &r) == 1) {
      expect_sane(r, cfg, "seq " + std::to_string(r.seq));
      res.push_back(r);
    }
  }
  // result of window `seq` (nullptr if it was dropped)
  const imest_result_t *window(uint32_t seq) const
  {
    for (const auto &r : res)
      if (r.seq == seq) return &r;
    return nullptr;
  }
  std::string dump() const
  {
    std::string o;
    char b[200];
    for (const auto &r : res) {
      std::snprintf(
          b, sizeof b,
          "  seq %2u %-18s valid %d tr %.5f rs %.4f used %u flags 0x%03x pe %.3g slip %.3g ei %.3g\n", r.seq,
          imest_reason_name(r.status), r.valid, r.tr_s, r.rs_ohm, r.used_samples, r.flags, r.pe_k2_rel,
          r.slip_ratio, r.e_i);
      o += b;
    }
    return o;
  }
};

} // namespace rob
