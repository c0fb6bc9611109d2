#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# Validity study: simulate a matrix of recordings with imest-sim, replay each
# with imest-replay (default configuration, the motor constants only), compare
# every window with the simulator's truth and report how well the validity
# rule separates good from bad windows. Results: README.md in this folder.
#
# usage: tools/studies/validity-study/run.sh [BUILD_DIR] [OUT_DIR]
#   BUILD_DIR  build with imest-sim and imest-replay (default: build-vs; built if missing)
#   OUT_DIR    where the per-case results go (default: BUILD_DIR/validity-study)
# Runs on 2 cores (JOBS=n to change); a few minutes. Needs /usr/bin/python3 + numpy.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
B=${1:-$ROOT/build-vs}
OUT=${2:-$B/validity-study}
JOBS=${JOBS:-2}
if [ ! -x "$B/bin/imest-sim" ] || [ ! -x "$B/bin/imest-replay" ]; then
  cmake -S "$ROOT" -B "$B" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$B" -j2 --target imest-sim imest-replay >/dev/null
fi
rm -rf "$OUT/cases" "$OUT/tmp"
mkdir -p "$OUT"

EXACT="--ls-uncertainty 0 --sigma-uncertainty 0"            # the simulator's own constants
M1="--pole-pairs 2 --ls 0.2908 --sigma 0.096 $EXACT"        # paper motor (sim default)
M2S="--pole-pairs 4 --ls 0.05 --lr 0.05 --rs 0.5 --tr 0.3"  # second motor (sigma 0.096)
M2R="--pole-pairs 4 --ls 0.05 --sigma 0.096 $EXACT"
RATED=2.064

cases() {
  # name|imest-sim args|imest-replay args|cut: drop rows with t < cut [s]
  # --- EXP1: 60 Hz DOL run-up, then no load (zero slip) ---------------------
  echo "exp1_ideal|--preset exp1 --duration 5 --ideal-sensors|$M1|0"
  for s in 1 2 3 4; do echo "exp1_12b_s$s|--preset exp1 --duration 5 --seed $s|$M1|0"; done
  for s in 1 2; do echo "exp1_12b_10A_s$s|--preset exp1 --duration 5 --seed $s --i-range 10|$M1|0"; done
  echo "exp1_12b_noise0|--preset exp1 --duration 5 --noise-lsb 0|$M1|0"
  for s in 1 2; do echo "exp1_12b_noise3_s$s|--preset exp1 --duration 5 --noise-lsb 3 --seed $s|$M1|0"; done
  echo "exp1_enc1024|--preset exp1 --duration 5 --encoder-counts 1024|$M1|0"
  echo "exp1_enc65536|--preset exp1 --duration 5 --encoder-counts 65536|$M1|0"
  echo "exp1_12b_fs10k|--preset exp1 --duration 5 --fs 10000|$M1|0"
  echo "exp1_pwm|--preset exp1 --duration 4 --supply pwm|$M1|0"
  echo "exp1_pwm_ideal|--preset exp1 --duration 4 --supply pwm --ideal-sensors|$M1|0"
  for c in 0.02 0.3 2.5; do echo "exp1_12b_cut$c|--preset exp1 --duration 6 --seed 5|$M1|$c"; done
  echo "exp1_12b_f50|--preset exp1 --duration 5 --seed 1|$M1 --filter-hz 50|0"
  # --- EXP2: 30 Hz V/f ramp, no load, rated load ramped in at 1.5..2.5 s -----
  echo "exp2_ideal|--preset exp2 --duration 8 --ideal-sensors|$M1|0"
  for s in 1 2 3 4; do echo "exp2_12b_s$s|--preset exp2 --duration 8 --seed $s|$M1|0"; done
  echo "exp2_12b_noise0|--preset exp2 --duration 8 --noise-lsb 0|$M1|0"
  for s in 1 2; do echo "exp2_12b_noise3_s$s|--preset exp2 --duration 8 --noise-lsb 3 --seed $s|$M1|0"; done
  echo "exp2_enc1024|--preset exp2 --duration 8 --encoder-counts 1024|$M1|0"
  echo "exp2_enc65536|--preset exp2 --duration 8 --encoder-counts 65536|$M1|0"
  echo "exp2_12b_fs10k|--preset exp2 --duration 8 --fs 10000|$M1|0"
  echo "exp2_pwm_ideal|--preset exp2 --duration 8 --supply pwm --ideal-sensors|$M1|0"
  for s in 1 2; do echo "exp2_pwm_s$s|--preset exp2 --duration 8 --supply pwm --seed $s|$M1|0"; done
  echo "exp2_pwm_aa800|--preset exp2 --duration 8 --supply pwm --aa-hz 800 --vmeas aa|$M1 --aa-hz 800|0"
  for c in 0.6 2.3 3.7; do echo "exp2_12b_cut$c|--preset exp2 --duration 9 --seed 6|$M1|$c"; done
  # --- load sweep, sinusoidal steady state, 30 Hz / 115 V and 60 Hz / 230 V --
  for f in 30 60; do
    v=$((f == 30 ? 115 : 230))
    for x in 0 0.05 0.1 0.25 0.5 1.0 1.5; do
      l=$(awk -v x=$x -v r=$RATED 'BEGIN { printf "%.4g", x * r }')
      base="--supply sine --vll $v --freq $f --start steady --load-nm $l --duration 5"
      echo "load${f}_x${x}_ideal|$base --ideal-sensors|$M1|0"
      for s in 1 2; do echo "load${f}_x${x}_12b_s$s|$base --seed $s|$M1|0"; done
      echo "load${f}_x${x}_noise3|$base --noise-lsb 3 --seed 3|$M1|0"
      echo "load${f}_x${x}_enc65536|$base --encoder-counts 65536 --seed 4|$M1|0"
      echo "load${f}_x${x}_enc1024|$base --encoder-counts 1024 --seed 5|$M1|0"
      echo "load${f}_x${x}_12b_f50|$base --seed 1|$M1 --filter-hz 50|0"
    done
    echo "load${f}_x1.0_fs10k|--supply sine --vll $v --freq $f --start steady --load-nm $RATED --duration 5 --fs 10000|$M1|0"
  done
  # --- second motor (n_p 4, L_S 0.05 H, R_S 0.5 ohm, T_R 0.3 s), 40 A sensor ---
  for f in 30 60; do
    v=$((f == 30 ? 115 : 230))
    for l in 0 1 3 6 12 24; do
      base="$M2S --supply sine --vll $v --freq $f --start steady --load-nm $l --duration 5 --i-range 40"
      echo "m2_${f}hz_L${l}_12b|$base --seed 7|$M2R|0"
      echo "m2_${f}hz_L${l}_ideal|$base --ideal-sensors|$M2R|0"
      echo "m2_${f}hz_L${l}_12b_f50|$base --seed 7|$M2R --filter-hz 50|0"
    done
  done
  echo "m2_vf30_12b|$M2S --preset exp2 --load-nm 20 --duration 8 --i-range 40 --seed 8|$M2R|0"
  echo "m2_vf30_ideal|$M2S --preset exp2 --load-nm 20 --duration 8 --i-range 40 --ideal-sensors|$M2R|0"
}

cases >"$OUT/cases.txt"
echo "validity study: $(wc -l <"$OUT/cases.txt") cases, $JOBS jobs, results in $OUT" >&2
t0=$(date +%s)
tr '\n' '\0' <"$OUT/cases.txt" | xargs -0 -P "$JOBS" -n 1 "$HERE/one_case.sh" "$OUT" "$B"
echo "simulated and replayed in $(($(date +%s) - t0)) s" >&2
rmdir "$OUT/tmp" 2>/dev/null || true
/usr/bin/python3 "$HERE/analyse.py" "$OUT" | tee "$OUT/report.md"
