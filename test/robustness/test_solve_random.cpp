/* SPDX-License-Identifier: Apache-2.0 */
// The background solve (internal imest__bg_solve) on 20 000 seeded random windows
// of sums: raw bit patterns (NaN, Inf, denormal, huge), special values, and
// structured sums R = sum W'W from random W (full rank, rank deficient, scaled
// by 1e+-30, sign flips, one entry poisoned, random motor constants and
// bands). Property (solve_property.h): it returns within the documented
// iteration bound, and status OK implies finite T_R inside the band, finite
// R_S and E_I. The same property is fuzzed by fuzz/fuzz_solve.cpp.
#include <gtest/gtest.h>

#include <cfloat>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>

extern "C" {
#include "solve_property.h"
}

namespace {

constexpr double kM = 0.6237; // M*beta of the paper's motor (any positive value will do)

struct Gen {
  std::mt19937_64 rng;
  explicit Gen(uint64_t seed) : rng(seed) {}
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  int pick(int n) { return (int)(rng() % (uint64_t)n); }
  double gauss() { return std::normal_distribution<double>(0.0, 1.0)(rng); }
  double bits()
  {
    const uint64_t u = rng();
    double d;
    std::memcpy(&d, &u, sizeof d);
    return d;
  }
  double special()
  {
    static const double v[] = {std::numeric_limits<double>::quiet_NaN(),
                               -std::numeric_limits<double>::quiet_NaN(),
                               std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity(),
                               0.0,
                               -0.0,
                               4.9e-324,
                               -4.9e-324,
                               2.2e-308,
                               DBL_MAX,
                               -DBL_MAX,
                               1e300,
                               -1e300,
                               1e-300,
                               1.0,
                               -1.0,
                               1e30,
                               1e-30};
    return v[pick((int)(sizeof v / sizeof v[0]))];
  }
};

void kvec(double k1, double k2, double K[8])
{
  K[0] = k1;
  K[1] = k2;
  K[2] = k2 * k2;
  K[3] = k1 * k2;
  K[4] = 1 / k2;
  K[5] = k1 / k2;
  K[6] = k1 / (k2 * k2);
  K[7] = 1 / (k2 * k2);
}

// R_W, R_Wy, R_y from `rows` random rows of W (column 2 = -m column 3, as the
// solve expects), y = W K(k1, k2) + noise. rank < 8: W built from that many
// random directions only.
bg_sums_t structured(Gen &g, int rows, int rank, double noise, double m)
{
  bg_sums_t s{};
  double colscale[8], basis[8][8];
  for (int j = 0; j < 8; ++j) colscale[j] = std::pow(10.0, g.uni(-3, 3));
  for (int r = 0; r < 8; ++r)
    for (int j = 0; j < 8; ++j) basis[r][j] = g.gauss();
  const double k1 = std::pow(10.0, g.uni(0, 3)), k2 = std::pow(10.0, g.uni(-1, 3));
  double K[8];
  kvec(k1, k2, K);
  for (int n = 0; n < rows; ++n) {
    double w[8] = {0};
    for (int r = 0; r < rank; ++r) {
      const double c = g.gauss();
      for (int j = 0; j < 8; ++j) w[j] += c * basis[r][j];
    }
    for (int j = 0; j < 8; ++j) w[j] *= colscale[j];
    w[2] = -m * w[3];
    double y = 0;
    for (int j = 0; j < 8; ++j) y += w[j] * K[j];
    y += noise * g.gauss() * (std::fabs(y) + 1e-300);
    for (int i = 0; i < 8; ++i) {
      s.rwy[i] += w[i] * y;
      for (int j = 0; j < 8; ++j) s.rw[i][j] += w[i] * w[j];
    }
    s.ry += y * y;
  }
  return s;
}

double *entry(bg_sums_t &s, int k)
{ // 0..72
  if (k < 64) return &s.rw[k / 8][k % 8];
  if (k < 72) return &s.rwy[k - 64];
  return &s.ry;
}

bg_solve_cfg_t default_cfg()
{
  bg_solve_cfg_t c{};
  c.sigma = 0.096;
  c.ls_h = 0.2908;
  c.tr_nominal_s = 0.1;
  c.tr_min_s = 1e-3;
  c.tr_max_s = 10.0;
  return c;
}

std::string hexdump(const bg_sums_t &s, const bg_solve_cfg_t &c)
{
  std::string o;
  char b[64];
  const double *p = &s.rw[0][0];
  for (int k = 0; k < 73; ++k) {
    std::snprintf(b, sizeof b, "%a%s",
                  k < 64   ? p[k]
                  : k < 72 ? s.rwy[k - 64]
                           : s.ry,
                  k % 8 == 7 ? "\n" : " ");
    o += b;
  }
  std::snprintf(b, sizeof b, "\ncfg %a %a %a %a %a\n", c.sigma, c.ls_h, c.tr_nominal_s, c.tr_min_s,
                c.tr_max_s);
  return o + b;
}

} // namespace

TEST(SolveRandom, PropertyHoldsOn20000SeededCases)
{
#if defined(__SANITIZE_ADDRESS__)
  const int kCases = 6000; // same generator, fewer cases under ASan
#else
  const int kCases = 20000;
#endif
  Gen g(0x1e57'501f'e5ee'd001ull);
  int failures = 0, by_status[32] = {0}, config_errors = 0;
  unsigned int max_work = 0;
  for (int n = 0; n < kCases && failures < 5; ++n) {
    bg_sums_t s{};
    bg_solve_cfg_t cfg = default_cfg();
    const int kind = n % 8;
    switch (kind) {
    case 0: // raw bit patterns
      for (int k = 0; k < 73; ++k) *entry(s, k) = g.bits();
      break;
    case 1: // special values everywhere
      for (int k = 0; k < 73; ++k) *entry(s, k) = g.pick(3) ? g.special() : g.gauss();
      break;
    case 2: // structured, full rank, noise from 1e-8 to 1
      s = structured(g, 8 + g.pick(200), 8, std::pow(10.0, g.uni(-8, 0)), kM);
      break;
    case 3: // rank deficient (also zero rows: rank 0)
      s = structured(g, 1 + g.pick(100), g.pick(8), std::pow(10.0, g.uni(-8, 0)), kM);
      break;
    case 4: { // scaled by 1e+-30 (and beyond, to overflow)
      s = structured(g, 8 + g.pick(50), 8, 1e-3, kM);
      const double f = std::pow(10.0, g.uni(-300, 300) * (g.pick(2) ? 0.1 : 1.0));
      for (int k = 0; k < 73; ++k) *entry(s, k) *= f;
      break;
    }
    case 5: { // sign flips: of single entries, of R_W, of R_y
      s = structured(g, 8 + g.pick(50), 8, 1e-3, kM);
      const int how = g.pick(3);
      if (how == 0)
        for (int t = 1 + g.pick(4); t > 0; --t) *entry(s, g.pick(73)) *= -1;
      else if (how == 1)
        for (int k = 0; k < 64; ++k) *entry(s, k) *= -1;
      else
        s.ry = -s.ry;
      break;
    }
    case 6: // one or two entries poisoned
      s = structured(g, 8 + g.pick(50), 8, 1e-3, kM);
      for (int t = 1 + g.pick(2); t > 0; --t) *entry(s, g.pick(73)) = g.pick(2) ? g.special() : g.bits();
      break;
    default: { // random motor constants, band and m (some invalid)
      s = structured(g, 8 + g.pick(50), g.pick(4) ? 8 : 6, 1e-4, g.pick(5) ? g.uni(0, 5) : g.special());
      cfg.sigma = g.pick(8) ? g.uni(0.0, 1.0) : g.special();
      cfg.ls_h = g.pick(8) ? std::pow(10.0, g.uni(-4, 1)) : g.special();
      cfg.tr_nominal_s = g.pick(8) ? std::pow(10.0, g.uni(-4, 2)) : g.special();
      cfg.tr_min_s = g.pick(8) ? std::pow(10.0, g.uni(-5, 0)) : g.special();
      cfg.tr_max_s = g.pick(8) ? cfg.tr_min_s * std::pow(10.0, g.uni(-1, 5)) : g.special();
      break;
    }
    }
    bg_solve_out_t out;
    std::memset(&out, 0xA5, sizeof out); // garbage in: the solve must set what it reports
    const int rc = imest__bg_solve(&s, &cfg, &out);
    const char *bad = solve_property(rc, &cfg, &out);
    if (rc >= 0 && rc < 32) by_status[rc]++;
    if (rc == IMEST_ERR_CONFIG) ++config_errors;
    if (out.work > max_work) max_work = out.work;
    if (bad != nullptr) {
      ++failures;
      ADD_FAILURE() << "case " << n << " (kind " << kind << "): " << bad << " (status " << rc << ", tr "
                    << out.tr_s << ")\n"
                    << hexdump(s, cfg);
    }
  }
  std::printf("[ solve    ] %d cases: ok %d, numeric %d, no_root %d, config %d; most work %u of %u\n", kCases,
              by_status[IMEST_OK], by_status[IMEST_REASON_NUMERIC], by_status[IMEST_REASON_NO_ROOT],
              config_errors, max_work, (unsigned)BG_SOLVE_WORK_BOUND);
  // the structured cases must reach the OK branch often, or the property is vacuous
  EXPECT_GT(by_status[IMEST_OK], kCases / 8);
}

// NULL arguments: an error status, no crash.
TEST(SolveRandom, NullArguments)
{
  bg_sums_t s{};
  bg_solve_cfg_t cfg = default_cfg();
  bg_solve_out_t out;
  EXPECT_EQ(imest__bg_solve(nullptr, &cfg, &out), IMEST_ERR_NULL);
  EXPECT_EQ(imest__bg_solve(&s, nullptr, &out), IMEST_ERR_NULL);
  EXPECT_NE(imest__bg_solve(&s, &cfg, nullptr), IMEST_OK);
}
