# SPDX-License-Identifier: Apache-2.0
"""Joins the replayed windows with the truth, classifies them and computes the summary.

Per window: e_TR = T_R / T_R,true - 1 and e_RS likewise (truth: the simulator's columns averaged
over the window; T_R,true is the T_R an IFOC needs, `T_R_ifoc_s`, which the simulator writes
with the real-motor effects on and which is `T_R_true_s` without them; e_TR_lrrr is the error
against the effective L_R/R_R, `T_R_true_s`). T_R is judged by `tr_valid`, R_S by `rs_valid` where imest-replay writes them,
otherwise both by `valid`.

* T_R good: valid and |e_TR| <= 1 %; R_S good: valid and |e_RS| <= 3 % (the goals).
* gross false-valid: T_R valid and |e_TR| > 10 %, or R_S valid and |e_RS| > 25 % (or a valid
  estimate that is not a number).
* marginal false-valid: not gross, and T_R valid with 2 % < |e_TR| <= 10 % or R_S valid with
  5 % < |e_RS| <= 25 %.
"""
import csv
import math
import os
from collections import Counter, defaultdict

TR_GOOD, RS_GOOD = 0.01, 0.03
TR_MARG, RS_MARG = 0.02, 0.05
TR_GROSS, RS_GROSS = 0.10, 0.25


def _f(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def load_point(p, work, skip, replay_name=None):
    """The windows of one point (list of dicts), steady-state ones only (seq >= skip). The
    replay output is work/<replay_name or name>.replay.csv, the truth work/<name>.truth.csv."""
    name = p["name"]
    rep = os.path.join(work, (replay_name or name) + ".replay.csv")
    tru = os.path.join(work, name + ".truth.csv")
    with open(tru) as f:
        truth = {int(r["seq"]): r for r in csv.DictReader(f)}
    rows = []
    with open(rep) as f:
        rd = csv.DictReader(f)
        cols = rd.fieldnames or []
        per_param = "tr_valid" in cols and "rs_valid" in cols
        for r in rd:
            seq = int(r["seq"])
            if seq < skip or seq not in truth:
                continue
            t = truth[seq]
            w = {k: p[k] for k in ("name", "family", "motor", "f_pct", "load_pct", "sensors",
                                   "encoder", "input", "goal")}
            w["seq"] = seq
            w["t_end_s"] = _f(r["t_end_s"])
            w["tr_s"], w["rs_ohm"] = _f(r["T_R_s"]), _f(r["R_S_ohm"])
            w["tr_true_s"], w["rs_true_ohm"] = _f(t.get("tr_ifoc_s", t["tr_true_s"])), _f(t["rs_true_ohm"])
            w["tr_lrrr_s"] = _f(t["tr_true_s"])
            w["speed_rad_s"], w["load_nm"] = _f(t["speed_rad_s"]), _f(t["load_nm"])
            w["valid"] = int(r["valid"])
            w["tr_valid"] = int(r["tr_valid"]) if per_param else w["valid"]
            w["rs_valid"] = int(r["rs_valid"]) if per_param else w["valid"]
            w["status"] = r["status"]
            w["tr_reason"] = r.get("tr_reason") or ("none" if w["tr_valid"] else r["status"])
            w["rs_reason"] = r.get("rs_reason") or ("none" if w["rs_valid"] else r["status"])
            for k in ("E_I", "pe_k1_rel", "pe_k2_rel", "slip_ratio", "span_s", "tr_bound_rel",
                      "rs_bound_rel"):
                w[k] = _f(r.get(k))  # nan where this imest-replay does not write it
            w["e_tr"] = w["tr_s"] / w["tr_true_s"] - 1.0
            w["e_tr_lrrr"] = w["tr_s"] / w["tr_lrrr_s"] - 1.0
            w["e_rs"] = w["rs_ohm"] / w["rs_true_ohm"] - 1.0
            classify(w)
            rows.append(w)
    return rows, per_param


def classify(w):
    atr, ars = abs(w["e_tr"]), abs(w["e_rs"])
    atr = atr if math.isfinite(atr) else math.inf
    ars = ars if math.isfinite(ars) else math.inf
    w["tr_good"] = int(w["tr_valid"] and atr <= TR_GOOD)
    w["rs_good"] = int(w["rs_valid"] and ars <= RS_GOOD)
    gross = (w["tr_valid"] and atr > TR_GROSS) or (w["rs_valid"] and ars > RS_GROSS)
    marg = (w["tr_valid"] and TR_MARG < atr <= TR_GROSS) or (w["rs_valid"] and RS_MARG < ars <= RS_GROSS)
    w["fv_gross"] = int(bool(gross))
    w["fv_marginal"] = int(bool(marg) and not gross)
    w["any_valid"] = int(w["tr_valid"] or w["rs_valid"])


def summary(rows):
    """The summary lines (name -> value)."""
    goal = [w for w in rows if w["goal"]]
    n = len(goal)
    nv = sum(w["any_valid"] for w in goal)
    s = dict(
        coverage_tr=sum(w["tr_good"] for w in goal) / n if n else math.nan,
        coverage_rs=sum(w["rs_good"] for w in goal) / n if n else math.nan,
        false_valid_gross=sum(w["fv_gross"] for w in rows),
        false_valid_marginal=sum(w["fv_marginal"] for w in goal) / nv if nv else 0.0,
        false_valid_gross_goal=sum(w["fv_gross"] for w in goal),
        false_valid_marginal_windows=sum(w["fv_marginal"] for w in rows),
        tr_valid_goal=sum(w["tr_valid"] for w in goal) / n if n else math.nan,
        rs_valid_goal=sum(w["rs_valid"] for w in goal) / n if n else math.nan,
        windows_goal=n,
        windows=len(rows),
    )
    return s


def median(xs):
    xs = sorted(x for x in xs if math.isfinite(x))
    if not xs:
        return math.nan
    k = len(xs) // 2
    return xs[k] if len(xs) % 2 else 0.5 * (xs[k - 1] + xs[k])


def point_table(rows, pts):
    """One row per point: counts, medians of the errors (valid or not), the commonest reasons."""
    by = defaultdict(list)
    for w in rows:
        by[w["name"]].append(w)
    out = []
    for p in pts:
        ws = by.get(p["name"], [])
        if not ws:
            continue
        trr = Counter(w["tr_reason"] for w in ws if not w["tr_valid"])
        rsr = Counter(w["rs_reason"] for w in ws if not w["rs_valid"])
        out.append(dict(
            name=p["name"], family=p["family"], motor=p["motor"], f_pct=p["f_pct"],
            load_pct=p["load_pct"], sensors=p["sensors"], encoder=p["encoder"], input=p["input"],
            goal=int(p["goal"]), f_hz=round(p["f_hz"], 4), vll=round(p["vll"], 2),
            load_nm=round(p["load_nm"], 4), windows=len(ws),
            tr_valid=sum(w["tr_valid"] for w in ws), tr_good=sum(w["tr_good"] for w in ws),
            rs_valid=sum(w["rs_valid"] for w in ws), rs_good=sum(w["rs_good"] for w in ws),
            fv_gross=sum(w["fv_gross"] for w in ws), fv_marginal=sum(w["fv_marginal"] for w in ws),
            e_tr_med_pct=100 * median([w["e_tr"] for w in ws]),
            e_rs_med_pct=100 * median([w["e_rs"] for w in ws]),
            pe_k2_med=median([w["pe_k2_rel"] for w in ws]),
            ei_med=median([w["E_I"] for w in ws]),
            slip_med=median([w["slip_ratio"] for w in ws]),
            span_med_s=median([w["span_s"] for w in ws]),
            tr_refused=";".join(f"{k} {v}" for k, v in trr.most_common()),
            rs_refused=";".join(f"{k} {v}" for k, v in rsr.most_common()),
        ))
    return out


WINDOW_COLS = ["name", "family", "motor", "f_pct", "load_pct", "sensors", "encoder", "input", "goal",
               "seq", "t_end_s", "tr_s", "tr_true_s", "e_tr", "tr_lrrr_s", "e_tr_lrrr", "rs_ohm",
               "rs_true_ohm", "e_rs",
               "valid", "tr_valid", "rs_valid", "status", "tr_reason", "rs_reason", "E_I",
               "pe_k1_rel", "pe_k2_rel", "slip_ratio", "span_s", "tr_bound_rel", "rs_bound_rel",
               "speed_rad_s", "load_nm", "tr_good",
               "rs_good", "fv_gross", "fv_marginal"]


def write_csv(path, rows, cols=None):
    cols = cols or list(rows[0].keys())
    with open(path, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore", lineterminator="\n")
        wr.writeheader()
        for r in rows:
            wr.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


REAL_TR, REAL_RS = 0.02, 0.05  # the product promise: a valid T_R within 2 %, a valid R_S within 5 %


def real_stats(ws):
    """Counts of the real-motor table for the windows ws: valid, valid and within the promise,
    valid and outside it (the confident wrong numbers; a valid non-number counts), the worst
    valid error (relative, signed) and the median error of all windows."""
    def one(key, e, lim):
        v = [w for w in ws if w[key]]
        errs = [w[e] if math.isfinite(w[e]) else math.inf for w in v]
        worst = max(errs, key=abs) if errs else math.nan
        return {f"{key[:2]}_valid": len(v),
                f"{key[:2]}_within": sum(abs(x) <= lim for x in errs),
                f"{key[:2]}_wrong": sum(abs(x) > lim for x in errs),
                f"{key[:2]}_worst": worst,
                f"{key[:2]}_median_all": median([w[e] for w in ws])}
    s = dict(windows=len(ws))
    s.update(one("tr_valid", "e_tr", REAL_TR))
    s.update(one("rs_valid", "e_rs", REAL_RS))
    lr = [w["e_tr_lrrr"] if math.isfinite(w["e_tr_lrrr"]) else math.inf for w in ws if w["tr_valid"]]
    s["tr_wrong_lrrr"] = sum(abs(x) > REAL_TR for x in lr)  # the same against L_R/R_R
    s["tr_worst_lrrr"] = max(lr, key=abs) if lr else math.nan
    return s


def real_summary(rows):
    """family -> real_stats, in the order of points.REAL_FAMILIES."""
    import points
    out = {}
    for fam, _, _ in points.REAL_FAMILIES:
        ws = [w for w in rows if w["family"] == fam]
        if ws:
            out[fam] = real_stats(ws)
    return out
