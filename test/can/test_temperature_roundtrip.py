#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""IMEST_TEMP end to end: imest-replay --temperatures --candump writes each window's six frames and
its IMEST_TEMP (base + 6), and imest-monitor --temperatures shows the same temperatures as replay's
CSV, within the frame's resolution (0.01 degC, 0.2 K; values beyond the fields' ranges as their
ends, named in 'clamped'), on a heat run from imest-sim (exp2, heating sped up 100 times) with two
sets of references (the second makes the temperatures negative), 11- and 29-bit identifiers.
Without --temperatures the replay's log and the monitor's CSV are what they were; a window whose
IMEST_TEMP is missing or corrupted shows empty temperature cells; an IMEST_TEMP that comes before
its window's frames is matched all the same; a log of IMEST_TEMP frames alone decodes nothing,
and the monitor says so.

usage: test_temperature_roundtrip.py REPLAY SIM MONITOR WORKDIR
Exit status: 0 pass; 1 a check failed (each named); 2 usage error.
"""
import csv
import math
import os
import subprocess
import sys

TEMP_COLS = ["stator_c", "stator_uncert_k", "stator_valid", "rotor_c", "rotor_uncert_k", "rotor_valid"]
MOTOR = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0",
         "--sigma-uncertainty", "0", "--quiet"]  # the simulator's own constants: exact
FAILS = []


def check(cond, what):
    if not cond:
        print("FAIL " + what)
        FAILS.append(what)


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def rows(text):
    return list(csv.DictReader(text.splitlines()))


def close(mon, rep, step, limit, col, k):
    """The monitor's cell against replay's: nan for nan; a value beyond the field at its end and
    named in 'clamped'; else within half a step (and the float32 / printing rounding)."""
    m, r = mon[col], float(rep[col])
    if math.isnan(r):
        check(m == "nan", f"window {k}: {col} replay nan, monitor {m!r}")
        return
    clamped = col in mon["clamped"].split(";")
    if abs(r) >= limit - step / 2:
        check(clamped and float(m) == math.copysign(limit, r),
              f"window {k}: {col} replay {r} beyond the field: monitor {m!r}, clamped {mon['clamped']!r}")
        return
    check(not clamped, f"window {k}: {col} {m} named in clamped {mon['clamped']!r}")
    check(abs(float(m) - r) <= step / 2 + 1e-4, f"window {k}: {col} replay {r}, monitor {m}")


def compare(mon_rows, rep_rows, what):
    check(len(mon_rows) == len(rep_rows) and len(rep_rows) >= 15,
          f"{what}: {len(mon_rows)} monitor rows, {len(rep_rows)} replay rows")
    for k, (m, r) in enumerate(zip(mon_rows, rep_rows)):
        check(m["t_s"] == r["t_end_s"] and m["seq"] == r["seq"], f"{what} window {k}: t_s / seq")
        check(m["frames"] == "0x7f", f"{what} window {k}: frames {m['frames']}")
        close(m, r, 0.01, 327.67, "stator_c", k)
        close(m, r, 0.01, 327.67, "rotor_c", k)
        close(m, r, 0.2, 25.2, "stator_uncert_k", k)
        close(m, r, 0.2, 25.2, "rotor_uncert_k", k)
        for col in ("stator_valid", "rotor_valid"):
            check(m[col] == r[col], f"{what} window {k}: {col} monitor {m[col]} replay {r[col]}")


def main():
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    replay, sim, monitor, work = sys.argv[1:5]
    os.makedirs(work, exist_ok=True)
    rec = os.path.join(work, "temp_heat.csv")
    subprocess.run([sim, "--preset", "exp2", "--duration", "20", "--supply", "vf", "--seed", "5",
                    "--thermal-speedup", "100", "-o", rec], check=True, capture_output=True, timeout=300)
    log = os.path.join(work, "temp_rt.log")
    plain_log = os.path.join(work, "temp_rt_plain.log")

    # the simulator's references (cold R_S 5.04 ohm, T_R 0.12 s at 22 degC), then references that
    # put the motor below the reference temperature: negative temperatures
    for refs, base, negative in (("22,5.04,0.12", [], False), ("22,7.0,0.16", [], True),
                                 ("22,5.04,0.12", ["--can-base-id", "0x18FF5000"], False)):
        what = f"--temperatures {refs} {' '.join(base)}".strip()
        rc, rep_out, err = run([replay, *MOTOR, "--temperatures", refs, "--candump", log, *base, rec])
        check(rc == 0, f"{what}: replay exit {rc}: {err.strip()}")
        with open(log) as fh:
            lines = fh.readlines()
        temp_id = "18FF5006#" if base else " 6A6#"
        n_temp = sum(temp_id in line for line in lines)
        rep_rows = rows(rep_out)
        check(n_temp == len(rep_rows) and len(lines) == 7 * len(rep_rows),
              f"{what}: {n_temp} IMEST_TEMP frames in {len(lines)} lines for {len(rep_rows)} windows")
        # each IMEST_TEMP follows its window's six frames
        check(all(temp_id in lines[7 * k + 6] for k in range(len(rep_rows))), f"{what}: frame order")
        rc, mon_out, err = run([monitor, "--log", log, "--csv", "--temperatures", *base])
        check(rc == 0, f"{what}: monitor exit {rc}: {err.strip()}")
        mon_rows = rows(mon_out)
        compare(mon_rows, rep_rows, what)
        stator = [float(r["stator_c"]) for r in mon_rows if r["stator_c"] != "nan"]
        median = sorted(stator)[len(stator) // 2] if stator else math.nan
        check((median < -5.0) == negative and (median > 15.0) != negative,
              f"{what}: stator temperatures' median {median}")
        check(any(r["rotor_valid"] == "1" for r in mon_rows) or negative, f"{what}: a valid rotor temperature")
        header = mon_out.splitlines()[0].split(",")
        i = header.index("rs_bound_rel")
        check(header[i + 1:i + 7] == TEMP_COLS and header[i + 7] == "clamped",
              f"{what}: the temperature columns after rs_bound_rel: {header}")
        if base:
            continue

        # without --temperatures: the six frames' log and the monitor's CSV as before
        rc, _, err = run([replay, *MOTOR, "--candump", plain_log, rec])
        with open(plain_log) as fh:
            plain = fh.readlines()
        check(rc == 0 and plain == [x for x in lines if temp_id not in x],
              f"{what}: the log without --temperatures is the same six frames per window")
        a = run([monitor, "--log", log, "--csv"])
        b = run([monitor, "--log", plain_log, "--csv"])
        check(a[0] == 0 and a[1] == b[1], f"{what}: monitor CSV without --temperatures byte-identical")
        check("--temperatures shows them" in a[2], f"{what}: the monitor says IMEST_TEMP came: {a[2]}")
        check("IMEST_TEMP" not in b[2], f"{what}: no IMEST_TEMP note on a log without it: {b[2]}")
        table = run([monitor, "--log", log, "--temperatures"])
        check(table[0] == 0 and "stator[C]" in table[1].splitlines()[0]
              and len(table[1].splitlines()) == len(rep_rows) + 1, f"{what}: table with temperatures")

        # one IMEST_TEMP lost, one corrupted, one before its window's frames
        edited = list(lines)
        del edited[7 * 2 + 6]                                   # window 2's IMEST_TEMP lost
        j = 7 * 4 + 6 - 1                                       # window 4's, after the deletion
        head, data = edited[j].rstrip("\n").split("#")
        edited[j] = head + "#" + data[:2] + ("00" if data[2:4] != "00" else "01") + data[4:] + "\n"
        j = 7 * 6 + 6 - 1                                       # window 6's, moved before its window
        edited.insert(7 * 6 - 1, edited.pop(j))
        path = os.path.join(work, "temp_rt_edited.log")
        with open(path, "w") as fh:
            fh.writelines(edited)
        rc, out, err = run([monitor, "--log", path, "--csv", "--temperatures"])
        ed = rows(out)
        check(rc == 0 and len(ed) == len(mon_rows), f"edited log: {len(ed)} rows: {err.strip()}")
        for k, (e, m) in enumerate(zip(ed, mon_rows)):
            if k in (2, 4):
                check(all(e[c] == "" for c in TEMP_COLS) and e["frames"] == "0x3f",
                      f"edited log, window {k}: no IMEST_TEMP: {[e[c] for c in TEMP_COLS]} {e['frames']}")
                check({c: e[c] for c in e if c not in TEMP_COLS + ["frames", "clamped"]}
                      == {c: m[c] for c in m if c not in TEMP_COLS + ["frames", "clamped"]},
                      f"edited log, window {k}: the six frames' columns unchanged")
            else:
                check(e == m, f"edited log, window {k}: as without the edits: {e} vs {m}")
        check("corrupted frame 0x6A6 (IMEST_TEMP): checksum mismatch" in err,
              f"edited log: the corrupted IMEST_TEMP reported: {err}")
        check("IMEST_TEMP frames %d (corrupted 1, without their window 0)" % (len(rep_rows) - 2) in err,
              f"edited log: the summary: {err}")
        only = os.path.join(work, "temp_rt_only.log")
        with open(only, "w") as fh:
            fh.writelines(x for x in lines if temp_id in x)
        rc, out, err = run([monitor, "--log", only, "--csv", "--temperatures"])
        check(rc == 1 and "IMEST_TEMP frame(s) at 0x6A0+6, but none of the six frames 0x6A0..0x6A5" in err,
              f"a log of IMEST_TEMP frames only: exit {rc}, {err}")
        rc, out, err = run([monitor, "--log", log, "--csv", "--temperatures", "--count", "3"])
        check(rc == 0 and rows(out) == mon_rows[:3], "--count 3 with --temperatures: the first three rows")
    if FAILS:
        print(f"FAILED: {len(FAILS)} check(s)")
        return 1
    print("IMEST_TEMP round trip: replay's temperatures decoded by the monitor within the frame's resolution")
    return 0


if __name__ == "__main__":
    sys.exit(main())
