/* SPDX-License-Identifier: Apache-2.0 */
// Fuzz the CSV reader of imest-replay (tools/replay/csv_reader.c): the input
// is the whole file. Property (test/robustness/parser_property.h): errors name
// the file and, for content errors, the line; rows are finite; it stops.
#include <unistd.h>

#include <string>

#include "fuzz_util.hpp"

extern "C" {
#include "parser_property.h"
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static std::string path = "/tmp/imest_fuzz_csv_" + std::to_string((long)getpid()) + ".csv";
  FILE *f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) fuzz::fail("cannot write the temporary file");
  if (size > 0 && std::fwrite(data, 1, size, f) != size) fuzz::fail("short write");
  std::fclose(f);
  long lines = 1;
  for (size_t k = 0; k < size; ++k) lines += data[k] == '\n';
  if (const char *bad = imest_csv_property(path.c_str(), lines)) fuzz::fail(bad);
  return 0;
}
