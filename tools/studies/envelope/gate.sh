#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# CTest form of the envelope benchmark (label envelope): the reduced run, then the gate
# false_valid_gross == 0 (no window with T_R valid and > 10 % off or R_S valid and > 25 % off).
# Usage: gate.sh IMEST_SIM IMEST_REPLAY OUT_DIR
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
sim=${1:?usage: gate.sh IMEST_SIM IMEST_REPLAY OUT_DIR} replay=${2:?} out=${3:?}
summary=$("$here/run" --sim "$sim" --replay "$replay" --out "$out" --quiet)
echo "$summary"
for k in coverage_tr coverage_rs false_valid_gross false_valid_marginal windows_goal; do
  grep -Eq "^$k [0-9.]+$" <<<"$summary" || { echo "envelope gate: no summary line $k" >&2; exit 1; }
done
[ -s "$out/results.md" ] && [ -s "$out/windows.csv" ] || { echo "envelope gate: no tables" >&2; exit 1; }
gross=$(awk '$1 == "false_valid_gross" { print $2 }' <<<"$summary")
if [ "$gross" != 0 ]; then
  echo "envelope gate FAILED: $gross window(s) valid and grossly wrong; see $out/results.md" >&2
  exit 1
fi
echo "envelope gate: passed (false_valid_gross 0)"
