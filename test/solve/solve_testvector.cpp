/* SPDX-License-Identifier: Apache-2.0 */
// The testvector, parsed once per process, and its sums (solve_util.hpp,
// testvector.hpp): the solve tests and the benchmarks link this one object.
#include <fstream>

#include "solve_util.hpp"
#include "testvector.hpp"

namespace solvetest {

const nlohmann::json &testvector()
{
  static const nlohmann::json j = [] {
    std::ifstream f(IMEST_TESTVECTOR);
    return nlohmann::json::parse(f);
  }();
  return j;
}

bg_sums_t tv_sums()
{
  const auto &j = testvector();
  bg_sums_t s{};
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 8; ++k) s.rw[i][k] = j["R_W"][i][k].get<double>();
    s.rwy[i] = j["R_Wy"][i].get<double>();
  }
  s.ry = j["R_y"].get<double>();
  return s;
}

} // namespace solvetest
