// Shared helpers for the simulator tests.
#pragma once
#include <cmath>
#include <complex>
#include <vector>

#include "imsim/imsim.h"

namespace simtest {
using cd = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

inline imsim_config ideal(const char *preset = "exp1") {
  imsim_config c;
  imsim_config_preset(&c, preset);
  c.ideal_sensors = true;
  c.thermal = false;
  return c;
}

// Runs n samples (after the t = 0 one) and returns all samples including t = 0.
inline std::vector<imsim_sample> run(const imsim_config &c, long n) {
  static imsim sim;  // large-ish, keep off the stack
  std::vector<imsim_sample> out(static_cast<size_t>(n + 1));
  if (imsim_init(&sim, &c, &out[0]) != 0) return {};
  for (long k = 1; k <= n; ++k) imsim_step(&sim, &out[static_cast<size_t>(k)]);
  return out;
}

inline cd iab(const imsim_sample &s) { return {s.i_ab_true[0], s.i_ab_true[1]}; }
inline cd psiab(const imsim_sample &s) { return {s.psi_ab[0], s.psi_ab[1]}; }
}  // namespace simtest
