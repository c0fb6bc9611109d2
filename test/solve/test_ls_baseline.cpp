/* SPDX-License-Identifier: Apache-2.0 */
// Over-parameterised least-squares baseline (docs/METHOD.md §9): minimum-norm SVD
// solution of the 7-column reduced normal equations (columns 1,2,4..8,
// column-scaled), T_R = 1/K2 from it, against the constrained estimate, on
// the testvector (true T_R = 0.12 s).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>

#include "solve_util.hpp"

TEST(LsBaseline, ConstrainedBeatsOverParameterisedLs)
{
  const bg_sums_t s = solvetest::tv_sums();
  const int cols[7] = {0, 1, 3, 4, 5, 6, 7};
  Eigen::MatrixXd A(7, 7);
  Eigen::VectorXd b(7), d(7);
  for (int i = 0; i < 7; ++i) d[i] = 1 / std::sqrt(s.rw[cols[i]][cols[i]]);
  for (int i = 0; i < 7; ++i) {
    b[i] = s.rwy[cols[i]] * d[i];
    for (int j = 0; j < 7; ++j) A(i, j) = s.rw[cols[i]][cols[j]] * d[i] * d[j];
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  svd.setThreshold(1e-12);
  const Eigen::VectorXd z = svd.solve(b);
  const Eigen::VectorXd x = z.cwiseProduct(d); // K1, K2, K4..K8 (K3 folded into K4)
  const double tr_ls = 1 / x[1], tr_ls_k5 = x[3];
  const Eigen::VectorXd sv = svd.singularValues();
  bg_solve_out_t o;
  const bg_solve_cfg_t cfg = solvetest::default_cfg();
  ASSERT_EQ(imest__bg_solve(&s, &cfg, &o), IMEST_OK);
  std::printf("[ls-baseline] cond (column-scaled, 7 columns) %.3g; LS T_R = 1/K2 = %.6g s (K5 = %.6g s); "
              "constrained T_R = %.6g s; true 0.12 s\n",
              sv[0] / sv[6], tr_ls, tr_ls_k5, o.tr_s);
  EXPECT_LT(std::fabs(o.tr_s - 0.12), std::fabs(tr_ls - 0.12));
  EXPECT_LT(std::fabs(o.tr_s - 0.12), std::fabs(tr_ls_k5 - 0.12));
  EXPECT_LT(std::fabs(o.tr_s - 0.12) / 0.12, 1e-3);
}
