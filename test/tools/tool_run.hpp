/* SPDX-License-Identifier: Apache-2.0 */
// Running a host tool as a user does, for the tool tests: a temporary folder,
// the command's exit code and output, recordings from the simulator.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include <gtest/gtest.h>

namespace tool_run {

struct Out {
  int code;
  std::string out, err;
};

inline std::string tmpdir()
{
  static std::string d;
  if (d.empty()) {
    char tmpl[] = "/tmp/imest-tool-test-XXXXXX";
    d = mkdtemp(tmpl);
    std::atexit([] { std::system(("rm -rf " + tmpdir()).c_str()); });
  }
  return d;
}

inline std::string slurp(const std::string &p)
{
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs a shell command; stdout and stderr captured.
inline Out run(const std::string &cmd)
{
  const std::string o = tmpdir() + "/out.txt", e = tmpdir() + "/err.txt";
  const int rc = std::system((cmd + " >" + o + " 2>" + e).c_str());
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, slurp(o), slurp(e)};
}

inline std::string write(const std::string &name, const std::string &text)
{
  std::string p = tmpdir() + "/" + name; // not const: returned by move
  std::ofstream(p) << text;
  return p;
}

const std::string kMotor =
    " --pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0 ";

inline Out replay(const std::string &file, const std::string &extra = "")
{
  return run(std::string(REPLAY_BIN) + kMotor + extra + " " + file);
}

// A recording from the simulator, made once per test process.
inline const std::string &sim_csv(const std::string &name, const std::string &args)
{
  static std::map<std::string, std::string> made;
  auto it = made.find(name);
  if (it != made.end()) return it->second;
  const std::string p = tmpdir() + "/" + name;
  const Out o = run(std::string(SIM_BIN) + " " + args + " --out " + p);
  EXPECT_EQ(o.code, 0) << o.err;
  return made[name] = p;
}

inline std::vector<std::string> split(const std::string &line)
{
  std::vector<std::string> f;
  std::stringstream ls(line);
  std::string x;
  while (std::getline(ls, x, ',')) f.push_back(x);
  return f;
}

inline std::vector<std::vector<std::string>> rows(const std::string &csv)
{
  std::vector<std::vector<std::string>> r;
  std::stringstream s(csv);
  std::string line;
  while (std::getline(s, line)) r.push_back(split(line));
  return r;
}

// A column's index by its header name in rows() (-1 if absent).
inline int col(const std::vector<std::vector<std::string>> &r, const std::string &name)
{
  for (size_t j = 0; !r.empty() && j < r[0].size(); ++j)
    if (r[0][j] == name) return (int)j;
  return -1;
}

// A copy of a CSV recording with each data row (its fields, its 0-based
// index) rewritten, or left out where fn returns false; the header is kept.
inline std::string rewrite(const std::string &src, const std::string &name,
                           const std::function<bool(std::vector<std::string> &, long)> &fn)
{
  std::ifstream in(src);
  std::string line, text;
  std::getline(in, line);
  text = line + "\n";
  for (long k = 0; std::getline(in, line); ++k) {
    std::vector<std::string> f = split(line);
    if (!fn(f, k)) continue;
    for (size_t j = 0; j < f.size(); ++j) text += (j ? "," : "") + f[j];
    text += "\n";
  }
  return write(name, text);
}

inline std::string fmt(const char *format, double x)
{
  char b[64];
  std::snprintf(b, sizeof b, format, x);
  return b;
}

// The estimate columns of replay's output (everything after t_end_s).
inline std::string estimates(const std::string &out)
{
  std::string r;
  for (const auto &row : rows(out)) {
    for (size_t j = 1; j < row.size(); ++j) r += row[j] + ",";
    r += "\n";
  }
  return r;
}

} // namespace tool_run
