#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Accuracy of imest-replay on the simulator's recordings of the paper's two
# experiments, ideal and 12-bit sensors: per-window error of T_R and R_S
# against the truth averaged over the same window, valid/invalid counts.
# Usage: tools/studies/accuracy/run.sh [BUILD_DIR] [EXP2_SECONDS]
# Environment: REPLAY_ARGS = extra imest-replay options for every recording.
set -euo pipefail
top=$(cd "$(dirname "$0")/../../.." && pwd)
build=${1:-$top/build}
dur2=${2:-120}
sim=$build/bin/imest-sim
rep=$build/bin/imest-replay
[ -x "$sim" ] && [ -x "$rep" ] || { echo "build first: cmake --build $build --target imest-sim imest-replay" >&2; exit 2; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
motor="--pole-pairs 2 --ls 0.2908 --sigma 0.096 --ls-uncertainty 0 --sigma-uncertainty 0"  # exact
printf '| recording | windows | valid | invalid (reasons) | T_R error %% valid: mean / max abs | R_S error %% valid: mean / max abs |\n|---|---|---|---|---|---|\n'
run() { # name, sim args, replay args
  local name=$1 sargs=$2 rargs=${3:-}
  "$sim" $sargs --out "$tmp/$name.csv" --no-progress 2>/dev/null
  "$rep" $motor $rargs ${REPLAY_ARGS:-} "$tmp/$name.csv" > "$tmp/$name.win" 2>/dev/null
  awk -F, -v name="$name" '
    FNR == 1 { next }
    FILENAME ~ /\.csv$/ { t[++n] = $1; tr[n] = $9; rs[n] = $10; next }
    { w[++m] = $0 }
    END {
      # truth per window: mean over the samples t in (t_end - window, t_end]
      j = 1; nv = 0; ni = 0; reasons = ""
      for (k = 1; k <= m; ++k) {
        split(w[k], f, ",")
        te = f[1]; if (k == 1) ts = t[1] - 1e-9; 
        s1 = 0; s2 = 0; c = 0
        while (j <= n && t[j] <= te + 1e-9) { if (t[j] > ts) { s1 += tr[j]; s2 += rs[j]; c++ } j++ }
        ts = te
        if (f[5] == 1) {
          nv++; etr = (f[2] - s1 / c) / (s1 / c) * 100; ers = (f[3] - s2 / c) / (s2 / c) * 100
          str += etr; srs += ers; a = etr < 0 ? -etr : etr; if (a > mtr) mtr = a
          a = ers < 0 ? -ers : ers; if (a > mrs) mrs = a
        } else { ni++; cnt[f[6]]++ }
      }
      for (r in cnt) reasons = reasons (reasons == "" ? "" : ", ") cnt[r] " " r
      if (nv) printf "| %s | %d | %d | %d (%s) | %+.3f / %.3f | %+.3f / %.3f |\n", name, m, nv, ni, reasons, str / nv, mtr, srs / nv, mrs
      else printf "| %s | %d | 0 | %d (%s) | – | – |\n", name, m, ni, reasons
    }' "$tmp/$name.csv" "$tmp/$name.win"
}
run exp1_ideal "--preset exp1 --duration 3 --ideal-sensors"
run exp1_12bit "--preset exp1 --duration 3"
run exp2_ideal "--preset exp2 --duration $dur2 --supply vf --ideal-sensors"
run exp2_12bit "--preset exp2 --duration $dur2 --supply vf"
run exp2_12bit_pwm "--preset exp2 --duration $dur2 --supply pwm" "--u-delay 50e-6"
run exp2_12bit_midrun "--preset exp2 --duration $dur2 --supply vf --start steady"
