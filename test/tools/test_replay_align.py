#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""imest-replay's alignment check (docs/feeding-logs.md, section 3, alignment check).

Records from imest-sim over a range of operating points (a V/f ramp), correctly aligned and with
the voltage columns shifted one row early (row k holds row k+1's) and one row late (row k holds
row k-1's): the aligned record gives no note, each shifted one a note naming its direction and the
option that fixes it; for the duty-cycle input (duties and v_dc shifted) and for measured phase
voltages. The check changes nothing: the windows' CSV is the same with --no-align-check, which
also silences it. A record at one operating point gives no note, shifted or not: there a one-row
shift cannot be told from a different R_S.

usage: test_replay_align.py REPLAY SIM
Exit status: 0 every check passed; 1 a check failed (each listed); 2 usage error.
"""
import os
import subprocess
import sys
import tempfile

FAILS = []


def check(cond, what, detail=""):
    if not cond:
        FAILS.append(what + ("\n    " + detail[:1500] if detail else ""))


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def simulate(sim, d, name, args, cols):
    """imest-sim ARGS; the columns COLS (by name) into d/name.csv; returns the rows."""
    path = os.path.join(d, name + ".sim.csv")
    rc, _, err = run([sim] + args + ["--no-progress", "--out", path])
    if rc != 0:
        sys.exit("imest-sim failed: " + err)
    with open(path) as f:
        head = f.readline().strip().split(",")
        at = [head.index(c) for c in cols]
        rows = [[x[k] for k in at] for x in (line.strip().split(",") for line in f) if x != [""]]
    os.remove(path)
    return rows


def write(d, name, header, rows, voltage_cols, shift):
    """Row k with row k+shift's voltage columns (the rows without one are left out)."""
    path = os.path.join(d, name + ".csv")
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for k in range(len(rows)):
            j = k + shift
            if 0 <= j < len(rows):
                r = list(rows[k])
                for c in voltage_cols:
                    r[c] = rows[j][c]
                f.write(",".join(r) + "\n")
    return path


def notes(replay, args, path):
    rc, out, err = run([replay] + args + [path])
    check(rc == 0, f"imest-replay {path} exits 0", err)
    return out, [line for line in err.splitlines() if "alignment" in line]


def case(replay, d, label, header, rows, vcols, args, fix_early, fix_late):
    aligned = write(d, label + "0", header, rows, vcols, 0)
    out, n = notes(replay, args, aligned)
    check(n == [], f"{label}: an aligned record gives no alignment note", "\n".join(n))
    out_off, n_off = notes(replay, args + ["--no-align-check"], aligned)
    check(out == out_off, f"{label}: the windows' CSV is the same with --no-align-check")
    for shift, word, fix in ((1, "early", fix_early), (-1, "late", fix_late)):
        path = write(d, f"{label}{word}", header, rows, vcols, shift)
        out, n = notes(replay, args, path)
        ok = len(n) == 1 and f"one row {word}" in n[0] and fix in n[0]
        check(ok, f"{label}: the voltage one row {word} is noted, with '{fix}'", "\n".join(n))
        out_off, n_off = notes(replay, args + ["--no-align-check"], path)
        check(n_off == [], f"{label} {word}: --no-align-check gives no note", "\n".join(n_off))
        check(out == out_off, f"{label} {word}: the windows' CSV does not depend on the check")


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    replay, sim = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as d:
        # duty input: the 4 kW drive (8 kHz, firmware timing, 2 us dead time), V/f ramp to
        # 50 Hz over 30 s under a light load
        duty = ["t", "d_a", "d_b", "d_c", "v_dc", "i_a", "i_b", "i_c", "theta"]
        ramp = ["--preset", "4kw", "--start", "rest", "--vf-ramp", "30", "--vf-boost", "8",
                "--load-nm", "10", "--load-on", "3", "--load-ramp", "5", "--duration", "32",
                "--dead-time", "2e-6"]
        rows = simulate(sim, d, "duty", ramp, duty)
        m4 = ["--pole-pairs", "2", "--ls", "0.178039", "--sigma", "0.064463", "--ls-uncertainty", "0", "--sigma-uncertainty", "0", "--from-rest", "no"]
        case(replay, d, "duty", duty, rows, [1, 2, 3, 4], m4 + ["--voltage", "duty", "--dead-time", "2e-6"],
             "--u-delay -0.000125", "--pwm-timing last")
        # measured phase voltages: the paper's motor on an ideal V/f source (4 kHz), ramp to 60 Hz
        phase = ["t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta"]
        rows = simulate(sim, d, "phase", ["--preset", "exp2", "--vf-ramp", "20", "--freq", "60",
                                          "--vll", "230", "--vf-boost", "10", "--load-on", "0",
                                          "--load-ramp", "3", "--load-nm", "1.5", "--duration", "24",
                                          "--no-thermal"], phase)
        mp = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0", "--sigma-uncertainty", "0", "--from-rest", "no"]
        case(replay, d, "phase", phase, rows, [1, 2, 3], mp, "--u-delay -0.00025", "--u-delay 0.00025")
        # one operating point (the 4 kW drive steady at rated load): nothing to tell, no note
        rows = simulate(sim, d, "steady", ["--preset", "4kw", "--duration", "6"], duty)
        for shift in (0, -1):
            path = write(d, f"steady{shift}", duty, rows, [1, 2, 3, 4], shift)
            _, n = notes(replay, m4 + ["--voltage", "duty"], path)
            check(n == [], f"steady, shift {shift}: no note at one operating point", "\n".join(n))
    for f in FAILS:
        print("FAIL:", f)
    print(f"test_replay_align: {len(FAILS)} failure(s)")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
