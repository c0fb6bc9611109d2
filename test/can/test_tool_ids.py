#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""One identifier option for every tool: imest-replay and imest-monitor both
take --can-base-id ID and --can-ext (their older spellings --can-id, and
--base-id / --ext, still work), with the same spellings of the identifier (a
29-bit identifier above 0x7FF without any flag, --can-ext for small 29-bit
ones, the old CAN_EFF_FLAG form), and refuse the same out-of-range ones with
the same message and exit code 2. What replay publishes (through the
application-side publisher) decodes with the monitor, whose CSV has replay's
column names in replay's order, with the same values (float32 on the bus).
replay's --candump-iface labels the log; its old --can-iface is refused.

usage: test_tool_ids.py REPLAY MONITOR WORKDIR
"""
import math
import os
import subprocess
import sys

replay, monitor, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
fails = []


def check(cond, msg):
    if not cond:
        fails.append(msg)


# a short balanced 3-phase recording (2 windows of 1 s at 4 kHz): loaded motor at 30 Hz
rec = os.path.join(work, "ids_rec.csv")
with open(rec, "w") as f:
    f.write("t,u_a,u_b,u_c,i_a,i_b,i_c,theta\n")
    w = 2 * math.pi * 30
    for k in range(8000):
        t = k / 4000
        u = [150 * math.cos(w * t - p) for p in (0, 2 * math.pi / 3, 4 * math.pi / 3)]
        i = [8 * math.cos(w * t - 0.6 - p) for p in (0, 2 * math.pi / 3, 4 * math.pi / 3)]
        f.write("%.6f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.6f\n" % (t, *u, *i, 0.97 * w * t / 2))

MOTOR = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0", "--sigma-uncertainty", "0", "--quiet"]
log = os.path.join(work, "ids.log")


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


for args, first_id, monitor_args in (
        (["--can-base-id", "0x18FF5000"], "18FF5000", ["--can-base-id", "0x18FF5000"]),
        (["--can-base-id", "0x98FF5000"], "18FF5000", ["--can-base-id", "0x18FF5000"]),
        (["--can-base-id", "0x100", "--can-ext"], "00000100", ["--can-base-id", "0x100", "--can-ext"]),
        (["--can-id", "0x100", "--can-ext"], "00000100", ["--base-id", "0x100", "--ext"]),  # older spellings
        (["--can-base-id", "1696"], "6A0", []),
        ([], "6A0", [])):
    rc, out, err = run([replay] + MOTOR + ["--candump", log] + args + [rec])
    check(rc == 0, f"replay {args}: rc {rc} {err}")
    windows = len(out.splitlines()) - 1
    with open(log) as fh:
        lines = fh.read().splitlines()
    check(len(lines) == 6 * windows and windows == 2, f"replay {args}: {len(lines)} frames, {windows} windows")
    check(lines and lines[0].split()[2].startswith(first_id + "#"), f"replay {args}: first frame {lines[:1]}")
    rc, out, err = run([monitor, "--log", log, "--csv"] + monitor_args)
    check(rc == 0 and len(out.splitlines()) == 1 + windows and "lost 0," in err,
          f"monitor {monitor_args} on replay {args}: rc {rc} {err}")

# the monitor's CSV: replay's names, in replay's order, the same values
rc, rep_out, err = run([replay] + MOTOR + ["--candump", log, "--candump-iface", "can9", rec])
with open(log) as fh:
    check(" can9 " in fh.readline(), "--candump-iface labels the log")
rc, mon_out, err = run([monitor, "--log", log, "--csv"])
rep_cols, mon_cols = rep_out.splitlines()[0].split(","), mon_out.splitlines()[0].split(",")
shared = [c for c in mon_cols if c in rep_cols]
check(shared == [c for c in rep_cols if c in mon_cols], f"shared columns in replay's order: {shared}")
check(mon_cols[0] == "t_s" and mon_cols[1:len(shared) + 1] == shared,
      f"the monitor: t_s, the shared columns, then its own: {mon_cols}")
check(len(shared) >= 18, f"shared columns: {shared}")
for rl, ml in zip(rep_out.splitlines()[1:], mon_out.splitlines()[1:]):
    r, m = dict(zip(rep_cols, rl.split(","))), dict(zip(mon_cols, ml.split(",")))
    check(abs(float(m["t_s"]) - float(r["t_end_s"])) < 1e-6, f"t_s {m['t_s']} vs t_end_s {r['t_end_s']}")
    for c in shared:
        if c in ("status", "tr_reason", "rs_reason", "valid", "tr_valid", "rs_valid", "seq", "n_roots",
                 "n_admissible", "windows", "flags"):
            check(m[c] == r[c], f"{c}: monitor {m[c]!r} replay {r[c]!r}")
        elif not m["clamped"]:
            a, b = float(m[c]), float(r[c])
            # float32 on the bus, or the field's step (tools/imest.dbc) and the printed digits
            step = {"E_I": 1e-4, "span_s": 1e-3}.get(c, 0.0 if c in ("T_R_s", "R_S_ohm") else 2e-5)
            check(a == b or (math.isnan(a) and math.isnan(b)) or abs(a - b) <= max(step, 1e-6 * abs(b)),
                  f"{c}: monitor {m[c]} replay {r[c]}")
# --require-valid: exit 3 when no window has the column at 1, 0 otherwise; without it 0
short = os.path.join(work, "ids_short.csv")
with open(rec) as fh, open(short, "w") as out_f:
    out_f.writelines(fh.readlines()[:4001])  # one window, started mid-run: warmup, not valid
for which, col in (("", "valid"), ("=tr", "tr_valid"), ("=rs", "rs_valid")):
    rc, out, err = run([replay] + MOTOR + ["--from-rest", "no", "--require-valid" + which, short])
    check(rc == 3 and len(out.splitlines()) == 2 and f"none of the 1 window(s) has {col} = 1" in err,
          f"replay --require-valid{which} on a warm-up window: rc {rc} {err}")
rc, out, err = run([replay] + MOTOR + ["--from-rest", "no", short])
check(rc == 0, f"replay without --require-valid, no window valid: rc {rc} {err}")
rc, out, err = run([replay] + MOTOR + ["--require-valid=both", short])
check(rc == 2 and "takes valid, tr or rs" in err, f"replay --require-valid=both: rc {rc} {err}")
valid_any = any(line.split(",")[4] == "1" for line in rep_out.splitlines()[1:])
rc, out, err = run([replay] + MOTOR + ["--require-valid", rec])
check(rc == (0 if valid_any else 3), f"replay --require-valid on {rec}: rc {rc} {err}")

rc, out, err = run([replay] + MOTOR + ["--candump", log, "--can-iface", "vcan0", rec])
check(rc == 2 and "--can-iface is now --candump-iface" in err and out == "", f"replay --can-iface: rc {rc} {err}")

for bad, want in (("0x7FB", "beyond the 11-bit range (largest base 0x7FA); use a lower base, or --can-ext"),
                  ("0x20000000", "beyond the 29-bit range"),
                  ("zz", "not an identifier"),
                  ("-1", "negative")):
    rc, out, err = run([replay] + MOTOR + ["--candump", log, "--can-base-id", bad, rec])
    check(rc == 2 and want in err and out == "", f"replay --can-base-id {bad}: rc {rc} {err}")
    rc, out, err = run([monitor, "--log", log, "--can-base-id", bad])
    check(rc == 2 and want in err, f"monitor --can-base-id {bad}: rc {rc} {err}")

if fails:
    print("\n".join(fails))
    print(f"FAILED: {len(fails)} check(s)")
    sys.exit(1)
print("imest-replay and imest-monitor --can-base-id, shared columns: all checks passed")
