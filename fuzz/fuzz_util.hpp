/* SPDX-License-Identifier: Apache-2.0 */
// Shared by the fuzz targets: reading typed values from the input, failing
// loudly (abort: libFuzzer saves the input as a crash file).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace fuzz {

[[noreturn]] inline void fail(const char *what)
{
  std::fprintf(stderr, "PROPERTY VIOLATED: %s\n", what);
  std::abort();
}

struct Reader {
  const uint8_t *p;
  size_t n;
  template <class T> T get(T dflt)
  {
    if (n < sizeof(T)) return dflt;
    T v;
    std::memcpy(&v, p, sizeof v);
    p += sizeof v;
    n -= sizeof v;
    return v;
  }
  uint8_t byte(uint8_t dflt = 0) { return get<uint8_t>(dflt); }
};

} // namespace fuzz
