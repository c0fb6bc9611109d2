/* SPDX-License-Identifier: Apache-2.0 */
// The host parsers on seeded random and mutated input: the CSV reader of
// imest-replay (tools/replay/csv_reader.c) and the candump -L line parser
// (port/candump). Property (parser_property.h): no crash, no sanitizer error,
// a known return code, errors with a message (CSV: "file:line: ..."), parsed
// frames valid and round-tripping. The same properties are fuzzed by fuzz/.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

extern "C" {
#include "parser_property.h"
}

namespace {

struct Gen {
  std::mt19937_64 rng;
  explicit Gen(uint64_t seed) : rng(seed) {}
  int pick(int n) { return (int)(rng() % (uint64_t)n); }
  char any_byte() { return (char)(unsigned char)pick(256); }
  char from(const char *alphabet) { return alphabet[pick((int)std::strlen(alphabet))]; }
};

const char *const kTokens[] = {"nan",       "-inf",
                               "inf",       "1e999",
                               "-1e-999",   "",
                               " ",         "\"1\"",
                               ",,,",       "\xEF\xBB\xBF",
                               "\r",        "\n",
                               "\r\n",      "0x1p3",
                               "1e",        "--1",
                               "+",         ".",
                               "1,2",       "\"",
                               "\"\"",      "t",
                               "theta",     "u_a",
                               "i_c",       "\t",
                               "4.9e-324",  "1.7976931348623157e308",
                               "#",         "(",
                               ")",         "123#",
                               "12345678#", "##",
                               "#R",        "vcan0",
                               "(0.0)",     "FFFFFFFF",
                               "1FFFFFFF"};

// Random edits of s: flip/insert/delete bytes, splice tokens, truncate, repeat.
void mutate(Gen &g, std::string &s, int edits, const char *alphabet)
{
  for (int e = 0; e < edits; ++e) {
    const size_t at = s.empty() ? 0 : (size_t)g.pick((int)s.size() + 1);
    switch (g.pick(7)) {
    case 0:
      if (!s.empty()) s[std::min(at, s.size() - 1)] = g.pick(4) ? g.from(alphabet) : g.any_byte();
      break;
    case 1: s.insert(at, 1, g.pick(4) ? g.from(alphabet) : g.any_byte()); break;
    case 2:
      if (!s.empty()) s.erase(std::min(at, s.size() - 1), 1 + (size_t)g.pick(4));
      break;
    case 3: s.insert(at, kTokens[g.pick((int)(sizeof kTokens / sizeof kTokens[0]))]); break;
    case 4: s.resize(at); break;
    case 5: {
      const size_t from = at, len = (size_t)g.pick(40);
      if (from < s.size()) s.insert((size_t)g.pick((int)s.size() + 1), s.substr(from, len));
      break;
    }
    default:
      if (g.pick(50) == 0) s.insert(at, std::string(70000 + (size_t)g.pick(1000), g.from(alphabet)));
      break;
    }
  }
}

std::string valid_csv(Gen &g)
{
  std::vector<std::string> cols = {"t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta"};
  for (int x = g.pick(3); x > 0; --x) cols.push_back(g.pick(2) ? "extra" : "\"note\"");
  std::shuffle(cols.begin(), cols.end(), g.rng);
  const char *eol = g.pick(3) ? "\n" : "\r\n";
  std::string s = g.pick(8) ? "" : "\xEF\xBB\xBF";
  for (size_t k = 0; k < cols.size(); ++k)
    s += (k ? "," : "") + (g.pick(6) ? cols[k] : " \"" + cols[k] + "\" ");
  s += eol;
  for (int row = g.pick(12); row > 0; --row) {
    for (size_t k = 0; k < cols.size(); ++k) {
      char b[40];
      std::snprintf(b, sizeof b, "%s%.6g", k ? "," : "",
                    std::uniform_real_distribution<double>(-400, 400)(g.rng));
      s += b;
    }
    s += eol;
  }
  return s;
}

std::string valid_candump(Gen &g)
{
  imest_can_frame_t f{};
  f.id = g.pick(2) ? (uint32_t)g.pick(0x800) : ((uint32_t)g.rng() & IMEST_CAN_EFF_MASK) | IMEST_CAN_ID_EXT;
  f.dlc = (uint8_t)g.pick(9);
  for (unsigned k = 0; k < f.dlc; ++k) f.data[k] = (uint8_t)g.pick(256);
  char buf[IMEST_CANDUMP_LINE_MAX];
  const double t = std::uniform_real_distribution<double>(0, 2e9)(g.rng);
  const int n = imest_candump_format(buf, sizeof buf, t, g.pick(2) ? "can0" : nullptr, &f);
  EXPECT_GT(n, 0);
  return std::string(buf) + (g.pick(2) ? "\n" : "");
}

size_t count_lines(const std::string &s)
{
  size_t n = 1;
  for (char c : s) n += c == '\n';
  return n;
}

} // namespace

TEST(ParsersRandom, CandumpParserOn100000Lines)
{
  Gen g(0xCA4D'0001);
  int ok = 0, err = 0;
  const char *alpha = "()0123456789.#ABCDEFabcdefRr \tvcan";
  for (int n = 0; n < 100000; ++n) {
    std::string line;
    if (n % 10 == 0) { // random bytes
      for (int k = g.pick(80); k > 0; --k) line += g.any_byte();
    } else if (n % 10 == 1) { // random characters of the format
      for (int k = g.pick(80); k > 0; --k) line += g.from(alpha);
    } else {
      line = valid_candump(g);
      mutate(g, line, n % 10 == 2 ? 0 : 1 + g.pick(4), alpha);
    }
    const char *bad = imest_candump_property(line.c_str());
    if (bad != nullptr) {
      ADD_FAILURE() << "line " << n << ": " << bad << ": '" << line << "'";
      if (++err > 5) break;
    }
    imest_can_frame_t f;
    ok += imest_candump_parse(line.c_str(), nullptr, nullptr, &f, nullptr) == IMEST_CANDUMP_OK;
  }
  std::printf("[ parsers  ] candump: 100000 lines, %d parsed as frames\n", ok);
  EXPECT_GT(ok, 10000); // the mutations keep many lines valid: the frame branch is exercised
}

TEST(ParsersRandom, CsvReaderOn3000Files)
{
  char path[] = "/tmp/imest_csv_random_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  Gen g(0xC5F0'0001);
  int opened = 0, fails = 0;
  const char *alpha = "0123456789.,-+eE \"\r\ntu_abciheta";
  for (int n = 0; n < 3000; ++n) {
    std::string s;
    if (n % 10 == 0) {
      for (int k = g.pick(400); k > 0; --k) s += g.any_byte();
    } else {
      s = valid_csv(g);
      mutate(g, s, n % 10 == 1 ? 0 : 1 + g.pick(6), alpha);
    }
    FILE *f = std::fopen(path, "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(s.data(), 1, s.size(), f);
    std::fclose(f);
    const char *bad = imest_csv_property(path, (long)count_lines(s));
    if (bad != nullptr) {
      ADD_FAILURE() << "file " << n << ": " << bad << ":\n" << s.substr(0, 2000);
      if (++fails > 5) break;
    }
    csv_reader_t r;
    if (csv_open(&r, path) == 0) ++opened;
    csv_close(&r);
  }
  std::remove(path);
  std::printf("[ parsers  ] csv: 3000 files, %d with a valid header\n", opened);
  EXPECT_GT(opened, 500);
  // a file that does not exist: an error naming it
  EXPECT_EQ(imest_csv_property("/nonexistent/imest.csv", 1), nullptr);
}
