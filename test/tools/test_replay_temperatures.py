#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""imest-replay --temperatures (imest_temperature.h): a heat run from imest-sim (exp2, ideal V/f,
heating sped up 100 times) replayed with and without it. The existing columns keep their names,
order and values (other tools read them by position); seven columns follow; the rotor's
temperature, where valid, is within 5 K of the simulator's (the window's mean), and the stator's
within 3 K wherever R_S is valid (the default tolerance aside: the estimator's R_S bound is wider
than its error); the stated uncertainties cover the errors; bad references are usage errors.

usage: test_replay_temperatures.py REPLAY_BIN SIM_BIN
Exit status: 0 pass; 1 a check failed (each named); 2 usage error.
"""
import csv
import os
import subprocess
import sys
import tempfile

NEW = ["stator_c", "stator_uncert_k", "stator_valid", "rr_ohm", "rotor_c", "rotor_uncert_k", "rotor_valid"]
FAILS = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAILS.append(what)


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    replay, sim = sys.argv[1:3]
    motor = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0", "--sigma-uncertainty", "0", "--quiet"]
    with tempfile.TemporaryDirectory() as d:
        rec = os.path.join(d, "sim.csv")
        subprocess.run([sim, "--preset", "exp2", "--duration", "20", "--supply", "vf", "--seed", "5",
                        "--thermal-speedup", "100", "-o", rec], check=True, capture_output=True, timeout=120)
        plain = subprocess.run([replay, *motor, rec], check=True, capture_output=True, text=True).stdout
        # the simulator's references: cold R_S 5.04 ohm and T_R 0.12 s at --t-amb 22 degC
        p = subprocess.run([replay, *motor, "--temperatures", "22,5.04,0.12", rec], capture_output=True,
                           text=True)
        check(p.returncode == 0, "--temperatures: exit 0 (%d: %s)" % (p.returncode, p.stderr.strip()))
        a = [line.split(",") for line in plain.splitlines()]
        b = [line.split(",") for line in p.stdout.splitlines()]
        check(len(a) == len(b) and len(a) > 15, "as many rows (%d, %d)" % (len(a), len(b)))
        n = len(a[0])
        check(b[0][:n] == a[0] and b[0][n:] == NEW, "the header: the existing columns, then %s" % ",".join(NEW))
        check(all(x == y[:n] for x, y in zip(a, b)), "the existing columns' values unchanged")
        with open(rec) as f:
            truth = list(csv.DictReader(f))
        rows = [dict(zip(b[0], r)) for r in b[1:]]
        n_rot = n_st = 0
        for r in rows:
            t1 = float(r["t_end_s"])
            win = [x for x in truth if t1 - 1.0 < float(x["t"]) <= t1]
            ts = sum(float(x["temp_stator_c"]) for x in win) / len(win)
            tr = sum(float(x["temp_rotor_c"]) for x in win) / len(win)
            if r["rotor_valid"] == "1":
                n_rot += 1
                e = float(r["rotor_c"]) - tr
                check(abs(e) <= 5.0, "window at %s s: rotor %.2f degC, simulator %.2f" % (r["t_end_s"],
                                                                                     float(r["rotor_c"]), tr))
                check(abs(e) <= float(r["rotor_uncert_k"]), "  its error %.2f K within the stated %s K"
                      % (e, r["rotor_uncert_k"]))
                check(r["tr_valid"] == "1", "  and tr_valid")
            if r["rs_valid"] == "1":
                n_st += 1
                e = float(r["stator_c"]) - ts
                check(abs(e) <= 3.0, "window at %s s: stator %.2f degC, simulator %.2f" % (r["t_end_s"],
                                                                                      float(r["stator_c"]), ts))
                check(abs(e) <= float(r["stator_uncert_k"]), "  its error %.2f K within the stated %s K"
                      % (e, r["stator_uncert_k"]))
            if r["stator_valid"] == "1":
                check(float(r["stator_uncert_k"]) <= 3.0, "  stator_valid within 3 K")
        check(n_rot >= 10, "%d windows with a valid rotor temperature" % n_rot)
        check(n_st >= 10, "%d windows with R_S valid" % n_st)
        check(float(rows[-1]["rotor_c"]) > 60.0, "the rotor heated (%s degC at the end)" % rows[-1]["rotor_c"])
        for bad in ("22,5.04", "22,0,0.12", "22,5.04,abc"):
            q = subprocess.run([replay, *motor, "--temperatures", bad, rec], capture_output=True, text=True)
            check(q.returncode == 2 and "--temperatures" in q.stderr, "--temperatures %s: exit 2 (%d)"
                  % (bad, q.returncode))
    print("%d failures" % len(FAILS))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
