#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# CTest smoke test of the main job (label demo): 60 s of motor time through the
# whole chain into a temporary folder; checks that the files exist, that every
# window went over the CAN log and that summary.md parses.
# Usage: smoke-test.sh WORKDIR  (IMEST_DEMO_BIN and IMEST_MONITOR_BIN set by CTest)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
work=${1:?usage: smoke-test.sh WORKDIR}
rm -rf "$work"
mkdir -p "$work"
out="$work/results"

"$here/tools/demo-run" --no-setup --no-build --quiet --out "$out" --duration 60 >"$work/stdout.txt"

fail() { echo "demo smoke test: $*" >&2; exit 1; }
for f in windows.csv exp1_windows.csv ifoc_fixed_windows.csv ifoc_adaptive_windows.csv \
         exp2_avg30.csv exp2_avg120.csv summary.md \
         fig02_exp1_voltages.png fig03_exp1_current.png fig04_exp1_speed.png \
         fig05_tr_1s.png fig06_tr_30s.png fig07_tr_120s.png \
         fig08_rs_1s.png fig09_rs_30s.png fig10_rs_120s.png fig11_ifoc_closed_loop.png \
         fig12_ifoc_11kw.png fig13_verdicts.png fig15_temperatures.png ifoc11_fixed_windows.csv ifoc11_adaptive_windows.csv \
         fig14_duty_4kw.png duty4kw_windows.csv raw/duty4kw_commission.csv raw/duty4kw_true_constants.csv \
         raw/exp2.candump.log raw/exp2_monitor.csv; do
  [ -s "$out/$f" ] || fail "missing or empty: $f"
done

/usr/bin/python3 - "$out" <<'EOF'
import csv, re, sys
out = sys.argv[1]
need = ["t_end_s", "T_R_s", "R_S_ohm", "valid", "status", "T_R_true_s", "R_S_true_ohm",
        "tr_valid", "tr_reason", "rs_valid", "rs_reason"]
rows = list(csv.DictReader(open(f"{out}/windows.csv")))
assert len(rows) == 60, f"windows.csv: {len(rows)} rows, expected 60"
for k in need:
    assert k in rows[0], f"windows.csv: no column {k}"
assert all(r["via_can"] == "1" for r in rows), "a window did not come through the CAN log"
for r in rows:
    assert abs(float(r["R_S_true_ohm"]) - 5.04) < 0.2, r
    assert abs(float(r["T_R_true_s"]) - 0.12) < 0.01, r
md = open(f"{out}/summary.md").read()
# error table: one row per experiment and averaging level, numbers in every cell
# (a statistic without a valid window names the most common reasons instead, the rest of its cells "–")
runs = "exp1|exp2|ifoc_fixed|ifoc_adaptive|ifoc11_fixed|ifoc11_adaptive|duty4kw"
rows = re.findall(r"^\| (" + runs + r") \| (1 s|30 s avg|120 s avg) \|(.*)\|$", md, re.M)
for need_run in ("exp2", "ifoc11_fixed", "duty4kw"):
    assert (need_run, "1 s") in [(a, b) for a, b, _ in rows], f"summary: no {need_run} 1-s row"
for a, b, rest in rows:
    cells = [c.strip() for c in rest.split("|")]
    assert len(cells) == 8, f"summary: error row {a} {b}: {len(cells)} cells"
    for n_at in (0, 4):  # n for T_R, n for R_S, then mean, max, bias
        n, stats = int(cells[n_at]), cells[n_at + 1:n_at + 4]
        if n == 0:
            assert re.match(r"no valid window: \d+/\d+ [a-z_]+", stats[0]), f"summary: {a} {b}: {stats[0]!r}"
            assert stats[1:] == ["–", "–"], f"summary: {a} {b}: {stats}"
        else:
            for c in stats:
                float(c)
# no cell of any table (and no word of the text) is "nan"
for line in md.splitlines():
    if line.startswith("|"):
        for c in line.strip("|").split("|"):
            assert not re.search(r"\bnan\b", c, re.I), f"summary: a cell is nan: {line}"
assert not re.search(r"\bnan\b", md, re.I), "summary: 'nan' in the text"
# the duty-cycle run: commissioning's inverter model and the estimation rows
assert "## Without voltage sensors: the duty-cycle input (4 kW drive)" in md, "summary: no duty-cycle section"
for label in ("inverter: dead time", "inverter: device drops (V_sw0 + V_d0) / 2", "inverter: slopes r_sw - r_d",
              "inverter: the model's stated uncertainty"):
    assert re.search(r"^\| " + re.escape(label) + r" \| [0-9.]+ ", md, re.M), f"summary: no row '{label}'"
for par in ("T_R", "R_S"):
    m = re.search(r"^\| identified constants \| " + par + r" \| (\d+) / (\d+) \| ([0-9.]+) % \| ([^|]*) \|", md, re.M)
    assert m, f"summary: no duty-cycle row for {par}"
    assert int(m.group(2)) == 10, f"duty4kw: {m.group(2)} windows, expected 10 (60 s / 6)"
    assert abs(100 * int(m.group(1)) / int(m.group(2)) - float(m.group(3))) < 0.06, m.group(0)
duty = list(csv.DictReader(open(f"{out}/duty4kw_windows.csv")))
assert all(r["via_can"] == "1" for r in duty), "duty4kw: a window did not come through the CAN log"
# the operating point was chosen where the product works: T_R valid after the warm-up, within 1 %
tr_ok = [r for r in duty if r["tr_valid"] == "1"]
assert len(tr_ok) >= 8, f"duty4kw: only {len(tr_ok)} of 10 windows have a valid T_R"
assert all(abs(float(r["T_R_err_pct"])) < 1.0 for r in tr_ok), "duty4kw: a valid T_R is more than 1 % off"
tel = re.search(r"^\| exp2 \| (\d+) \| (\d+) \| [^|]* \| [^|]* \| (\d+) \| (\d+) \|", md, re.M)
assert tel, "summary: no exp2 telemetry row"
assert int(tel.group(1)) == 60 and int(tel.group(3)) == 60, tel.group(0)
assert int(tel.group(4)) == 0, "lost frames in a local log"
assert re.search(r"^\| total \| [0-9.]+ \|$", md, re.M), "summary: no total wall time"
# a window that is not valid: its estimate never appears in the summary (only its verdict)
for name in ("exp1_windows.csv", "windows.csv"):
    for r in csv.DictReader(open(f"{out}/{name}")):
        if r["valid"] != "1":
            for key, fmt in (("R_S_ohm", "%.5g"), ("R_S_ohm", "%.4f"), ("T_R_s", "%.5g"), ("T_R_s", "%.5f")):
                txt = fmt % float(r[key])
                assert txt not in md, f"summary prints {name} window {r['seq']}'s {key} {txt}"
# the adaptive runs' controller uses the T_R tracker's output (imest_tracker.h) from the next window on
# (ifoc_T_R_s is the window's mean, written with 6 digits)
for name in ("ifoc_adaptive_windows.csv", "ifoc11_adaptive_windows.csv"):
    rows = list(csv.DictReader(open(f"{out}/{name}")))
    for k in ("trk_T_R_s", "trk_state", "trk_age_s", "trk_bound_rel", "tr_bound_rel"):
        assert k in rows[0], f"{name}: no column {k}"
    assert {r["trk_state"] for r in rows} <= {"nominal", "tracking", "holding", "stale"}, name
    assert rows[-1]["trk_state"] == "tracking", f"{name}: the tracker is not tracking at the end"
    for a, b in zip(rows, rows[1:]):
        used, trk = float(b["ifoc_T_R_s"]), float(a["trk_T_R_s"])
        assert abs(used / trk - 1) < 1e-5, f"{name} window {b['seq']}: controller T_R {used}, tracker {trk}"
for sec in ("## R_S and the encoder", "Why the fixed-T_R torque error changes sign"):
    assert sec in md, f"summary: no '{sec}'"
# the heat run's temperatures (imest_temperature.h): columns, figure, and the summary's table
rows = list(csv.DictReader(open(f"{out}/windows.csv")))
for k in ("est_stator_c", "est_stator_uncert_k", "est_stator_valid", "est_rotor_c", "est_rotor_uncert_k",
          "est_rotor_valid"):
    assert k in rows[0], f"windows.csv: no column {k}"
trows = dict(re.findall(r"^\| (stator|rotor) \| (\d+) / 60 \|", md, re.M))
assert set(trows) == {"stator", "rotor"}, "summary: no temperature rows"
rot = re.search(r"^\| rotor \| (\d+) / 60 \| ([0-9.]+) \| ([0-9.]+) \|", md, re.M)
assert rot and int(rot.group(1)) > 0 and float(rot.group(3)) <= 5.0, f"summary: rotor temperature {rot}"
print("demo smoke test: ok")
EOF
