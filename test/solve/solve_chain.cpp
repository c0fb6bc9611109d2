/* SPDX-License-Identifier: Apache-2.0 */
// Which Sturm chain this test binary's solve library has (SOLVE_CHAIN_F32, set
// per binary by test/solve/CMakeLists.txt): the one file of the solve tests
// compiled once per chain; the tests themselves are compiled once.

namespace solvetest {
bool chain_f32();
bool chain_f32()
{
  return SOLVE_CHAIN_F32 != 0;
}
} // namespace solvetest
