#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""One identifier parser for every tool: imest-replay --can-id and
imest-monitor --base-id take the same spellings (a 29-bit identifier above
0x7FF without any flag, --can-ext / --ext for small 29-bit ones, the old
CAN_EFF_FLAG form) and refuse the same out-of-range ones with a message and
exit code 2. What replay publishes (through the application-side publisher)
decodes with the monitor.

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

MOTOR = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--quiet"]
log = os.path.join(work, "ids.log")


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


for args, first_id, monitor_args in (
        (["--can-id", "0x18FF5000"], "18FF5000", ["--base-id", "0x18FF5000"]),
        (["--can-id", "0x98FF5000"], "18FF5000", ["--base-id", "0x18FF5000"]),
        (["--can-id", "0x100", "--can-ext"], "00000100", ["--base-id", "0x100", "--ext"]),
        (["--can-id", "1696"], "6A0", []),
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

for bad, want in (("0x7FB", "beyond the 11-bit range (largest base 0x7FA); use a lower base, or --can-ext"),
                  ("0x20000000", "beyond the 29-bit range"),
                  ("zz", "not an identifier"),
                  ("-1", "negative")):
    rc, out, err = run([replay] + MOTOR + ["--candump", log, "--can-id", bad, rec])
    check(rc == 2 and want in err and out == "", f"replay --can-id {bad}: rc {rc} {err}")
    rc, out, err = run([monitor, "--log", log, "--base-id", bad])
    check(rc == 2 and want.replace("--can-ext", "--ext") in err, f"monitor --base-id {bad}: rc {rc} {err}")

if fails:
    print("\n".join(fails))
    print(f"FAILED: {len(fails)} check(s)")
    sys.exit(1)
print("imest-replay --can-id and imest-monitor --base-id: all checks passed")
