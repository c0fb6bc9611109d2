#!/usr/bin/python3
"""DBC against codec: an independent decoder (python3-canmatrix, loading
tools/imest.dbc) decodes a candump log written by the C library, and every
signal must equal what the C decoder (imest-monitor --csv) prints.

usage: test_dbc.py SELFTEST MONITOR DBC WORKDIR
"""
import csv
import math
import os
import re
import struct
import subprocess
import sys

import canmatrix.formats

selftest, monitor, dbc_path, work = sys.argv[1:5]
os.makedirs(work, exist_ok=True)
log = os.path.join(work, "dbc_check.log")
N = 40
fails = []


def check(cond, msg):
    if not cond:
        fails.append(msg)


def crc8_j1850(data):
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


subprocess.run([selftest, "--log", log, "--count", str(N)], check=True)
out = subprocess.run([monitor, "--log", log, "--csv"], check=True, capture_output=True, text=True)
rows = list(csv.DictReader(out.stdout.splitlines()))
check(len(rows) == N, f"monitor printed {len(rows)} rows, expected {N}")

db = canmatrix.formats.loadp_flat(dbc_path)
base = 0x6A0
frames = {f.arbitration_id.id: f for f in db.frames}
check(sorted(frames) == [base, base + 1, base + 2, base + 3], f"DBC ids {sorted(frames)}")

# structure: 8-byte frames, Intel byte order, no overlapping signals, counter
# and CRC at the same place everywhere
for fid, fr in frames.items():
    check(fr.size == 8, f"{fr.name}: dlc {fr.size}")
    used = {}
    for s in fr.signals:
        check(s.is_little_endian, f"{fr.name}.{s.name} not Intel byte order")
        for b in range(s.start_bit, s.start_bit + s.size):
            check(b not in used, f"{fr.name}: {s.name} overlaps {used.get(b)} at bit {b}")
            used[b] = s.name
        check(s.start_bit + s.size <= 64, f"{fr.name}.{s.name} beyond 64 bits")
    ctr = fr.signal_by_name("Counter")
    crc = fr.signal_by_name("CRC")
    check(ctr is not None and ctr.start_bit == 48 and ctr.size == 8, f"{fr.name}: Counter")
    check(crc is not None and crc.start_bit == 56 and crc.size == 8, f"{fr.name}: CRC")

line_re = re.compile(r"^\((\d+\.\d+)\) (\S+) ([0-9A-F]{3}|[0-9A-F]{8})#([0-9A-F]*)$")
windows = []
cur = None
with open(log) as fh:
    for n, line in enumerate(fh, 1):
        m = line_re.match(line.strip())
        check(m is not None, f"log line {n} not candump -L: {line!r}")
        if not m:
            continue
        fid = int(m.group(3), 16)
        data = bytes.fromhex(m.group(4))
        check(len(data) == 8, f"line {n}: {len(data)} bytes")
        idx = fid - base
        check(crc8_j1850(bytes([idx]) + data[:7]) == data[7], f"line {n}: CRC mismatch")
        sig = {k: v for k, v in frames[fid].decode(data).items()}
        counter = int(sig["Counter"].raw_value)
        check(int(sig["CRC"].raw_value) == data[7], f"line {n}: CRC signal")
        if cur is None or cur["_ctr"] != counter:
            cur = {"_ctr": counter, "t": float(m.group(1))}
            windows.append(cur)
        for name, d in sig.items():
            cur[name] = d
        cur.setdefault("_ids", []).append(idx)

check(len(windows) == N, f"{len(windows)} windows in the log")
status_names = frames[base + 2].signal_by_name("Status").values


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0] if math.isfinite(x) else x


def same_float(a, b):
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b


def u16(dec, row_val, field, k):
    raw = int(dec.raw_value)
    if raw == 65535:
        check(row_val == "nan", f"window {k}: {field} raw 65535 (n/a) but C printed {row_val}")
    else:
        phys = float(dec.phys_value)
        check(abs(phys - float(row_val)) <= 1e-9, f"window {k}: {field} DBC {phys} C {row_val}")


for k, (w, row) in enumerate(zip(windows, rows)):
    check(sorted(w["_ids"]) == [0, 1, 2, 3], f"window {k}: frames {w['_ids']}")
    check(abs(w["t"] - float(row["t_s"])) < 1e-6, f"window {k}: t {w['t']} vs {row['t_s']}")
    check(int(w["Seq"].raw_value) == int(row["seq"]), f"window {k}: seq")
    tr = float(w["TR_s"].phys_value)
    rs = float(w["RS_ohm"].phys_value)
    check(same_float(tr, f32(float(row["T_R_s"]))), f"window {k}: T_R DBC {tr} C {row['T_R_s']}")
    check(same_float(rs, f32(float(row["R_S_ohm"]))), f"window {k}: R_S DBC {rs} C {row['R_S_ohm']}")
    u16(w["EI"], row["E_I"], "E_I", k)
    u16(w["PE_K1_rel"], row["pe_k1_rel"], "pe_k1_rel", k)
    u16(w["PE_K2_rel"], row["pe_k2_rel"], "pe_k2_rel", k)
    check(int(w["Valid"].raw_value) == int(row["valid"]), f"window {k}: valid")
    st = int(w["Status"].raw_value)
    check(status_names.get(st) == row["status"],
          f"window {k}: status {st} = {status_names.get(st)!r} in the DBC, C says {row['status']!r}")
    check(int(w["NRoots"].raw_value) == int(row["n_roots"]), f"window {k}: n_roots")
    check(int(w["NAdmissible"].raw_value) == int(row["n_admissible"]), f"window {k}: n_admissible")
    flags = 0
    for name, bit in (("Flag_Warmup", 0x1), ("Flag_InputFault", 0x2), ("Flag_AdcSat", 0x4),
                      ("Flag_EncoderFault", 0x8), ("Flag_Overrun", 0x10), ("HessianPD", 0x100)):
        if int(w[name].raw_value):
            flags |= bit
    check(flags == int(row["flags"], 16), f"window {k}: flags DBC 0x{flags:X} C {row['flags']}")
    sat = 0
    for name, bit in (("Sat_TR", 1), ("Sat_RS", 2), ("Sat_EI", 4), ("Sat_PE_K1", 8), ("Sat_PE_K2", 16)):
        if int(w[name].raw_value):
            sat |= bit
    check(sat == int(row["sat"], 16), f"window {k}: sat DBC 0x{sat:X} C {row['sat']}")
    check(int(w["TxFailed"].raw_value) == int(row["tx_failed"]), f"window {k}: tx_failed")
    check(w["_ctr"] == int(row["counter"]), f"window {k}: counter")
    # the synthetic values themselves (see can_selftest.c): edge windows
    if k % 10 == 3:
        check(math.isnan(tr) and row["status"] == "no_root", f"window {k}: NaN window")
    if k % 10 == 5:
        # T_R 1e300, E_I 9.5, PE_K1 +inf, PE_K2 2.0 saturate; R_S -inf is carried as -inf
        check(sat == 0x1D, f"window {k}: saturation bits 0x{sat:X}, expected 0x1D")
        check(tr == 3.4028234663852886e38 and rs == -math.inf, f"window {k}: {tr} {rs}")

# the window at k=6 comes after an estimator gap of 2 windows
check("estimator gaps 2" in out.stderr, "monitor summary: " + out.stderr.strip())

if fails:
    print("\n".join(fails[:50]))
    print(f"FAILED: {len(fails)} mismatch(es)")
    sys.exit(1)
print(f"DBC and C decoder agree on {len(rows)} windows ({4 * len(rows)} frames), "
      f"{sum(len(f.signals) for f in frames.values())} signals")
