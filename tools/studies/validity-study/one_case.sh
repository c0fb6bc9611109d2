#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# One case of the validity study: simulate, optionally cut the first rows,
# replay, and write per-window truth means next to the replay output.
# usage: one_case.sh OUT_DIR BUILD_DIR 'name|sim args|replay args|cut_s'
# Environment: REPLAY_ARGS = extra imest-replay options for every case (e.g. --dc-block-hz 0).
set -u
OUT=$1 B=$2 LINE=$3
IFS='|' read -r NAME SIMARGS REPARGS CUT <<<"$LINE"
CSV="$OUT/tmp/$NAME.csv"
mkdir -p "$OUT/tmp" "$OUT/cases"
# shellcheck disable=SC2086
if ! "$B/bin/imest-sim" $SIMARGS --no-progress --out "$CSV" 2>"$OUT/cases/$NAME.simlog"; then
  echo "SIM FAILED: $NAME" >&2; exit 0
fi
if [ -n "$CUT" ] && [ "$CUT" != 0 ]; then
  # windows starting mid-run: drop the rows with t < CUT (header kept)
  awk -F, -v c="$CUT" 'NR == 1 || $1 + 1e-9 >= c' "$CSV" >"$CSV.cut" && mv "$CSV.cut" "$CSV"
fi
# shellcheck disable=SC2086
"$B/bin/imest-replay" $REPARGS ${REPLAY_ARGS:-} "$CSV" >"$OUT/cases/$NAME.replay.csv" 2>"$OUT/cases/$NAME.log"
# window k = data rows k*N .. k*N+N-1, N = window length in samples (1 s windows)
awk -F, -v name="$NAME" '
  NR == 1 { for (j = 1; j <= NF; j++) col[$j] = j; next }
  NR == 2 { t0 = $1 }
  NR == 3 { N = int(1.0 / ($1 - t0) + 0.5) }
  { r = NR - 2; k = int(r / (N > 0 ? N : 1)); n[k]++;
    tr[k] += $col["T_R_true_s"]; rs[k] += $col["R_S_true_ohm"];
    w[k] += $col["speed_rad_s"]; ld[k] += $col["load_nm"];
    if (k > kmax) kmax = k }
  END { print "seq,tr_true_s,rs_true_ohm,speed_rad_s,load_nm,rows";
        for (k = 0; k <= kmax; k++) if (n[k] == N)
          printf "%d,%.9g,%.9g,%.6g,%.6g,%d\n", k, tr[k]/n[k], rs[k]/n[k], w[k]/n[k], ld[k]/n[k], n[k] }
' "$CSV" >"$OUT/cases/$NAME.truth.csv"
rm -f "$CSV"
