/* SPDX-License-Identifier: Apache-2.0 */
// Shared helpers for the simulator tests.
#pragma once
#include <cmath>
#include <complex>
#include <vector>

#include "imsim/imsim.h"

namespace simtest {
using cd = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

inline imsim_config_t ideal(const char *preset = "exp1")
{
  imsim_config_t c;
  imsim_config_preset(&c, preset);
  c.ideal_sensors = true;
  c.thermal = false;
  return c;
}

// The inverter errors of the tests: 2 us dead time, switch 1 V + 0.02 ohm, diode 0.8 V + 0.01 ohm.
inline void add_inverter_errors(imsim_config_t &c)
{
  c.dead_time_s = 2e-6;
  c.v_switch_v = 1.0;
  c.r_switch_ohm = 0.02;
  c.v_diode_v = 0.8;
  c.r_diode_ohm = 0.01;
}

// Runs n samples (after the t = 0 one) and returns all samples including t = 0.
inline std::vector<imsim_sample_t> run(const imsim_config_t &c, long n)
{
  static imsim_t sim; // large-ish, keep off the stack
  std::vector<imsim_sample_t> out(static_cast<size_t>(n + 1));
  if (imsim_init(&sim, &c, &out[0]) != 0) return {};
  for (long k = 1; k <= n; ++k) imsim_step(&sim, &out[static_cast<size_t>(k)]);
  return out;
}

inline cd iab(const imsim_sample_t &s)
{
  return {s.i_ab_true[0], s.i_ab_true[1]};
}
inline cd psiab(const imsim_sample_t &s)
{
  return {s.psi_ab[0], s.psi_ab[1]};
}
} // namespace simtest
