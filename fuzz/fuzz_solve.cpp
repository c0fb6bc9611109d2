/* SPDX-License-Identifier: Apache-2.0 */
// Fuzz the background solve (internal imest__bg_solve) with arbitrary window sums:
// the input bytes are the 73 doubles of R_W, R_Wy, R_y (NaN, Inf, huge,
// denormal ...), optionally followed by the 5 doubles of the solve config.
// Property (test/robustness/solve_property.h): it returns within the
// documented iteration bound; status OK implies finite T_R in the band,
// finite R_S, E_I, K1, K2, Hessian and PE indices.
#include "fuzz_util.hpp"

extern "C" {
#include "solve_property.h"
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  fuzz::Reader in{data, size};
  bg_sums_t s;
  std::memset(&s, 0, sizeof s);
  // the first byte chooses the layout: full 8x8 as given, or symmetric with
  // the solve's structure (row/column 2 = -m x row/column 3), which reaches
  // the later stages more often
  const uint8_t mode = in.byte();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) s.rw[i][j] = in.get<double>(0.0);
  for (int i = 0; i < 8; ++i) s.rwy[i] = in.get<double>(0.0);
  s.ry = in.get<double>(0.0);
  if (mode & 1) {
    const double m = 0.6237;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < i; ++j) s.rw[i][j] = s.rw[j][i];
    for (int j = 0; j < 8; ++j) s.rw[2][j] = s.rw[j][2] = -m * s.rw[3][j];
    s.rw[2][2] = m * m * s.rw[3][3];
    s.rwy[2] = -m * s.rwy[3];
  }
  bg_solve_cfg_t cfg{};
  cfg.weight_c = (mode & 4) ? imest__bg_solve_weight_c(&s) : 0.0;
  cfg.sigma = 0.096;
  cfg.ls_h = 0.2908;
  cfg.tr_nominal_s = 0.1;
  cfg.tr_min_s = 1e-3;
  cfg.tr_max_s = 10.0;
  if (mode & 2) {
    cfg.sigma = in.get<double>(cfg.sigma);
    cfg.ls_h = in.get<double>(cfg.ls_h);
    cfg.tr_nominal_s = in.get<double>(cfg.tr_nominal_s);
    cfg.tr_min_s = in.get<double>(cfg.tr_min_s);
    cfg.tr_max_s = in.get<double>(cfg.tr_max_s);
    cfg.weight_c = in.get<double>(cfg.weight_c);
  }
  bg_solve_out_t out;
  std::memset(&out, 0xA5, sizeof out);
  const int rc = imest__bg_solve(&s, &cfg, &out);
  if (const char *bad = solve_property(rc, &cfg, &out)) fuzz::fail(bad);
  return 0;
}
