/* SPDX-License-Identifier: Apache-2.0 */
// imest-bench-solve: microseconds per imest__bg_solve on the testvector (not a
// test; prints figures). Usage: imest-bench-solve [repetitions]
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "solve_util.hpp"

// NOLINTNEXTLINE(bugprone-exception-escape): a benchmark; a JSON or file error ends it in terminate()
int main(int argc, char **argv)
{
  const long reps = (argc > 1) ? std::atol(argv[1]) : 20000;
  const bg_sums_t s = solvetest::tv_sums();
  const bg_solve_cfg_t cfg = solvetest::default_cfg();
  bg_solve_out_t o{};
  bg_solve_stats_t st{};
  volatile double sink = 0;
  (void)imest__bg_solve_ex(&s, &cfg, &o, &st);
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < reps; ++i) {
    (void)imest__bg_solve(&s, &cfg, &o);
    sink = sink + o.tr_s;
  }
  const auto t1 = std::chrono::steady_clock::now();
  const double us = std::chrono::duration<double, std::micro>(t1 - t0).count() / (double)reps;
#ifdef BG_ROOTS_DOUBLE
  const char *chain = "float64";
#else
  const char *chain = "float32";
#endif
  std::printf("imest__bg_solve (%s Sturm chain): %.2f us per solve over %ld repetitions; T_R = %.9g s\n",
              chain, us, reps, o.tr_s);
  std::printf("roots %u, work %u (Sturm %u, bisect %u, polish %u, quality %u); no allocation\n", o.n_roots,
              o.work, st.roots.sturm_evals, st.roots.bisect_steps, st.roots.polish_evals, st.quality_evals);
  return 0;
}
