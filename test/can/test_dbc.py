#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/imest.dbc against the C codec, in two ways:

1. Structure: the C signal table (imest-can-selftest --table, i.e.
   src/can/can_signals.c, and IMEST_TEMP's layout from imest_temperature.h)
   and the DBC (loaded with python3-canmatrix) must describe the same
   signals: frame, start bit, length, byte order, signedness / float, factor,
   offset, min/max, not-available and enum value tables (reason names =
   imest_reason_name()). Mutated copies of the DBC must be caught (the
   comparison can fail), IMEST_TEMP's signals too.
2. Values: an independent decoder (canmatrix) decodes a candump log written
   by the C library (the six frames and IMEST_TEMP per window), and every
   signal must equal what the C decoder (imest-monitor --csv --temperatures)
   prints.

usage: test_dbc.py SELFTEST MONITOR DBC WORKDIR
"""
import csv
import math
import os
import re
import struct
import subprocess
import sys
from decimal import Decimal

import canmatrix.formats

selftest, monitor, dbc_path, work = sys.argv[1:5]
os.makedirs(work, exist_ok=True)
BASE = 0x6A0
fails = []


def check(cond, msg):
    if not cond:
        fails.append(msg)


# --------------------------------------------------------------------------- C table

def c_table():
    out = subprocess.run([selftest, "--table"], check=True, capture_output=True, text=True).stdout
    t = {"signals": [], "reasons": {}, "optional": []}
    for line in out.splitlines():
        f = line.split()
        if f[0] == "frames":
            t["nframes"], t["counter"], t["crc"] = int(f[1]), int(f[3]), int(f[5])
        elif f[0] == "signal":
            t["signals"].append({"frame": int(f[1]), "start": int(f[2]), "len": int(f[3]), "kind": f[4],
                                 "scale": int(f[5]), "mask": int(f[6])})
        elif f[0] == "optional":
            t["optional"].append(int(f[1]))
        elif f[0] == "reason":
            t["reasons"][int(f[1])] = f[2]
    return t


def compare(db, t):
    """Every difference between the DBC and the C table, as messages."""
    bad = []
    frames = {f.arbitration_id.id: f for f in db.frames}
    want_ids = [BASE + i for i in list(range(t["nframes"])) + t["optional"]]
    if sorted(frames) != want_ids:
        bad.append(f"DBC frames {[hex(i) for i in sorted(frames)]}, C has {t['nframes']} from 0x{BASE:X} "
                   f"and {t['optional']}")
    enum_values = dict(t["reasons"])
    enum_values[255] = "out_of_range"
    c_by_pos = {(s["frame"], s["start"]): s for s in t["signals"]}
    seen = set()
    for fid, fr in sorted(frames.items()):
        idx = fid - BASE
        if fr.size != 8:
            bad.append(f"{fr.name}: dlc {fr.size}")
        used = {}
        for s in fr.signals:
            where = f"{fr.name}.{s.name} (frame {idx}, bit {s.start_bit})"
            if not s.is_little_endian:
                bad.append(f"{where}: not Intel byte order")
            for b in range(s.start_bit, s.start_bit + s.size):
                if b in used:
                    bad.append(f"{fr.name}: {s.name} overlaps {used[b]} at bit {b}")
                used[b] = s.name
            if s.start_bit + s.size > 64:
                bad.append(f"{where}: beyond 64 bits")
            if s.name in ("Counter", "CRC"):
                start = t["counter"] if s.name == "Counter" else t["crc"]
                if (s.start_bit, s.size, s.is_signed, s.factor, s.offset) != (start, 8, False, 1, 0):
                    bad.append(f"{where}: C has it at bit {start}, 8 bits, unsigned")
                continue
            c = c_by_pos.get((idx, s.start_bit))
            if c is None:
                bad.append(f"{where}: not in the C table")
                continue
            seen.add((idx, s.start_bit))
            ones = (1 << c["len"]) - 1
            if s.size != c["len"]:
                bad.append(f"{where}: {s.size} bits, C {c['len']}")
            is_f32 = c["kind"] == "f32"
            is_signed = c["kind"] in ("f32", "temp_c")  # temp_c: int16, -32768 = not available
            if bool(s.is_float) != is_f32 or bool(s.is_signed) != is_signed:
                bad.append(f"{where}: float {s.is_float} signed {s.is_signed}, C kind {c['kind']}")
            scaled = c["kind"] in ("scaled", "temp_c", "temp_k")
            factor = Decimal(1) / Decimal(c["scale"]) if scaled else Decimal(1)
            if Decimal(str(s.factor)) != factor or Decimal(str(s.offset)) != 0:
                bad.append(f"{where}: factor {s.factor} offset {s.offset}, C factor {factor} offset 0")
            want_min = Decimal(0)
            if is_f32:
                want_max = Decimal(0)  # unspecified: the whole float range
            elif c["kind"] == "temp_c":  # +-(2^(len-1) - 1): the most negative raw is not available
                want_max = Decimal((ones >> 1)) * factor
                want_min = -want_max
            elif scaled:
                want_max = Decimal(ones - 1) * factor
            else:
                want_max = Decimal(ones)
            if Decimal(str(s.min)) != want_min or Decimal(str(s.max)) != want_max:
                bad.append(f"{where}: range [{s.min}|{s.max}], C [{want_min}|{want_max}]")
            values = {int(k): v for k, v in s.values.items()}
            if c["kind"] in ("scaled", "temp_k"):
                want_values = {ones: "not_available"}
            elif c["kind"] == "temp_c":
                want_values = {-(1 << (c["len"] - 1)): "not_available"}
            elif c["kind"] == "enum":
                want_values = enum_values
            else:
                want_values = {}
            if values != want_values:
                bad.append(f"{where}: value table {values}, C {want_values}")
            if c["kind"] == "sat" and not s.name.startswith("Sat_"):
                bad.append(f"{where}: a saturation bit in C")
        if "Counter" not in used.values() or "CRC" not in used.values():
            bad.append(f"{fr.name}: no Counter or CRC")
    for key, c in c_by_pos.items():
        if key not in seen:
            bad.append(f"C signal frame {key[0]} bit {key[1]} ({c['kind']}, {c['len']} bits) not in the DBC")
    # F32/SCALED ranges are guarded by exactly one saturation bit each
    carried = [s["mask"] for s in t["signals"] if s["kind"] == "sat"]
    for s in t["signals"]:
        if s["kind"] in ("f32", "scaled") and carried.count(s["mask"]) != 1:
            bad.append(f"C signal frame {s['frame']} bit {s['start']}: saturation bit 0x{s['mask']:X} "
                       f"carried {carried.count(s['mask'])} times")
    return bad


table = c_table()
db = canmatrix.formats.loadp_flat(dbc_path)
for msg in compare(db, table):
    check(False, "structure: " + msg)

# the comparison must catch a changed DBC: one mutation at a time
with open(dbc_path) as fh:
    dbc_text = fh.read()
mutations = {
    "EI factor": (" SG_ EI : 32|16@1+ (0.0001,0)", " SG_ EI : 32|16@1+ (0.001,0)"),
    "Span_s start bit": (" SG_ Span_s : 24|16@1+", " SG_ Span_s : 25|16@1+"),
    "TR_bound_rel max": ("TR_bound_rel : 0|16@1+ (2E-005,0) [0|1.31068]", "TR_bound_rel : 0|16@1+ (2E-005,0) [0|1.31070]"),
    "reason name": ('VAL_ 1700 RS_reason 0 "ok" 10 "warmup"', 'VAL_ 1700 RS_reason 0 "ok" 10 "warm_up"'),
    "signal removed": (" SG_ Windows : 40|8@1+ (1,0) [0|255] \"\" IMEST_MONITOR\n", ""),
    "signedness": (" SG_ Seq : 0|32@1+", " SG_ Seq : 0|32@1-"),
    "IMEST_TEMP factor": (" SG_ Stator_C : 0|16@1- (0.01,0)", " SG_ Stator_C : 0|16@1- (0.1,0)"),
    "IMEST_TEMP signedness": (" SG_ Rotor_C : 16|16@1-", " SG_ Rotor_C : 16|16@1+"),
    "IMEST_TEMP start bit": (" SG_ Rotor_uncert_K : 40|7@1+", " SG_ Rotor_uncert_K : 41|7@1+"),
    "IMEST_TEMP length": (" SG_ Stator_uncert_K : 32|7@1+", " SG_ Stator_uncert_K : 32|8@1+"),
    "IMEST_TEMP range": ("[-327.67|327.67] \"degC\" IMEST_MONITOR\n SG_ Rotor_C",
                         "[-327.68|327.67] \"degC\" IMEST_MONITOR\n SG_ Rotor_C"),
    "IMEST_TEMP not available": ('VAL_ 1702 Rotor_C -32768 "not_available"', 'VAL_ 1702 Rotor_C 32767 "not_available"'),
    "IMEST_TEMP valid bit removed": (" SG_ Rotor_valid : 47|1@1+ (1,0) [0|1] \"\" IMEST_MONITOR\n", ""),
    "IMEST_TEMP identifier": (" 1702 ", " 1703 "),  # its BO_, CM_ and VAL_ lines
}
for what, (old, new) in mutations.items():
    check(old in dbc_text, f"mutation '{what}': text not found in the DBC")
    path = os.path.join(work, "mutated.dbc")
    with open(path, "w") as fh:
        fh.write(dbc_text.replace(old, new))
    check(compare(canmatrix.formats.loadp_flat(path), table) != [], f"mutation '{what}' not detected")

# --------------------------------------------------------------------------- values

log = os.path.join(work, "dbc_check.log")
N = 40
NF = table["nframes"]
subprocess.run([selftest, "--log", log, "--count", str(N), "--temperatures"], check=True)
out = subprocess.run([monitor, "--log", log, "--csv", "--temperatures"], check=True, capture_output=True, text=True)
rows = list(csv.DictReader(out.stdout.splitlines()))
check(len(rows) == N, f"monitor printed {len(rows)} rows, expected {N}")
frames = {f.arbitration_id.id: f for f in db.frames}


def crc8_j1850(data):
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


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
        idx = fid - BASE
        check(crc8_j1850(bytes([idx]) + data[:7]) == data[7], f"line {n}: CRC mismatch")
        sig = dict(frames[fid].decode(data).items())
        counter = int(sig["Counter"].raw_value)
        check(int(sig["CRC"].raw_value) == data[7], f"line {n}: CRC signal")
        if cur is None or cur["_ctr"] != counter:
            cur = {"_ctr": counter, "t": float(m.group(1))}
            windows.append(cur)
        cur.update(sig)
        cur.setdefault("_ids", []).append(idx)
        # reserved bits are 0
        used = sum(((1 << s.size) - 1) << s.start_bit for s in frames[fid].signals)
        check(int.from_bytes(data, "little") & ~used == 0, f"line {n}: reserved bits set")

check(len(windows) == N, f"{len(windows)} windows in the log")
reason_names = dict(frames[BASE + 2].signal_by_name("Status").values)


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0] if math.isfinite(x) else x


def same_float(a, b):
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b


def c_value(text, sat_bit_set, field, k, clamped=None):
    """The C decoder's cell: a number (a clamped one as its field's limit), its column
    named in 'clamped' exactly when saturated."""
    check(text[:1] not in "<>", f"window {k}: {field} printed {text!r}: a number, not a bound")
    if clamped is not None:
        check((field in clamped.split(";")) == sat_bit_set,
              f"window {k}: {field} in clamped {clamped!r}, saturation bit {sat_bit_set}")
    return float(text)


def scaled(w, name, row, col, sat_name, k):
    row_val = row[col]
    dec = w[name]
    sat = bool(int(w[sat_name].raw_value))
    if int(dec.raw_value) == 65535:
        check(row_val == "nan", f"window {k}: {name} raw 65535 (n/a) but C printed {row_val}")
    else:
        phys = float(dec.phys_value)
        check(abs(phys - c_value(row_val, sat, col, k, row["clamped"])) <= 1e-9,
              f"window {k}: {name} DBC {phys} C {row_val}")


def reason(w, name, row_val, k):
    raw = int(w[name].raw_value)
    check(reason_names.get(raw) == row_val,
          f"window {k}: {name} {raw} = {reason_names.get(raw)!r} in the DBC, C says {row_val!r}")


def temperature(w, name, row, col, k):
    """A temperature or an uncertainty: the DBC's value within float32 of the C decoder's; not
    available (raw -32768, 127) as nan; a value at its field's end named in 'clamped'."""
    sig = frames[BASE + 6].signal_by_name(name)
    raw = int(w[name].raw_value)
    na = -(1 << (sig.size - 1)) if sig.is_signed else (1 << sig.size) - 1
    if raw == na:
        check(row[col] == "nan", f"window {k}: {name} raw {raw} (n/a) but C printed {row[col]!r}")
        return None
    top = (1 << (sig.size - 1)) - 1 if sig.is_signed else (1 << sig.size) - 2
    phys = float(w[name].phys_value)
    check(abs(phys - float(row[col])) <= 1e-4, f"window {k}: {name} DBC {phys} C {row[col]}")
    check((col in row["clamped"].split(";")) == (abs(raw) == top),
          f"window {k}: {col} in clamped {row['clamped']!r}, raw {raw}")
    return phys


for k, (w, row) in enumerate(zip(windows, rows)):
    check(sorted(w["_ids"]) == list(range(NF)) + table["optional"], f"window {k}: frames {w['_ids']}")
    check(row["frames"] == "0x%x" % ((1 << (NF + 1)) - 1), f"window {k}: frames mask {row['frames']}")
    stator = temperature(w, "Stator_C", row, "stator_c", k)
    rotor = temperature(w, "Rotor_C", row, "rotor_c", k)
    temperature(w, "Stator_uncert_K", row, "stator_uncert_k", k)
    temperature(w, "Rotor_uncert_K", row, "rotor_uncert_k", k)
    check(int(w["Stator_valid"].raw_value) == int(row["stator_valid"]), f"window {k}: stator_valid")
    check(int(w["Rotor_valid"].raw_value) == int(row["rotor_valid"]), f"window {k}: rotor_valid")
    # the synthetic temperatures (can_selftest.c): within the frame's resolution, edges as sent
    if k % 10 == 3:
        check(stator is None and rotor is None, f"window {k}: temperatures not available")
    elif k % 10 == 5:
        check(stator == 327.67 and rotor == -327.67 and row["stator_uncert_k"] == "25.2"
              and row["rotor_uncert_k"] == "25.2", f"window {k}: clamped temperatures {row}")
    else:
        check(abs(stator - (-40.0 + 7.37 * k)) <= 0.0051 and abs(rotor - (150.0 - 11.13 * k)) <= 0.0051,
              f"window {k}: temperatures {stator} {rotor}")
        check(int(row["stator_valid"]) == k % 2 and int(row["rotor_valid"]) == (k % 3 == 0),
              f"window {k}: valid bits {row['stator_valid']} {row['rotor_valid']}")
    check(abs(w["t"] - float(row["t_s"])) < 1e-6, f"window {k}: t {w['t']} vs {row['t_s']}")
    check(int(w["Seq"].raw_value) == int(row["seq"]), f"window {k}: seq")
    tr = float(w["TR_s"].phys_value)
    rs = float(w["RS_ohm"].phys_value)
    check(same_float(tr, f32(c_value(row["T_R_s"], bool(int(w["Sat_TR"].raw_value)), "T_R_s", k,
                                     row["clamped"]))),
          f"window {k}: T_R DBC {tr} C {row['T_R_s']}")
    check(same_float(rs, f32(c_value(row["R_S_ohm"], bool(int(w["Sat_RS"].raw_value)), "R_S_ohm", k,
                                     row["clamped"]))),
          f"window {k}: R_S DBC {rs} C {row['R_S_ohm']}")
    scaled(w, "EI", row, "E_I", "Sat_EI", k)
    scaled(w, "PE_K1_rel", row, "pe_k1_rel", "Sat_PE_K1", k)
    scaled(w, "PE_K2_rel", row, "pe_k2_rel", "Sat_PE_K2", k)
    scaled(w, "TR_bound_rel", row, "tr_bound_rel", "Sat_TR_bound", k)
    scaled(w, "RS_bound_rel", row, "rs_bound_rel", "Sat_RS_bound", k)
    scaled(w, "Span_s", row, "span_s", "Sat_Span", k)
    check(int(w["Valid"].raw_value) == int(row["valid"]), f"window {k}: valid")
    check(int(w["TR_valid"].raw_value) == int(row["tr_valid"]), f"window {k}: tr_valid")
    check(int(w["RS_valid"].raw_value) == int(row["rs_valid"]), f"window {k}: rs_valid")
    reason(w, "Status", row["status"], k)
    reason(w, "TR_reason", row["tr_reason"], k)
    reason(w, "RS_reason", row["rs_reason"], k)
    check(int(w["NRoots"].raw_value) == int(row["n_roots"]), f"window {k}: n_roots")
    check(int(w["NAdmissible"].raw_value) == int(row["n_admissible"]), f"window {k}: n_admissible")
    check(int(w["Windows"].raw_value) == int(row["windows"]), f"window {k}: windows")
    flags = 0
    for name, bit in (("Flag_Warmup", 0x1), ("Flag_InputFault", 0x2), ("Flag_AdcSat", 0x4),
                      ("Flag_EncoderFault", 0x8), ("Flag_Overrun", 0x10), ("HessianPD", 0x100)):
        if int(w[name].raw_value):
            flags |= bit
    check(flags == int(row["flags"], 16), f"window {k}: flags DBC 0x{flags:X} C {row['flags']}")
    sat = 0
    for name, bit in (("Sat_TR", 1), ("Sat_RS", 2), ("Sat_EI", 4), ("Sat_PE_K1", 8), ("Sat_PE_K2", 16),
                      ("Sat_Span", 32), ("Sat_TR_bound", 64), ("Sat_RS_bound", 128)):
        if int(w[name].raw_value):
            sat |= bit
    check(sat == int(row["sat"], 16), f"window {k}: sat DBC 0x{sat:X} C {row['sat']}")
    check(int(w["TxFailed"].raw_value) == int(row["tx_failed"]), f"window {k}: tx_failed")
    check(w["_ctr"] == int(row["counter"]), f"window {k}: counter")
    # the synthetic values themselves (see can_selftest.c): edge windows
    if k % 10 == 3:
        check(math.isnan(tr) and row["status"] == "no_root" and row["tr_reason"] == "no_root",
              f"window {k}: NaN window")
    if k % 10 == 5:
        # T_R 1e300, E_I 9.5, PE_K1 +inf, PE_K2 2.0, bounds 5 and -1, span 100 s saturate;
        # R_S -inf is carried as -inf; RS_reason 300 is out of range; 300 windows -> 255
        check(sat == 0xFD, f"window {k}: saturation bits 0x{sat:X}, expected 0xFD")
        check(tr == 3.4028234663852886e38 and rs == -math.inf, f"window {k}: {tr} {rs}")
        check(float(row["T_R_s"]) > 1e38 and row["pe_k1_rel"] == "1.31068"
              and row["rs_bound_rel"] == "0.00000" and row["span_s"] == "65.534"
              and row["clamped"] == "T_R_s;E_I;pe_k1_rel;pe_k2_rel;span_s;tr_bound_rel;rs_bound_rel;"
                                    "stator_c;stator_uncert_k;rotor_c;rotor_uncert_k",
              f"window {k}: {row}")
        check(row["rs_reason"] == "out_of_range" and row["windows"] == "255", f"window {k}: {row}")
    if k % 10 == 7:
        check(row["tr_valid"] == "1" and row["rs_valid"] == "0" and row["rs_reason"] == "rs_out_of_range"
              and row["valid"] == "0", f"window {k}: T_R valid, R_S not: {row}")

# the window at k=6 comes after an estimator gap of 2 windows
check("estimator gaps 2" in out.stderr, "monitor summary: " + out.stderr.strip())

if fails:
    print("\n".join(fails[:50]))
    print(f"FAILED: {len(fails)} mismatch(es)")
    sys.exit(1)
print(f"DBC and C table agree on {len(table['signals'])} signals in {NF} + {len(table['optional'])} frames "
      f"({len(mutations)} mutations of the DBC detected); DBC and C decoder agree on "
      f"{len(rows)} windows ({(NF + 1) * len(rows)} frames)")
