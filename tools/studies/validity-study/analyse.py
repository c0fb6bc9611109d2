#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Analysis of the validity study (run.sh): joins every replayed window with the
simulator's truth averaged over the same window, classifies it, and measures
how well the validity rule separates good from bad windows, for the defaults
and for other thresholds (the rule is re-evaluated from the printed indices,
in the order of src/estimator/window/bg_validity.c; the re-evaluation is checked against the
`valid` column for the defaults).

usage: analyse.py OUT_DIR        (prints a Markdown report on stdout)
"""
import csv
import math
import os
import re
import sys

import numpy as np

# Classification of a window by its true errors (README: "Classes").
GOOD_TR, GOOD_RS = 0.02, 0.05     # good: |e_TR| < 2 % and |e_RS| < 5 %
GROSS_TR, GROSS_RS = 0.10, 0.25   # gross: |e_TR| > 10 % or |e_RS| > 25 % (or no number)

DEFAULTS = dict(pe=0.1, slip=0.1, ei=3.0, slip_kind="est")  # the library defaults
TR_NOMINAL = 0.1
FLAG_REASONS = 0x000F  # input fault, ADC saturation, encoder fault, warm-up


def load(out):
    rows = []
    cdir = os.path.join(out, "cases")
    names = sorted(f[: -len(".replay.csv")] for f in os.listdir(cdir) if f.endswith(".replay.csv"))
    for name in names:
        tpath = os.path.join(cdir, name + ".truth.csv")
        if not os.path.exists(tpath):
            continue  # case still running or failed
        with open(tpath) as f:
            truth = {int(r["seq"]): r for r in csv.DictReader(f)}
        with open(os.path.join(cdir, name + ".replay.csv")) as f:
            for r in csv.DictReader(f):
                seq = int(r["seq"])
                if seq not in truth:
                    continue
                t = truth[seq]
                w = dict(case=name, group=re.sub(r"_s[0-9]+$", "", name), seq=seq)
                for k in ("T_R_s", "R_S_ohm", "E_I", "pe_k1_rel", "pe_k2_rel", "slip_ratio", "i_rms_a"):
                    w[k] = float(r[k])
                for k in ("valid", "hessian_pd", "n_roots", "n_admissible", "used_samples"):
                    w[k] = int(r[k])
                w["flags"] = int(r["flags"], 16)
                w["status"] = r["status"]
                w["tr_true"] = float(t["tr_true_s"])
                w["rs_true"] = float(t["rs_true_ohm"])
                w["speed"] = float(t["speed_rad_s"])
                w["load"] = float(t["load_nm"])
                w["e_tr"] = w["T_R_s"] / w["tr_true"] - 1.0
                w["e_rs"] = w["R_S_ohm"] / w["rs_true"] - 1.0
                solved = w["n_admissible"] > 0 and math.isfinite(w["T_R_s"])
                # slip_ratio = rms(di/dt)/rms(i) * T_R_used, T_R_used = estimate if solved, else nominal
                tr_used = w["T_R_s"] if solved else TR_NOMINAL
                w["di_over_i"] = w["slip_ratio"] / tr_used
                w["slip_nom"] = w["di_over_i"] * TR_NOMINAL
                w["slip_true"] = w["di_over_i"] * w["tr_true"]
                w["solved"] = solved
                if not (math.isfinite(w["e_tr"]) and math.isfinite(w["e_rs"])):
                    w["cls"] = "gross"
                elif abs(w["e_tr"]) < GOOD_TR and abs(w["e_rs"]) < GOOD_RS:
                    w["cls"] = "good"
                elif abs(w["e_tr"]) > GROSS_TR or abs(w["e_rs"]) > GROSS_RS:
                    w["cls"] = "gross"
                else:
                    w["cls"] = "marginal"
                # faults invalidate a window; warm-up only when it took more than
                # half of it (bg_validity.c), which the status tells
                w["flagged"] = bool(w["flags"] & (FLAG_REASONS & ~0x1)) or w["status"] == "warmup"
                rows.append(w)
    return rows


def judge(w, pe, slip, ei, slip_kind="est"):
    """Validity re-evaluated with the given thresholds; returns the reason ('ok' = valid)."""
    if w["flagged"]:
        return "flag"
    if not w["i_rms_a"] >= 0.05:
        return "no_current"
    s = w["slip_ratio"] if slip_kind == "est" else w["slip_nom"]
    if not s >= slip:
        return "zero_slip"
    if not w["solved"]:
        return "no_root"
    if not w["hessian_pd"]:
        return "not_minimum"
    if not w["pe_k2_rel"] <= pe:
        return "poorly_determined"
    if not w["E_I"] <= ei:
        return "high_residual"
    if not (0.0 <= w["R_S_ohm"] <= 1e3):
        return "rs_out_of_range"
    return "ok"


def stats(xs):
    xs = np.array([x for x in xs if math.isfinite(x)])
    if xs.size == 0:
        return "-"
    return "%.3g / %.3g / %.3g" % (xs.min(), np.median(xs), xs.max())


def counts(rows, **th):
    fv_gross = fv_marg = fi = valid = 0
    for w in rows:
        ok = judge(w, **th) == "ok"
        valid += ok
        if ok and w["cls"] == "gross":
            fv_gross += 1
        elif ok and w["cls"] == "marginal":
            fv_marg += 1
        elif not ok and w["cls"] == "good":
            fi += 1
    return valid, fv_gross, fv_marg, fi


def main():
    out = sys.argv[1]
    rows = load(out)
    p = print
    mism = [w for w in rows if (judge(w, **DEFAULTS) == "ok") != bool(w["valid"])]
    p("# Validity study: results\n")
    p("%d windows from %d recordings. Classes by true error: good |e_TR| < %g %% and |e_RS| < %g %%; "
      "gross |e_TR| > %g %% or |e_RS| > %g %%; marginal in between." %
      (len(rows), len({w["case"] for w in rows}), 100 * GOOD_TR, 100 * GOOD_RS, 100 * GROSS_TR,
       100 * GROSS_RS))
    p("Re-evaluated rule vs the estimator's own `valid` (defaults): %d mismatches.\n" % len(mism))
    for w in mism[:10]:
        p("  MISMATCH %s #%d status %s" % (w["case"], w["seq"], w["status"]))

    # ---- per group, defaults --------------------------------------------------
    p("## Per scenario, default thresholds (pe_k2_rel <= 0.1, slip_ratio >= 0.1, E_I <= 3)\n")
    p("| scenario | win | good | marg | gross | valid | false-valid gross | false-valid marg | "
      "false-invalid | e_TR % of valid (min/med/max) | e_RS % of valid | statuses |")
    p("|---|---|---|---|---|---|---|---|---|---|---|---|")
    groups = []
    for w in rows:
        if w["group"] not in groups:
            groups.append(w["group"])
    tot = np.zeros(8, dtype=int)
    for g in groups:
        gw = [w for w in rows if w["group"] == g]
        v, fvg, fvm, fi = counts(gw, **DEFAULTS)
        nc = [sum(w["cls"] == c for w in gw) for c in ("good", "marginal", "gross")]
        st = {}
        for w in gw:
            st[w["status"]] = st.get(w["status"], 0) + 1
        vw = [w for w in gw if w["valid"]]
        row = [len(gw)] + nc + [v, fvg, fvm, fi]
        tot += np.array(row)
        p("| %s | %s | %s | %s | %s |" % (
            g, " | ".join(str(x) for x in row),
            stats([100 * w["e_tr"] for w in vw]), stats([100 * w["e_rs"] for w in vw]),
            ", ".join("%s %d" % kv for kv in sorted(st.items()))))
    p("| **total** | %s | | | |\n" % " | ".join(str(x) for x in tot))

    # ---- distributions ----------------------------------------------------------
    clean = [w for w in rows if not w["flagged"] and w["solved"]]
    p("## Distributions (windows without warm-up/saturation flags and with a solution): "
      "min / median / max\n")
    p("| class | n | pe_k2_rel | pe_k1_rel | E_I | slip_ratio (T_R est.) | slip_ratio (T_R nominal 0.1 s) | "
      "slip_ratio (true T_R) | n_roots | hessian PD |")
    p("|---|---|---|---|---|---|---|---|---|---|")
    for c in ("good", "marginal", "gross"):
        cw = [w for w in clean if w["cls"] == c]
        p("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %d/%d |" % (
            c, len(cw), stats([w["pe_k2_rel"] for w in cw]), stats([w["pe_k1_rel"] for w in cw]),
            stats([w["E_I"] for w in cw]), stats([w["slip_ratio"] for w in cw]),
            stats([w["slip_nom"] for w in cw]), stats([w["slip_true"] for w in cw]),
            stats([w["n_roots"] for w in cw]), sum(w["hessian_pd"] for w in cw), len(cw)))
    p("")
    good = [w for w in clean if w["cls"] == "good"]
    gross = [w for w in clean if w["cls"] == "gross"]
    # where the spurious minimum sits: K2 = 1/T_R against the electrical speed n_p * omega
    ratio = [(1.0 / w["T_R_s"]) / ((4 if w["case"].startswith("m2") else 2) * w["speed"])
             for w in gross if w["speed"] > 10 and w["T_R_s"] < 0.02]
    p("Gross windows with T_R < 20 ms at speed: %d; K2/(n_p*omega) min / median / max = %s.\n" %
      (len(ratio), stats(ratio)))
    if good and gross:
        gmax = max(good, key=lambda w: w["pe_k2_rel"])
        bmin = min(gross, key=lambda w: w["pe_k2_rel"])
        p("Largest pe_k2_rel of a good window: %.4g (%s #%d); smallest of a gross window: %.4g (%s #%d, "
          "e_TR %+.1f %%).\n" % (gmax["pe_k2_rel"], gmax["case"], gmax["seq"], bmin["pe_k2_rel"],
                                 bmin["case"], bmin["seq"], 100 * bmin["e_tr"]))

    # ---- per-scenario-family distributions of pe_k2_rel ----------------------------
    p("### pe_k2_rel by family and class (min / median / max)\n")
    p("| family | good | marginal | gross |")
    p("|---|---|---|---|")
    fams = []
    for w in clean:
        f = re.sub(r"_x[0-9.]+", "", w["group"])
        f = re.sub(r"_L[0-9]+", "", f)
        w["family"] = f
        if f not in fams:
            fams.append(f)
    for f in fams:
        fw = [w for w in clean if w["family"] == f]
        cells = []
        for c in ("good", "marginal", "gross"):
            cw = [w["pe_k2_rel"] for w in fw if w["cls"] == c]
            cells.append("%d: %s" % (len(cw), stats(cw)) if cw else "-")
        p("| %s | %s |" % (f, " | ".join(cells)))
    p("")

    # ---- threshold sweep ------------------------------------------------------
    p("## Threshold sweep (all %d windows)\n" % len(rows))
    p("| max_pe_k2_rel | min_slip_ratio | slip measure | max_ei | valid | false-valid gross | "
      "false-valid marginal | false-invalid (good) |")
    p("|---|---|---|---|---|---|---|---|")
    for pe in (0.02, 0.04, 0.05, 0.1, 0.2, 0.3, 0.5, 1e9):
        for slip, kind in ((0.0, "est"), (0.05, "est"), (0.02, "nom"), (0.05, "nom"), (0.1, "nom")):
            for ei in (3.0, 1e9):
                v, fvg, fvm, fi = counts(rows, pe=pe, slip=slip, ei=ei, slip_kind=kind)
                p("| %s | %g | %s | %s | %d | %d | %d | %d |" % (
                    "none" if pe > 1e8 else "%g" % pe, slip, kind, "none" if ei > 1e8 else "%g" % ei,
                    v, fvg, fvm, fi))
    p("")

    # ---- listings -------------------------------------------------------------
    def line(w, reason):
        return ("| %s | %d | %s | %+.2f | %+.2f | %.3g | %.3g | %.3g | %.3g | %.3g | %d | %.3g | %.3g |" % (
            w["case"], w["seq"], reason, 100 * w["e_tr"], 100 * w["e_rs"], w["pe_k2_rel"], w["pe_k1_rel"],
            w["E_I"], w["slip_ratio"], w["slip_true"], w["n_roots"], w["speed"], w["load"]))
    hdr = ("| case | win | status | e_TR % | e_RS % | pe_k2_rel | pe_k1_rel | E_I | slip_ratio | slip(true T_R) "
           "| n_roots | speed rad/s | load N m |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    p("## Valid but not good (defaults)\n")
    p(hdr)
    for w in rows:
        if w["valid"] and w["cls"] != "good":
            p(line(w, w["status"]))
    p("\n## Good but invalid, other than warm-up/saturation flags (defaults)\n")
    p(hdr)
    for w in rows:
        if not w["valid"] and w["cls"] == "good" and not w["flagged"]:
            p(line(w, w["status"]))
    p("\n## Gross windows invalid for zero_slip although the true slip ratio is >= 0.2 (wrong reason)\n")
    p(hdr)
    for w in rows:
        if w["status"] == "zero_slip" and w["cls"] == "gross" and w["slip_true"] >= 0.2:
            p(line(w, w["status"]))
    p("\n## Valid windows with the largest |e_TR| (defaults)\n")
    p(hdr)
    vw = sorted((w for w in rows if w["valid"]), key=lambda w: -abs(w["e_tr"]))
    for w in vw[:12]:
        p(line(w, w["status"]))


if __name__ == "__main__":
    main()
