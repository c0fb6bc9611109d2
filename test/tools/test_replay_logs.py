#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""imest-replay reads what drives log, without edits (docs/feeding-logs.md, section 1.1).

One canonical recording from imest-sim (t,u_a,u_b,u_c,i_a,i_b,i_c,theta; i_c written as
-i_a - i_b and the voltages as the phase-to-neutral set of their line-to-line values, so that
the derived columns are bit for bit what the reader computes), then variants of its header and
layout: each must give the SAME window rows. A gap with --gaps restart gives the canonical
rows up to the gap and a restart after it; the refusals quote what was read.

usage: test_replay_logs.py REPLAY SIM
Exit status: 0 every check passed; 1 a check failed (each listed); 2 usage error.
"""
import os
import subprocess
import sys
import tempfile

MOTOR = ["--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0", "--sigma-uncertainty", "0"]
NAMES = ["t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta"]
FAILS = []


def check(cond, what, detail=""):
    if not cond:
        FAILS.append(what + ("\n    " + detail[:1500] if detail else ""))


def run(cmd, stdin=None):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, stdin=stdin)
    return p.returncode, p.stdout, p.stderr


def canonical(sim, d):
    """The simulator's columns, i_c and u_* made what the reader derives."""
    path = os.path.join(d, "sim.csv")
    rc, _, err = run([sim, "--preset", "exp2", "--duration", "6", "--supply", "vf", "--seed", "5",
                      "--out", path])
    if rc != 0:
        sys.exit("imest-sim failed: " + err)
    with open(path) as f:
        head = f.readline().strip().split(",")
        at = [head.index(n) for n in NAMES]
        rows = []
        for line in f:
            x = line.strip().split(",")
            t, ua, ub, uc, ia, ib, _, th = (x[k] for k in at)
            uab, ubc = float(ua) - float(ub), float(ub) - float(uc)
            uca = -uab - ubc  # as the reader forms the one not logged
            rows.append({"t": t, "u_ab": uab, "u_bc": ubc, "u_a": (uab - uca) / 3.0,
                         "u_b": (ubc - uab) / 3.0, "u_c": (uca - ubc) / 3.0, "i_a": ia, "i_b": ib,
                         "i_c": -float(ia) - float(ib), "theta": th})
    return rows


def text(v):
    return repr(v) if isinstance(v, float) else v


def write(d, name, header, cols, rows, sep=",", pre="", every=None, fmt=text):
    """header: what the file's header says; cols: the canonical field of each column."""
    path = os.path.join(d, name)
    with open(path, "w") as f:
        f.write(pre + sep.join(header) + "\n")
        for k, r in enumerate(rows):
            if every and k % every == 0:
                f.write("# a comment between rows\n\n")
            f.write(sep.join(fmt(r[c]) if callable(fmt) else text(r[c]) for c in cols) + "\n")
    return path


def windows(out):
    return out.splitlines()


def slurp(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    replay, sim = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="imest-replay-logs-") as d:
        rows = canonical(sim, d)
        canon = write(d, "canon.csv", NAMES, NAMES, rows)
        rc, ref, err = run([replay] + MOTOR + [canon])
        check(rc == 0 and len(windows(ref)) == 7, "canonical: 6 windows", err + ref)
        check("note:" not in err, "canonical: no note about the header", err)

        def same(name, path, extra=(), notes=()):
            rc, out, err = run([replay] + MOTOR + list(extra) + [path])
            check(rc == 0, name + ": exit 0", err)
            check(out == ref, name + ": the canonical window rows", err + "\n" + out[:600])
            for n in notes:
                check(n in err, name + ": says '%s'" % n, err)
            return err

        same("units in brackets and parentheses, ';'",
             write(d, "units.csv", ["t [s]", "u_a[V]", "u_b (V)", "u_c(V)", "i_a [A]", "i_b(A)",
                                     "i_c [A]", "theta [rad]"], NAMES, rows, sep=";"),
             notes=["separated by ';'"])
        same("upper case and aliases, tab, comments",
             write(d, "alias.csv", ["TIME", "VA", "V_B", "u_cn", "IA", "I_B", "iC", "Angle"], NAMES, rows,
                   sep="\t", pre="# exported by a drive\n# second comment\n\n", every=5000),
             notes=["separated by tab"])
        same("two current sensors",
             write(d, "two_i.csv", ["t", "u_a", "u_b", "u_c", "i_a", "i_b", "theta"],
                   ["t", "u_a", "u_b", "u_c", "i_a", "i_b", "theta"], rows),
             notes=["i_c = -i_a - i_b"])
        same("two current sensors, i_a derived",
             write(d, "two_i_bc.csv", ["t", "u_a", "u_b", "u_c", "i_c", "i_b", "theta"],
                   ["t", "u_a", "u_b", "u_c", "i_c", "i_b", "theta"], rows),
             notes=["i_a = -i_b - i_c"])
        same("line-to-line voltages",
             write(d, "ll.csv", ["t", "u_ab", "u_bc", "i_a", "i_b", "i_c", "theta"],
                   ["t", "u_ab", "u_bc", "i_a", "i_b", "i_c", "theta"], rows),
             notes=["line-to-line voltages converted to phase-to-neutral assuming no zero sequence"])
        ms_rows = [dict(r, t=repr(float(r["t"]) * 1000.0)) for r in rows]
        same("t in ms with a unit header",
             write(d, "ms.csv", ["Time [ms]"] + NAMES[1:], NAMES, ms_rows),
             notes=["t in ms (from its header 'Time [ms]'): converted to s"])
        same("t in ms without a unit, --fs", write(d, "ms_bare.csv", NAMES, NAMES, ms_rows),
             extra=["--fs", "4000"], notes=["in ms at --fs 4000 Hz"])
        # ';' with decimal commas (European tools)
        comma = write(d, "comma.csv", NAMES, NAMES, rows, sep=";",
                      fmt=lambda v: text(v).replace(".", ","))
        same("';' with decimal commas", comma, notes=["decimal comma"])

        # --fs that contradicts t: runs (as before), and says so quoting both rates
        rc, out, err = run([replay] + MOTOR + ["--fs", "8000", canon])
        check(rc == 0, "--fs 8000 on a 4 kHz t: still runs", err)
        check("4000 Hz" in err and "8000 Hz" in err, "--fs 8000 on a 4 kHz t: both rates quoted", err)
        rc, out, err = run([replay] + MOTOR + ["--fs", "4100", canon])
        check("4000 Hz" in err and "--fs says 4100 Hz" in err, "--fs 4100 on a 4 kHz t: named", err)
        rc, out, err = run([replay] + MOTOR + ["--fs", "4000", canon])
        check(out == ref and "note:" not in err, "--fs agreeing with t: no note, same rows", err)

        # a gap: one sample missing at the start of window 4
        gap_at = 12000
        gap = write(d, "gap.csv", NAMES, NAMES, rows[:gap_at] + rows[gap_at + 1:])
        rc, out, err = run([replay] + MOTOR + [gap])
        check(rc == 1, "gap: refused by default", err)
        check(":%d: irregular sampling" % (gap_at + 2) in err and "--gaps restart" in err
              and "t = %s after %s" % (rows[gap_at + 1]["t"], rows[gap_at - 1]["t"]) in err,
              "gap: the refusal quotes the line, the t read and names --gaps restart", err)
        rc, out, err = run([replay] + MOTOR + ["--gaps", "restart", gap])
        check(rc == 0, "gap, --gaps restart: exit 0", err)
        a, b = windows(out), windows(ref)
        check(len(a) == len(b) and a[:4] == b[:4], "gap: the rows before the gap are the canonical ones",
              out)
        if len(a) == len(b):
            f = [r.split(",") for r in a[4:]]
            g = [r.split(",") for r in b[4:]]
            check(f[0][5] == "warmup", "gap: the first window after it warms up", a[4])
            for x, y in zip(f[1:], g[1:]):
                check(x[4] == "1" and abs(float(x[1]) / float(y[1]) - 1) < 0.01,
                      "gap: later windows valid, T_R within 1 % of the canonical", x[1] + " " + y[1])
        check("1 gap in t" in err and "line %d" % (gap_at + 2) in err and "restarted at 1 gap" in err,
              "gap: how many and where", err)

        # refusals quote what was read and what was expected
        bad = write(d, "missing.csv", ["Time [ms]", "IA", "IB", "theta"], ["t", "i_a", "i_b", "theta"],
                    rows[:10], sep=";", pre="# comment\n\n")
        rc, _, err = run([replay] + MOTOR + [bad])
        check(rc == 1 and ":3: missing column 'u_a'" in err
              and "the header (line 3, separator ';') has: Time [ms], IA, IB, theta" in err
              and "t,u_a,u_b,u_c,i_a,i_b,i_c,theta" in err and "u_ab,u_bc,u_ca" in err,
              "missing column: quotes the header, its line and separator, and what is expected", err)
        bad = write(d, "unit.csv", NAMES[:4] + ["i_a [kA]"] + NAMES[5:], NAMES, rows[:10])
        rc, _, err = run([replay] + MOTOR + [bad])
        check(rc == 1 and "'i_a [kA]'" in err and "unit 'kA' is not known" in err and "A, mA" in err,
              "unknown unit: quoted, with the known ones", err)
        bad = write(d, "twice.csv", ["t", "IA", "i_a [A]"] + NAMES[1:4] + NAMES[5:], ["t", "i_a", "i_a"] +
                    NAMES[1:4] + NAMES[5:], rows[:10])
        rc, _, err = run([replay] + MOTOR + [bad])
        check(rc == 1 and "'IA' (2) and 'i_a [A]' (3) both read as i_a" in err, "two aliases: both quoted",
              err)
        bad = write(d, "two_u.csv", ["t", "u_a", "u_b", "i_a", "i_b", "i_c", "theta"],
                    ["t", "u_a", "u_b", "i_a", "i_b", "i_c", "theta"], rows[:10])
        rc, _, err = run([replay] + MOTOR + [bad])
        check(rc == 1 and "missing column 'u_c'" in err and "zero sequence" in err,
              "two phase voltages: refused, saying why", err)
        few = [dict(r) for r in rows[:10]]
        few[3]["u_b"] = "1.234,5"
        bad = write(d, "dotcomma.csv", NAMES, NAMES, few, sep=";",
                    fmt=lambda v: v if v == "1.234,5" else text(v).replace(".", ","))
        rc, _, err = run([replay] + MOTOR + [bad])
        check(rc == 1 and ":5: column 'u_b': '1.234,5' is not a number" in err,
              "'.' and ',' in one number: quoted with its line", err)

        # --candump - never shares stdout with the CSV
        rc, out, err = run([replay] + MOTOR + ["--candump", "-", canon])
        check(rc == 2 and out == "" and "-o FILE" in err, "--candump - with the CSV on stdout: exit 2, names -o",
              err)
        csv = os.path.join(d, "windows.csv")
        rc, out, err = run([replay] + MOTOR + ["--candump", "-", "-o", csv, canon])
        check(rc == 0 and slurp(csv) == ref, "-o FILE: the CSV in the file", err)
        check(out.startswith("(") and " vcan0 " in out and "t_end_s" not in out,
              "--candump - with -o: only frames on stdout", out[:300])
        os.remove(csv) if os.path.exists(csv) else None
        rc, out, err = run([replay] + MOTOR + ["--output=" + csv, "--quiet", canon])
        check(rc == 0 and out == "" and slurp(csv) == ref, "--output=FILE", err)
        rc, out, err = run([replay] + MOTOR + ["-o", os.path.join(d, "no", "such.csv"), canon])
        check(rc == 1 and "-o " in err and "no/such.csv" in err, "-o into a missing folder: exit 1, named", err)
        rc, out, err = run([replay] + MOTOR + ["--gaps", "bridge", canon])
        check(rc == 2 and "--gaps takes refuse or restart, not 'bridge'" in err, "--gaps bridge: exit 2", err)
        with open(canon) as f:
            rc, out, err = run([replay] + MOTOR + ["-o", "-", "-"], stdin=f)
        check(rc == 0 and out == ref, "-o - and stdin", err)

    for f in FAILS:
        print("FAIL " + f)
    print("%d failures" % len(FAILS))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
