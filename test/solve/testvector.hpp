/* SPDX-License-Identifier: Apache-2.0 */
// The testvector (test/data/testvector.json) as parsed JSON, for the tests that
// read its stage-by-stage values; defined in solve_testvector.cpp, the one file
// that instantiates the JSON parser.
#pragma once

#include <nlohmann/json.hpp>

namespace solvetest {
const nlohmann::json &testvector();
} // namespace solvetest
