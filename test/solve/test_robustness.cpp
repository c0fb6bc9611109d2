/* SPDX-License-Identifier: Apache-2.0 */
// Robustness of imest__bg_solve: random and garbage sums (zeros, NaN, Inf, huge,
// tiny, negative definite, rank 1, indefinite, unstructured), bad configs.
// imest__bg_solve must always return, with a known status, and never report a
// non-finite or out-of-band estimate with IMEST_OK. The iteration bound
// (out->work <= BG_SOLVE_WORK_BOUND and the per-stage bounds) is asserted
// on every case, and on realistic synthetic windows.
#include <gtest/gtest.h>

#include <cstdio>
#include <limits>

#include "solve_util.hpp"

using namespace solvetest;

namespace {

unsigned max_work = 0;

void check(const bg_sums_t &s, const bg_solve_cfg_t &cfg, const char *what, int *n_ok)
{
  bg_solve_out_t o;
  bg_solve_stats_t st;
  const int rc = imest__bg_solve_ex(&s, &cfg, &o, &st);
  EXPECT_EQ(rc, o.status) << what;
  EXPECT_TRUE(rc == IMEST_OK || rc == IMEST_REASON_NUMERIC || rc == IMEST_REASON_NO_ROOT)
      << what << " rc " << rc;
  EXPECT_LE(o.n_roots, (unsigned)IMEST_MAX_ROOTS);
  EXPECT_LE(o.n_admissible, o.n_roots);
  EXPECT_LE(st.roots.sturm_evals, BG_ROOTS_BOUND_STURM) << what;
  EXPECT_LE(st.roots.bisect_steps, BG_ROOTS_BOUND_BISECT) << what;
  EXPECT_LE(st.roots.polish_evals, BG_ROOTS_BOUND_POLISH) << what;
  EXPECT_LE(st.quality_evals, BG_QUALITY_BOUND) << what;
  EXPECT_LE(o.work, BG_SOLVE_WORK_BOUND) << what;
  max_work = std::max(max_work, o.work);
  if (rc != IMEST_OK) return;
  ++*n_ok;
  const double v[] = {o.k1,
                      o.k2,
                      o.tr_s,
                      o.rs_ohm,
                      o.e,
                      o.e_i,
                      o.hessian[0][0],
                      o.hessian[0][1],
                      o.hessian[1][1],
                      o.pe_k1,
                      o.pe_k2,
                      o.pe_quad[0],
                      o.pe_quad[1]};
  for (double x : v) EXPECT_TRUE(std::isfinite(x)) << what;
  EXPECT_GT(o.k1, 0) << what;
  EXPECT_GE(o.tr_s, cfg.tr_min_s) << what;
  EXPECT_LE(o.tr_s, cfg.tr_max_s) << what;
  EXPECT_GE(o.e, 0) << what;
  EXPECT_GE(o.pe_k1, 0) << what;
  EXPECT_GE(o.pe_k2, 0) << what;
  EXPECT_GE(o.n_admissible, 1u) << what;
  for (unsigned i = 0; i < o.n_roots; ++i) {
    EXPECT_TRUE(std::isfinite(o.roots_k2[i]) && o.roots_k2[i] > 0) << what;
    if (i) EXPECT_GT(o.roots_k2[i], o.roots_k2[i - 1]) << what;
  }
}

bg_sums_t fill(double v)
{
  bg_sums_t s{};
  for (auto &r : s.rw)
    for (double &x : r) x = v;
  for (double &x : s.rwy) x = v;
  s.ry = v;
  return s;
}

} // namespace

TEST(Robustness, GarbageSums)
{
  const bg_solve_cfg_t cfg = default_cfg();
  std::mt19937_64 rng(99);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(0, 1);
  int n_ok = 0, n = 0;
  const double inf = std::numeric_limits<double>::infinity();
  const double specials[] = {
      0.0, std::numeric_limits<double>::quiet_NaN(), inf, -inf, 1e308, -1e308, 1e-308, 5e-324, 1.0, -1.0};
  for (double v : specials) {
    check(fill(v), cfg, "constant", &n_ok);
    ++n;
  }
  const bg_sums_t tv = tv_sums();
  for (int it = 0; it < 3000; ++it) {
    bg_sums_t s = tv;
    const int kind = it % 10;
    char what[64];
    std::snprintf(what, sizeof what, "kind %d case %d", kind, it);
    switch (kind) {
    case 0: // one entry replaced by a special value
    {
      const double sp = specials[(size_t)(U(rng) * 10)];
      const int i = (int)(U(rng) * 73);
      if (i < 64)
        s.rw[i / 8][i % 8] = sp;
      else if (i < 72)
        s.rwy[i - 64] = sp;
      else
        s.ry = sp;
      break;
    }
    case 1: // negative definite
      for (auto &r : s.rw)
        for (double &x : r) x = -x;
      break;
    case 2: { // rank 1
      double u[8];
      for (double &x : u) x = N(rng) * std::pow(10.0, 6 * U(rng));
      for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) s.rw[i][j] = u[i] * u[j];
      for (int i = 0; i < 8; ++i) s.rwy[i] = u[i] * N(rng);
      break;
    }
    case 3: // random symmetric indefinite, random scales
      for (int i = 0; i < 8; ++i)
        for (int j = i; j < 8; ++j) s.rw[i][j] = s.rw[j][i] = N(rng) * std::pow(10.0, 20 * U(rng) - 10);
      for (double &x : s.rwy) x = N(rng) * std::pow(10.0, 20 * U(rng) - 10);
      s.ry = std::pow(10.0, 40 * U(rng) - 20);
      break;
    case 4: // testvector with heavy random perturbations
      for (auto &r : s.rw)
        for (double &x : r) x *= 1 + 0.5 * N(rng);
      break;
    case 5: // huge scale
      for (auto &r : s.rw)
        for (double &x : r) x *= 1e280;
      for (double &x : s.rwy) x *= 1e280;
      s.ry *= 1e280;
      break;
    case 6: // tiny scale
      for (auto &r : s.rw)
        for (double &x : r) x *= 1e-300;
      for (double &x : s.rwy) x *= 1e-300;
      s.ry *= 1e-300;
      break;
    case 7: // R_y <= 0 or R_Wy zero
      if (U(rng) < 0.5)
        s.ry = -s.ry * U(rng);
      else
        for (double &x : s.rwy) x = 0;
      break;
    case 8: // all zero but the diagonal
      for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
          if (i != j) s.rw[i][j] = 0;
      break;
    default: // non-symmetric
      for (auto &r : s.rw)
        for (double &x : r) x *= 1 + 0.01 * N(rng);
      break;
    }
    check(s, cfg, what, &n_ok);
    ++n;
  }
  std::printf(
      "[robustness] %d garbage cases: %d returned IMEST_OK (all finite, in band); max work %u (bound %u)\n",
      n, n_ok, max_work, BG_SOLVE_WORK_BOUND);
}

TEST(Robustness, RealisticWindowsAndBounds)
{
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  int n_ok = 0;
  for (int it = 0; it < 200; ++it) {
    Motor mo;
    mo.tr = 0.03 + 0.7 * U(rng);
    const bg_sums_t s = synthetic_sums(rng, mo, std::pow(10.0, -5 + 4 * U(rng)), 400);
    check(s, default_cfg(mo.sigma, mo.ls), "synthetic", &n_ok);
  }
  EXPECT_GE(n_ok, 150);
  std::printf("[robustness] 200 synthetic windows: %d OK; max work %u\n", n_ok, max_work);
}

TEST(Robustness, BadArguments)
{
  const bg_sums_t s = tv_sums();
  bg_solve_cfg_t cfg = default_cfg();
  bg_solve_out_t o;
  EXPECT_EQ(imest__bg_solve(nullptr, &cfg, &o), IMEST_ERR_NULL);
  EXPECT_EQ(imest__bg_solve(&s, nullptr, &o), IMEST_ERR_NULL);
  EXPECT_EQ(imest__bg_solve(&s, &cfg, nullptr), IMEST_ERR_NULL);
  cfg.tr_min_s = 1;
  cfg.tr_max_s = 0.5;
  EXPECT_EQ(imest__bg_solve(&s, &cfg, &o), IMEST_ERR_CONFIG);
  cfg = default_cfg();
  cfg.sigma = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(imest__bg_solve(&s, &cfg, &o), IMEST_ERR_CONFIG);
  cfg = default_cfg();
  cfg.tr_nominal_s = -1; // falls back to 0.1 s: still solves
  EXPECT_EQ(imest__bg_solve(&s, &cfg, &o), IMEST_OK);
  EXPECT_EQ(o.scale_s, 8.0);
  // a band that excludes every root: NO_ROOT, outputs NaN, no crash
  cfg = default_cfg();
  cfg.tr_min_s = 0.2;
  cfg.tr_max_s = 0.3;
  EXPECT_EQ(imest__bg_solve(&s, &cfg, &o), IMEST_REASON_NO_ROOT);
  EXPECT_EQ(o.n_roots, 3u);
  EXPECT_EQ(o.n_admissible, 0u);
  EXPECT_TRUE(std::isnan(o.tr_s));
}
