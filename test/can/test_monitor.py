#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""imest-monitor on candump logs: clean, lost, repeated, corrupted,
malformed and truncated input, a sender restart, options, exit codes
(0 decoded, 1 nothing decoded / input error, 2 usage, 3 --require-valid and
none valid), the CSV's columns (imest-replay's names and order, numbers only:
a clamped value is named in 'clamped') and the messages that say what is wrong
when nothing decodes.

usage: test_monitor.py SELFTEST MONITOR WORKDIR
"""
import os
import subprocess
import sys

selftest, monitor, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
fails = []
N = 20
NF = 6  # frames per window
HEADER = "t_s,T_R_s,R_S_ohm,E_I,valid,status,seq"
# imest-replay's columns the frames carry, in its order (tools/replay/replay.c), then the monitor's own
COLUMNS = ("t_s,T_R_s,R_S_ohm,E_I,valid,status,seq,pe_k1_rel,pe_k2_rel,n_roots,n_admissible,flags,"
           "tr_valid,rs_valid,tr_reason,rs_reason,span_s,windows,tr_bound_rel,rs_bound_rel,"
           "clamped,sat,tx_failed,counter,frames")


def check(cond, msg):
    if not cond:
        fails.append(msg)


def run(args, stdin=None):
    p = subprocess.run([monitor] + args, capture_output=True, text=True, input=stdin)
    return p.returncode, p.stdout, p.stderr


def rows(out):
    lines = out.splitlines()
    return lines[1:] if lines and lines[0].startswith(HEADER) else []


def write(name, lines):
    path = os.path.join(work, name)
    with open(path, "w") as fh:
        fh.write("".join(lines))
    return path


def publish(name, *args):
    path = os.path.join(work, name)
    subprocess.run([selftest, "--log", path] + list(args), check=True, capture_output=True)
    with open(path) as fh:
        return path, fh.readlines()


clean, good = publish("mon_clean.log", "--count", str(N))
check(len(good) == NF * N, f"selftest wrote {len(good)} lines")

# 1. clean log, CSV
rc, out, err = run(["--log", clean, "--csv"])
check(rc == 0, f"clean: rc {rc}")
check(out.splitlines()[0].startswith(HEADER + ","), "CSV header: " + out.splitlines()[0])
check(out.splitlines()[0] == COLUMNS, "CSV header: " + out.splitlines()[0])
r = rows(out)
check(len(r) == N, f"clean: {len(r)} rows")
check("lost 0, repeated 0, corrupted 0" in err, "clean summary: " + err)
check("no_root" in out and "high_residual" in out and ",ok," in out, "status names in CSV")
cols = out.splitlines()[0].split(",")
first = dict(zip(cols, r[0].split(",")))
check(first["t_s"] == "1700000001.000000" and first["seq"] == "0" and first["valid"] == "1"
      and first["status"] == "ok" and first["frames"] == "0x3f" and first["clamped"] == ""
      and first["sat"] == "0x0", f"first row {r[0]}")
sat_row = dict(zip(cols, r[5].split(",")))  # window 5: every field but R_S clamped
check(sat_row["pe_k1_rel"] == "1.31068" and sat_row["pe_k2_rel"] == "1.31068" and sat_row["E_I"] == "6.5534"
      and float(sat_row["T_R_s"]) > 1e38 and sat_row["span_s"] == "65.534"
      and sat_row["tr_bound_rel"] == "1.31068" and sat_row["rs_bound_rel"] == "0.00000",
      f"clamped values are printed as the limit, a number: {r[5]}")
check(sat_row["clamped"] == "T_R_s;E_I;pe_k1_rel;pe_k2_rel;span_s;tr_bound_rel;rs_bound_rel"
      and sat_row["sat"] == "0xfd", f"the clamped columns named in 'clamped': {r[5]}")
for k, line in enumerate(r):  # numeric columns hold numbers (or are empty)
    row = dict(zip(cols, line.split(",")))
    for c in ("t_s", "T_R_s", "R_S_ohm", "E_I", "valid", "seq", "pe_k1_rel", "pe_k2_rel", "n_roots",
              "n_admissible", "tr_valid", "rs_valid", "span_s", "windows", "tr_bound_rel", "rs_bound_rel",
              "tx_failed", "counter"):
        try:
            float(row[c])
        except ValueError:
            check(False, f"window {k}: {c} = {row[c]!r} is not a number")
check(sat_row["R_S_ohm"] == "-inf", "an infinity is carried as such, not saturated")
row7 = dict(zip(cols, r[7].split(",")))  # window 7: T_R trusted, R_S not
check(row7["tr_valid"] == "1" and row7["tr_reason"] == "ok" and row7["rs_valid"] == "0"
      and row7["rs_reason"] == "rs_out_of_range", f"per-parameter verdicts: {r[7]}")

# 2. table
rc, out, err = run(["--log", clean])
lines = out.splitlines()
check(rc == 0 and "T_R [s]" in lines[0] and "T_R verdict" in lines[0] and len(lines) == N + 1,
      f"table: {len(lines)} lines")
check(">1.31068" in lines[6] and " 1.31068" not in lines[6], "table: saturated PE shown as a bound: " + lines[6])
check("rs_out_of_range" in lines[8] and " ok " in lines[8], "table: R_S verdict apart from T_R: " + lines[8])
check("n/a" in lines[2], "table: a bound that is not available: " + lines[2])

# 3. lost frame: window 2's IMEST_RS
rc, out, err = run(["--log", write("mon_lost.log", good[:2 * NF + 1] + good[2 * NF + 2:]), "--csv"])
check(rc == 0 and len(rows(out)) == N, f"lost: rc {rc}, {len(rows(out))} rows")
check("lost 1 frame(s) up to the window with counter 2" in err, "lost event: " + err)
check("incomplete window (counter 2, seq 2): missing IMEST_RS" in err, "incomplete event: " + err)
inc = dict(zip(COLUMNS.split(","), rows(out)[2].split(",")))
check(inc["frames"] == "0x3d" and inc["R_S_ohm"] == "" and inc["pe_k2_rel"] == "" and inc["T_R_s"] != "",
      f"incomplete row: frames mask, the missing frame's columns empty: {rows(out)[2]}")
check("lost 1," in err and "windows 20 (incomplete 1)" in err, "lost summary: " + err)
# a whole window lost
rc, out, err = run(["--log", write("mon_lost_win.log", good[:3 * NF] + good[4 * NF:]), "--csv"])
check(f"lost {NF}, repeated 0, corrupted 0" in err and "incomplete 0" in err, "lost window summary: " + err)

# 4. repeated frame
rc, out, err = run(["--log", write("mon_rep.log", good[:5] + [good[4]] + good[5:]), "--csv"])
check(len(rows(out)) == N, "repeated: rows")
check("mon_rep.log:6: repeated frame 0x6A4 (IMEST_VERDICT), counter 0" in err, "repeat event: " + err)
check("lost 0, repeated 1," in err, "repeat summary: " + err)

# 5. corrupted frames are counted as corrupted, not also as lost
bad = good[NF + 2]
pos = bad.index("#") + 3
bad = bad[:pos] + ("0" if bad[pos] != "0" else "1") + bad[pos + 1:]
rc, out, err = run(["--log", write("mon_corrupt.log", good[:NF + 2] + [bad] + good[NF + 3:]), "--csv"])
check(f"mon_corrupt.log:{NF + 3}: corrupted frame 0x6A2 (IMEST_QUAL): checksum mismatch" in err, "corrupt: " + err)
check("lost 0, repeated 0, corrupted 1," in err and "incomplete 1" in err, "corrupt summary: " + err)
short = good[2 * NF].split("#")[0] + "#" + good[2 * NF].split("#")[1][:10] + "\n"
rc, out, err = run(["--log", write("mon_dlc.log", good[:2 * NF] + [short] + good[2 * NF + 1:]), "--csv"])
check("corrupted frame 0x6A0 (IMEST_TR): 5 data bytes, expected 8" in err, "short frame: " + err)
check("lost 0, repeated 0, corrupted 1," in err, "short frame summary: " + err)

# 6. malformed lines: named by number, the reader goes on
junk = ["this is not a candump line\n", "(1700000000.5) vcan0 123#0\n", "\x00\x01binary\n",
        "(1700000000.5) vcan0 6A0#" + "00" * 9 + "\n", "x" * 5000 + "\n"]
path = write("mon_junk.log", good[:2] + junk + good[2:])
rc, out, err = run(["--log", path, "--csv"])
check(rc == 0, f"junk: rc {rc}")
check(len(rows(out)) == N, f"junk: {len(rows(out))} rows")
for n in (3, 4, 5, 6, 7):
    check(f"mon_junk.log:{n}: malformed line" in err, f"junk line {n} not reported: " + err)
check("odd number of hex digits" in err and "more than 8 data bytes" in err, "junk reasons: " + err)
check("malformed lines 5" in err and "corrupted 0" in err, "junk summary: " + err)

# 7. truncated file (last line cut in the middle, no newline)
cut = good[-1][:len(good[-1]) // 2]
path = write("mon_trunc.log", good[:-1] + [cut])
rc, out, err = run(["--log", path, "--csv"])
check(f"mon_trunc.log:{NF * N}: malformed line" in err, "truncated line: " + err)
check("end of input: incomplete window" in err and "missing IMEST_BOUNDS" in err, "truncated end: " + err)
check(len(rows(out)) == N and "lost 0," in err, "truncated: rows, and the unrecorded tail is not lost")

# 8. stdin, and --opt=value
rc, out, err = run(["--log", "-", "--csv"], stdin="".join(good))
check(rc == 0 and len(rows(out)) == N, "stdin")
rc, out, err = run(["--log=-", "--csv", "--count=3", "--can-base-id=0x6A0"], stdin="".join(good))
check(rc == 0 and len(rows(out)) == 3, f"--opt=value: rc {rc} {err}")

# 9. a sender restart is a restart, not hundreds of lost frames
_, again = publish("mon_again.log", "--count", "5", "--epoch", "1700000100")
path = write("mon_restart.log", good + again)
rc, out, err = run(["--log", path, "--csv"])
check(rc == 0 and len(rows(out)) == N + 5, f"restart: rc {rc}, {len(rows(out))} rows")
check("sequence number went back to 0: the sender restarted" in err, "restart event: " + err)
check("lost 0, repeated 0, corrupted 0, estimator gaps 2, restarts 1," in err, "restart summary: " + err)

# 10. extended identifiers, one parser for every tool
ext, _ = publish("mon_ext.log", "--count", "5", "--base-id", "0x18FF5000")
with open(ext) as fh:
    check(" 18FF5005#" in fh.read(), "extended id in log")
for base in ("0x18FF5000", "0x98FF5000", "419385344"):
    rc, out, err = run(["--log", ext, "--csv", "--can-base-id", base])
    check(rc == 0 and len(rows(out)) == 5 and "lost 0," in err, f"extended {base}: " + err)
# the older spellings --base-id and --ext are the same options
rc, out, err = run(["--log", ext, "--csv", "--base-id", "0x18FF5000"])
check(rc == 0 and len(rows(out)) == 5, f"--base-id (older spelling): rc {rc} {err}")

# 11. --count
rc, out, err = run(["--log", clean, "--csv", "--count", "5"])
check(rc == 0 and len(rows(out)) == 5, "--count")
for bad_count in ("0", "-1", "abc", "2x", ""):
    rc, out, err = run(["--log", clean, "--count", bad_count])
    check(rc == 2 and "bad --count" in err and out == "", f"--count {bad_count!r}: rc {rc} {err}")

# 12. nothing decoded: exit 1 and say why
def nothing(args, want, what, stdin=None):
    rc, out, err = run(args, stdin)
    check(rc == 1 and "nothing decoded" in err and want in err, f"{what}: rc {rc}: {err}")


plain = []
for line in good:
    ident, data = line.split()[2].split("#")
    plain.append("  vcan0  %s   [8]  %s\n" % (ident, " ".join(data[i:i + 2] for i in range(0, 16, 2))))
nothing(["--log", write("mon_plain.log", plain)], "look like plain candump output", "plain candump")
nothing(["--log", write("mon_plain.log", plain)], "candump -L", "plain candump remedy")
nothing(["--log", clean, "--can-base-id", "0x100"],
        f"{NF * N} frame(s) read, none with identifiers 0x100..0x105; frames seen: 0x6A0 ({N}),",
        "wrong base id")
nothing(["--log", clean, "--can-base-id", "0x100"], "is --can-base-id right? 0x6A0 .. +5 look like an imest "
        "node: --can-base-id 0x6A0", "wrong base id: the likely base")
nothing(["--log", clean, "--can-ext"], "the log has 11-bit (standard) identifiers at that base: drop --can-ext",
        "--can-ext on an 11-bit log")
small_ext, _ = publish("mon_small_ext.log", "--count", "3", "--base-id", "0x500", "--ext")
nothing(["--log", small_ext, "--can-base-id", "0x500"], "29-bit (extended) identifiers at that base: add --can-ext",
        "29-bit log without --can-ext")
rc, out, err = run(["--log", small_ext, "--can-base-id", "0x500", "--can-ext"])
check(rc == 0 and len(rows(out) or out.splitlines()[1:]) == 3, f"29-bit log with --can-ext: {err}")
rc, out, err = run(["--log", small_ext, "--base-id", "0x500", "--ext"])
check(rc == 0 and len(rows(out) or out.splitlines()[1:]) == 3, f"29-bit log with --ext (older spelling): {err}")
nothing(["--log", write("mon_empty.log", [])], "the log is empty", "empty log")
nothing(["--log", "-"], "the log is empty", "empty stdin", stdin="")
nothing(["--log", write("mon_text.log", ["hello\n", "world\n"])], "2 line(s) read, none a candump -L frame line",
        "not a log")
all_bad = [line[:-3] + ("00" if line[-3:-1] != "00" else "11") + "\n" for line in good]
nothing(["--log", write("mon_allbad.log", all_bad)], "all corrupted (bad checksum or length)", "all corrupted")
rc, out, err = run(["--log", work])
check(rc == 1 and "is a directory" in err, f"directory as --log: rc {rc} {err}")
rc, out, err = run(["--log", os.path.join(work, "does-not-exist.log")])
check(rc == 1 and "cannot open log" in err and "No such file" in err, "missing log: " + err)

# 12b. --require-valid: exit 3 when windows decode but none has the column asked for at 1
rc, out, err = run(["--log", clean, "--csv", "--require-valid"])
check(rc == 0, f"--require-valid on a log with valid windows: rc {rc} {err}")
one_bad = write("mon_one_bad.log", good[3 * NF:4 * NF])  # window 3 only: no_root
for which, col in (("", "valid"), ("=valid", "valid"), ("=tr", "tr_valid"), ("=rs", "rs_valid")):
    rc, out, err = run(["--log", one_bad, "--csv", "--require-valid" + which])
    check(rc == 3 and len(rows(out)) == 1 and f"none of the 1 window(s) decoded has {col} = 1" in err,
          f"--require-valid{which} on a window not valid: rc {rc} {err}")
rc, out, err = run(["--log", one_bad, "--csv"])
check(rc == 0, f"without --require-valid a window not valid is success: rc {rc}")
t_only = write("mon_tr_only.log", good[7 * NF:8 * NF])  # window 7: T_R valid, R_S not
rc, _, err = run(["--log", t_only, "--require-valid=tr"])
check(rc == 0, f"--require-valid=tr, T_R valid: rc {rc} {err}")
rc, _, err = run(["--log", t_only, "--require-valid=rs"])
check(rc == 3, f"--require-valid=rs, R_S not valid: rc {rc} {err}")
nothing(["--log", write("mon_empty2.log", []), "--require-valid"], "the log is empty",
        "--require-valid, nothing decoded: still exit 1")

# 13. usage errors: exit 2
for args, want in ((["--log", clean, "--iface", "vcan0"], "exactly one of"),
                   (["--log", clean, "--can-iface", "vcan0"], "exactly one of --can-iface NAME or --log FILE"),
                   (["--log", clean, "--require-valid=both"], "takes valid, tr or rs"),
                   ([], "exactly one of"),
                   (["--log", clean, "--can-base-id", "0x7FB"], "beyond the 11-bit range (largest base 0x7FA); "
                    "use a lower base, or --can-ext"),
                   (["--log", clean, "--base-id", "0x20000000"], "beyond the 29-bit range"),
                   (["--log", clean, "--base-id", "zz"], "not an identifier"),
                   (["--log", clean, "--base-id", "-5"], "negative"),
                   (["--bogus"], "unknown option"),
                   (["--log", clean, "--csv=1"], "takes no value"),
                   (["--log"], "needs a value"),
                   (["--log", clean, "--timeout", "-1"], "bad --timeout")):
    rc, out, err = run(args)
    check(rc == 2 and want in err, f"usage {args}: rc {rc}: {err}")
rc, out, err = run(["--help"])
check(rc == 0 and "usage: imest-monitor" in out and "Exit status" in out, "--help")

# 14. live on this machine: no CAN in the kernel -> clear message, exit 1
rc, out, err = run(["--can-iface", "vcan0", "--timeout", "1"])
check((rc == 1 and ("no SocketCAN support" in err or "no such network interface" in err))
      or (rc == 1 and "listening" in err and "no frame received" in err), f"iface error: rc {rc} {err} {out}")

if fails:
    print("\n".join(fails))
    print(f"FAILED: {len(fails)} check(s)")
    sys.exit(1)
print("imest-monitor: all checks passed")
