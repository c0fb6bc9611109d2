#!/usr/bin/python3
"""imest-monitor on candump logs: clean, lost, repeated, corrupted,
malformed and truncated input, options and error paths.

usage: test_monitor.py SELFTEST MONITOR WORKDIR
"""
import os
import subprocess
import sys

selftest, monitor, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
fails = []
N = 20
HEADER = "t_s,seq,T_R_s,R_S_ohm,E_I,valid,status"


def check(cond, msg):
    if not cond:
        fails.append(msg)


def run(args, stdin=None):
    p = subprocess.run([monitor] + args, capture_output=True, text=True, input=stdin)
    return p.returncode, p.stdout, p.stderr


def rows(out):
    lines = out.splitlines()
    return lines[1:] if lines and lines[0].startswith(HEADER) else None


def write(name, lines):
    path = os.path.join(work, name)
    with open(path, "w") as fh:
        fh.write("".join(lines))
    return path


clean = os.path.join(work, "mon_clean.log")
subprocess.run([selftest, "--log", clean, "--count", str(N)], check=True)
with open(clean) as fh:
    good = fh.readlines()
check(len(good) == 4 * N, f"selftest wrote {len(good)} lines")

# 1. clean log, CSV
rc, out, err = run(["--log", clean, "--csv"])
check(rc == 0, f"clean: rc {rc}")
check(out.splitlines()[0].startswith(HEADER + ","), "CSV header: " + out.splitlines()[0])
r = rows(out)
check(r is not None and len(r) == N, f"clean: {len(r or [])} rows")
check("lost 0, repeated 0, corrupted 0" in err, "clean summary: " + err)
check("no_root" in out and "high_residual" in out and ",ok," in out, "status names in CSV")
first = r[0].split(",")
check(first[0] == "1700000001.000000" and first[1] == "0" and first[5] == "1" and first[6] == "ok",
      f"first row {r[0]}")

# 2. table
rc, out, err = run(["--log", clean])
lines = out.splitlines()
check(rc == 0 and "T_R [s]" in lines[0] and len(lines) == N + 1, f"table: {len(lines)} lines")

# 3. lost frame (line 10 = window 2, IMEST_RS)
rc, out, err = run(["--log", write("mon_lost.log", good[:9] + good[10:]), "--csv"])
r = rows(out)
check(len(r) == N, f"lost: {len(r)} rows")
check("lost 1 frame(s) 0x6A1 (IMEST_RS): counter 1 -> 3" in err, "lost event: " + err)
check("incomplete window (counter 2, seq 2): missing IMEST_RS" in err, "incomplete event: " + err)
check(",0x5\n" in out or out.rstrip().endswith("0x5") or ",0xB" in out or ",0xD" in out,
      "incomplete row frames mask")
check("lost 1," in err and "windows 20 (incomplete 1)" in err, "lost summary: " + err)

# 4. repeated frame
rc, out, err = run(["--log", write("mon_rep.log", good[:5] + [good[4]] + good[5:]), "--csv"])
check(len(rows(out)) == N, "repeated: rows")
check("mon_rep.log:6: repeated frame 0x6A0 (IMEST_TR), counter 1" in err, "repeat event: " + err)
check("repeated 1," in err, "repeat summary")

# 5. corrupted frame (one hex digit of the payload changed)
bad = good[6]
pos = bad.index("#") + 3
bad = bad[:pos] + ("0" if bad[pos] != "0" else "1") + bad[pos + 1:]
rc, out, err = run(["--log", write("mon_corrupt.log", good[:6] + [bad] + good[7:]), "--csv"])
check("mon_corrupt.log:7: corrupted frame 0x6A2 (IMEST_QUAL): checksum mismatch" in err, "corrupt: " + err)
check("corrupted 1," in err and "incomplete 1" in err, "corrupt summary: " + err)
short = good[8].split("#")[0] + "#" + good[8].split("#")[1][:10] + "\n"
rc, out, err = run(["--log", write("mon_dlc.log", good[:8] + [short] + good[9:]), "--csv"])
check("corrupted frame 0x6A0 (IMEST_TR): 5 data bytes, expected 8" in err, "short frame: " + err)

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
check(f"mon_trunc.log:{4 * N}: malformed line" in err, "truncated line: " + err)
check("end of input: incomplete window" in err and "missing IMEST_STAT" in err, "truncated end: " + err)
check(len(rows(out)) == N, "truncated: rows")

# 8. stdin
rc, out, err = run(["--log", "-", "--csv"], stdin="".join(good))
check(rc == 0 and len(rows(out)) == N, "stdin")

# 9. other base id: nothing is ours
rc, out, err = run(["--log", clean, "--csv", "--base-id", "0x100"])
check(len(rows(out)) == 0 and f"foreign {4 * N}" in err, "foreign: " + err)

# 10. extended identifiers
ext = os.path.join(work, "mon_ext.log")
subprocess.run([selftest, "--log", ext, "--count", "5", "--base-id", "0x18FF5000"], check=True)
with open(ext) as fh:
    check(" 18FF5003#" in fh.read(), "extended id in log")
rc, out, err = run(["--log", ext, "--csv", "--base-id", "0x18FF5000"])
check(len(rows(out)) == 5 and "lost 0," in err, "extended: " + err)
rc, out, err = run(["--log", ext, "--csv", "--base-id", "0x500", "--ext"])
check(len(rows(out)) == 0, "extended 0x500 is not 0x18FF5000")

# 11. --count
rc, out, err = run(["--log", clean, "--csv", "--count", "5"])
check(len(rows(out)) == 5, "--count")

# 12. usage and open errors
rc, out, err = run([])
check(rc == 1 and "exactly one of --iface" in err, "no source")
rc, out, err = run(["--log", clean, "--iface", "vcan0"])
check(rc == 1, "two sources")
rc, out, err = run(["--log", clean, "--base-id", "0x7FE"])
check(rc == 1 and "out of range" in err, "base id range")
rc, out, err = run(["--log", clean, "--base-id", "zz"])
check(rc == 1 and "bad --base-id" in err, "base id parse")
rc, out, err = run(["--log", os.path.join(work, "does-not-exist.log")])
check(rc == 2 and "cannot open log" in err and "No such file" in err, "missing log: " + err)
rc, out, err = run(["--bogus"])
check(rc == 1 and "unknown" in err, "unknown option")

# 13. live on this machine: no CAN in the kernel -> clear message, exit 2
rc, out, err = run(["--iface", "vcan0", "--timeout", "1"])
check((rc == 2 and ("no SocketCAN support" in err or "no such network interface" in err)
       and out == "") or (rc == 0 and "listening" in err), f"iface error: rc {rc} {err} {out}")

if fails:
    print("\n".join(fails))
    print(f"FAILED: {len(fails)} check(s)")
    sys.exit(1)
print("imest-monitor: all checks passed")
