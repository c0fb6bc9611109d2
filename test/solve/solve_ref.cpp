/* SPDX-License-Identifier: Apache-2.0 */
// Eigen's companion-matrix roots (solve_util.hpp): the polynomial solver
// instantiated once for test_roots.cpp and test_bruteforce.cpp.
#include <unsupported/Eigen/Polynomials>

#include "solve_util.hpp"

namespace solvetest {

std::vector<std::complex<double>> companion_roots(const double *c, int n)
{
  Eigen::VectorXd coef(n);
  for (int k = 0; k < n; ++k) coef[k] = c[k];
  const Eigen::PolynomialSolver<double, Eigen::Dynamic> ps(coef);
  return {ps.roots().data(), ps.roots().data() + ps.roots().size()};
}

} // namespace solvetest
