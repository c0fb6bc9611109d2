/* SPDX-License-Identifier: Apache-2.0 */
// Fuzz the candump -L line parser (port/candump): every line of the input.
// Property (test/robustness/parser_property.h): a known return code, errors
// with a message, parsed frames valid and round-tripping through the formatter.
#include <string>

#include "fuzz_util.hpp"

extern "C" {
#include "parser_property.h"
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  std::string all(reinterpret_cast<const char *>(data), size);
  if (const char *bad = imest_candump_property(all.c_str())) fuzz::fail(bad); // up to the first NUL
  size_t at = 0;
  while (at <= all.size()) { // and line by line, as a log reader does
    size_t nl = all.find('\n', at);
    if (nl == std::string::npos) nl = all.size();
    const std::string line = all.substr(at, nl - at + (nl < all.size() ? 1 : 0));
    if (const char *bad = imest_candump_property(line.c_str())) fuzz::fail(bad);
    at = nl + 1;
  }
  return 0;
}
