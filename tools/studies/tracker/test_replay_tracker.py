#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""replay-tracker on short synthetic results files (no simulation): what the tracker does with a
wrong verdict and with a loaded stretch without valid windows, checked from the per-window output
(-o) and from the summary line, against the rules that would fail the same checks.

usage: test_replay_tracker.py REPLAY_TRACKER
Exit status: 0 every check passed; 1 a check failed (each listed); 2 usage error.
"""
import csv
import os
import subprocess
import sys
import tempfile

RATE = 1e-3       # the tracker's default rate limit [1/s]
FALLBACK = 2.6e-4 # its default fall-back rate [1/s]: the rotor's cooling
# float32 state: a step may exceed its rate by the rounding of the value (an ulp of 0.1 is 7.5e-9)
SLACK = 2e-7

FAILS = []


def check(cond, what):
    if not cond:
        FAILS.append(what)


def write_results(path, n, truth, nominal):
    """n windows of 1 s, all valid, each 0.01 % off the truth (alternating), bound 0.05 %; the
    first row's trk_T_R_s is the nominal (as imest-demo writes it)."""
    with open(path, "w", encoding="utf-8") as f:
        f.write("experiment,seq,t_end_s,T_R_s,valid,tr_valid,tr_bound_rel,T_R_true_s,trk_T_R_s\n")
        for k in range(n):
            t = k + 1.0
            f.write("syn,%d,%.6f,%.9g,1,1,0.0005,%.9g,%.9g\n"
                    % (k, t, truth(t) * (1.0 + 1e-4 * (1 if k % 2 else -1)), truth(t), nominal))


def replay(exe, src, *opts):
    """(summary dict, per-window rows, exit code, stderr)."""
    with tempfile.NamedTemporaryFile(suffix=".csv", delete=False) as tmp:
        out = tmp.name
    try:
        p = subprocess.run([exe, *opts, "-o", out, src], capture_output=True, text=True, timeout=60)
        summary = dict(kv.split("=", 1) for kv in p.stdout.split()) if p.returncode == 0 else {}
        rows = list(csv.DictReader(open(out, encoding="utf-8"))) if p.returncode == 0 else []
    finally:
        os.unlink(out)
    return summary, rows, p.returncode, p.stderr


def steps(rows, states=None):
    """The largest relative change per second of the used T_R between consecutive rows (in the
    given states only), and the rows' count it was taken over."""
    worst, n = 0.0, 0
    for a, b in zip(rows, rows[1:]):
        if states is not None and b["state"] not in states:
            continue
        ua, ub = float(a["T_R_used_s"]), float(b["T_R_used_s"])
        worst = max(worst, abs(ub - ua) / (ua * (float(b["t_end_s"]) - float(a["t_end_s"]))))
        n += 1
    return worst, n


def wrong_verdicts(exe, d):
    """Every 50th valid window 10 % high, verdict valid: the tracker ignores them and moves no
    faster than its rate limit; every valid window as it is jumps 10 %."""
    src = os.path.join(d, "steady.csv")
    write_results(src, 150, lambda t: 0.1, 0.1)
    s, rows, rc, err = replay(exe, src, "--high-every", "50")
    check(rc == 0, "tracker, wrong verdicts: exit %d (%s)" % (rc, err.strip()))
    if rc != 0:
        return
    check(s["injected_high"] == "3", "injected_high %s, not 3 (150 valid windows, every 50th)" % s["injected_high"])
    high = [r for r in rows if r["injected"] == "high"]
    check(len(high) == 3 and all(abs(float(r["T_R_in_s"]) / 0.1 - 1.10) < 1e-3 for r in high),
          "the injected windows are not 10 %% high: %s" % [r["T_R_in_s"] for r in high])
    worst, n = steps(rows[2:])  # after the acquisition (the second window confirms the first)
    check(n > 100 and worst <= RATE + SLACK,
          "a 10 %%-high valid window moved the tracker by %.3g /s, more than its rate limit %g" % (worst, RATE))
    check(float(s["max_abs_e"]) < 2e-3, "tracker used a wrong verdict: max |e| %s" % s["max_abs_e"])
    check(s["rejected"] == "4", "rejected %s, not 4 (three outliers and the first window)" % s["rejected"])
    r, rows_raw, rc, err = replay(exe, src, "--rule", "raw", "--high-every", "50")
    check(rc == 0 and float(r["max_abs_e"]) > 0.09 and steps(rows_raw)[0] > 0.09,
          "every valid window as it is should take the 10 %% jump (max |e| %s)" % r.get("max_abs_e"))


def loaded_stretch(exe, d):
    """A warm rotor (truth 0.09 s against a cold nominal of 0.12 s) and 300 s without valid
    windows, the load kept: the default fall-back moves the tracker's T_R towards the nominal at
    2.6e-4 /s at most; at the rate limit it moves four times as fast; holding does not move."""
    src = os.path.join(d, "warm.csv")
    write_results(src, 400, lambda t: 0.09, 0.12)
    s, rows, rc, err = replay(exe, src, "--invalid-from", "30", "--invalid-for", "300")
    check(rc == 0, "tracker, loaded stretch: exit %d (%s)" % (rc, err.strip()))
    if rc != 0:
        return
    check(s["fallback_rel_per_s"] == "0.00026", "default fallback_rel_per_s %s, not 2.6e-4" % s["fallback_rel_per_s"])
    check(s["injected_invalid"] == "300", "injected_invalid %s, not 300" % s["injected_invalid"])
    stale = [r for r in rows if r["state"] == "stale"]
    # stale from t = 91 (60 s after the last accepted window, at 30) to 330, and at 331: the first
    # valid window after staleness awaits its confirmation (at 332)
    check(len(stale) == 241, "%d stale windows, not 241 (t = 91 .. 331)" % len(stale))
    worst, n = steps(rows, {"stale"})
    check(n == 241 and FALLBACK * 0.99 < worst <= FALLBACK + SLACK,
          "while stale the tracker moved by %.4g /s at most over %d windows, not the fall-back %g" % (worst, n, FALLBACK))
    check(float(s["max_stale_rate_rel_per_s"]) <= FALLBACK + SLACK,
          "summary max_stale_rate_rel_per_s %s above %g" % (s["max_stale_rate_rel_per_s"], FALLBACK))
    # after 241 s at 2.6e-4 /s: (1 + 2.6e-4)^241 - 1 = 6.5 % above the truth, no more
    drift = (1.0 + FALLBACK) ** 241 - 1.0
    check(abs(float(s["max_abs_e"]) - drift) < 2e-3,
          "max |e| %s, not the fall-back's %.4f" % (s["max_abs_e"], drift))
    # the tracker takes the estimate again when valid windows return: the last window is right
    check(abs(float(rows[-1]["e_rel"])) < 2e-4, "not back on the estimate at the end: e %s" % rows[-1]["e_rel"])

    fast, rows_fast, rc, _ = replay(exe, src, "--invalid-from", "30", "--fallback-rel-per-s", "1e-3")
    check(rc == 0 and steps(rows_fast, {"stale"})[0] > 0.99 * RATE and float(fast["max_abs_e"]) > 0.2,
          "the rate-limit fall-back should move at 1e-3 /s (26 %% in 240 s): max |e| %s" % fast.get("max_abs_e"))
    hold, _, rc, _ = replay(exe, src, "--invalid-from", "30", "--fallback-rel-per-s", "0")
    check(rc == 0 and float(hold["max_abs_e"]) < 2e-4 and hold["stale_windows"] == "241",
          "holding should keep the warm T_R, stale all the same: %s" % hold)


def bad_input(exe, d):
    src = os.path.join(d, "no_truth.csv")
    with open(src, "w", encoding="utf-8") as f:
        f.write("t_end_s,T_R_s,tr_valid,tr_bound_rel\n1,0.1,1,0.001\n")
    _, _, rc, err = replay(exe, src, "--tr-nominal", "0.1")
    check(rc == 1 and "T_R_true_s" in err, "a file without T_R_true_s: exit %d, %r" % (rc, err))
    src = os.path.join(d, "backwards.csv")
    with open(src, "w", encoding="utf-8") as f:
        f.write("t_end_s,T_R_s,tr_valid,tr_bound_rel,T_R_true_s\n2,0.1,1,0.001,0.1\n1,0.1,1,0.001,0.1\n")
    _, _, rc, err = replay(exe, src, "--tr-nominal", "0.1")
    check(rc == 1 and "not after" in err, "time going back: exit %d, %r" % (rc, err))
    _, _, rc, err = replay(exe, src, "--rule", "median")
    check(rc == 2 and "median" in err, "--rule median: exit %d, %r" % (rc, err))


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as d:
        wrong_verdicts(sys.argv[1], d)
        loaded_stretch(sys.argv[1], d)
        bad_input(sys.argv[1], d)
    for f in FAILS:
        print("FAIL " + f)
    print("%d failures" % len(FAILS))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
