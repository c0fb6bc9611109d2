/* SPDX-License-Identifier: Apache-2.0 */
// Fuzz the whole public path: imest_isr_abc / imest_isr_ab with arbitrary
// floats for a few windows, imest_background after every sample. Most samples
// are a clean rotating field (so that windows reach the solve); a selector
// byte per sample lets the fuzzer replace any of them by 7 arbitrary floats
// (u_a, u_b, u_c, i_a, i_b, i_c, theta). Property: no crash / sanitizer
// error; every result is either invalid with a non-OK status, or valid with
// finite T_R in [tr_min_s, tr_max_s], finite R_S in its band and finite E_I;
// any finite T_R reported lies inside the band; sample counts are consistent.
#include <cmath>

#include "fuzz_util.hpp"

extern "C" {
#include "imest/imest.h"
}

namespace {
void check(const imest_result_t &r, const imest_config_t &c, uint32_t window_n)
{
  if (r.samples != window_n) fuzz::fail("window with a wrong sample count");
  if (r.used_samples > r.samples) fuzz::fail("used_samples > samples");
  if (std::isfinite(r.tr_s) && !(r.tr_s >= c.tr_min_s && r.tr_s <= c.tr_max_s))
    fuzz::fail("T_R outside the band");
  if (!r.valid) {
    if (r.status == IMEST_OK) fuzz::fail("invalid with status OK");
    return;
  }
  if (r.status != IMEST_OK) fuzz::fail("valid with a non-OK status");
  if (!(std::isfinite(r.tr_s) && std::isfinite(r.rs_ohm) && std::isfinite(r.e_i) && std::isfinite(r.k1) &&
        std::isfinite(r.k2)))
    fuzz::fail("valid with a non-finite number");
  if (!(r.rs_ohm >= c.rs_min_ohm && r.rs_ohm <= c.rs_max_ohm)) fuzz::fail("valid with R_S outside the band");
  if (!(r.e_i <= c.max_ei && r.pe_k2_rel <= c.max_pe_k2_rel)) fuzz::fail("valid beyond the quality limits");
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  fuzz::Reader in{data, size};
  const uint8_t mode = in.byte();
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 1u + (mode & 3u);
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = 4000.0f;
  cfg.window_s = 0.05f; // 200 samples
  cfg.start_at_rest = (mode >> 2) & 1;
  if (mode & 8) cfg.i_limit_a = 20.0f;
  if (mode & 16) cfg.u_limit_v = 400.0f;
  if (mode & 32) cfg.aa_hz = 800.0f;
  const bool use_ab = (mode & 64) != 0;
  static imest_t s;
  if (imest_init(&s, &cfg) != IMEST_OK) fuzz::fail("default config rejected");
  const uint32_t window_n = 200;
  imest_result_t r;
  uint32_t last_seq = 0;
  bool any = false;
  for (int k = 0; k < 6 * (int)window_n; ++k) {
    // clean sample: 30 Hz field, 25 Hz mechanical speed (slip), 100 V / 3 A
    const float ph = 2.0f * 3.14159265f * 30.0f * (float)k / 4000.0f;
    float u[3] = {100 * std::cos(ph), 100 * std::cos(ph - 2.0944f), 100 * std::cos(ph + 2.0944f)};
    float i[3] = {3 * std::cos(ph - 0.6f), 3 * std::cos(ph - 2.6944f), 3 * std::cos(ph + 1.4944f)};
    float th = std::fmod(2.0f * 3.14159265f * 25.0f / (float)cfg.pole_pairs * (float)k / 4000.0f, 6.2831853f);
    const uint8_t sel = in.byte(0);
    if (sel >= 0xC0) {
      for (float &x : u) x = in.get<float>(x);
      for (float &x : i) x = in.get<float>(x);
      th = in.get<float>(th);
    }
    if (use_ab) {
      (void)imest_isr_ab(&s, u[0], u[1], i[0], i[1], th);
    } else {
      (void)imest_isr_abc(&s, u, i, th);
    }
    int rc;
    while ((rc = imest_background(&s, &r)) == 1) {
      check(r, cfg, window_n);
      if (any && r.seq <= last_seq) fuzz::fail("sequence not increasing");
      last_seq = r.seq;
      any = true;
    }
    if (rc != 0) fuzz::fail("imest_background returned neither 0 nor 1");
  }
  if (!any) fuzz::fail("no window in 6 windows of samples");
  return 0;
}
