# SPDX-License-Identifier: Apache-2.0
"""Part c of the integration study: what the estimator makes of an angle that is not the encoder's.

One steady recording per operating point (imest-sim, 16384-count encoder); its theta column is
replaced by a transformed angle and the record replayed (imest-replay, 1-s windows) from stdin:

* encoder N: the true mechanical angle (theta_true) quantised to N counts per revolution, as
  the simulator's encoder does (floor: the last count passed);
* speed error: the encoder's angle plus a ramp, a constant speed error of a share of the
  electrical frequency (0.1 / 0.5 / 1 %) or of the slip frequency (1 / 5 / 10 %);
* jitter: the encoder's angle plus white Gaussian noise of 0.1 / 0.3 / 1 / 3 electrical degrees
  rms per sample;
* slip observer: the angle of a sensorless speed estimate omega_e - slip_hat with the slip of an
  IFOC, slip_hat = (1/T_R_hat) i_q/i_d. In the steady state i_q/i_d = T_R x slip, so
  slip_hat = slip x T_R / T_R_hat: the angle is the encoder's plus the integral of
  (slip - slip_hat) / n_p, with T_R_hat 10 % high or low.

The T_R error is against the simulator's T_R (no thermal drift in these records).
"""
import math
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

COLS = ("t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta")


def variants(p):
    """(name, group, function(d) -> theta) of point p; d holds the record's columns."""
    np_ = p["np"]
    we = 2 * math.pi * p["f_hz"]
    v = []
    for n in (1024, 4096, 16384, 65536):
        v.append((f"encoder {n} counts", "encoder",
                  lambda d, n=n: np.floor(d["theta_true"] / (2 * math.pi) * n) * (2 * math.pi / n)))
    v.append(("exact angle", "encoder", lambda d: d["theta_true"]))
    for e in (0.1, 0.5, 1.0):
        v.append((f"speed error {e:g} % of f_e", "speed",
                  lambda d, e=e: d["theta"] + e / 100 * we / np_ * d["t"]))
    for e in (1.0, 5.0, 10.0):
        v.append((f"speed error {e:g} % of f_slip", "speed",
                  lambda d, e=e: d["theta"] + e / 100 * (we - np_ * d["speed_rad_s"]) / np_ * d["t"]))
    for s in (0.1, 0.3, 1.0, 3.0):
        v.append((f"jitter {s:g} el. deg rms", "jitter",
                  lambda d, s=s: d["theta"] + np.random.default_rng(7).normal(0.0, math.radians(s) / np_, len(d["t"]))))
    for k in (1.1, 0.9):
        def obs(d, k=k):
            slip = we - np_ * d["speed_rad_s"]          # true slip [el. rad/s]
            dw = (1.0 - 1.0 / k) * slip / np_           # speed error of the observer [mech. rad/s]
            dt = np.diff(d["t"], prepend=d["t"][0])
            return d["theta"] + np.cumsum(dw * dt)
        v.append((f"slip observer, T_R_hat = {k:g} T_R", "observer", obs))
    return v


def load(path):
    with open(path) as f:
        head = f.readline().strip().split(",")
    names = list(COLS) + ["theta_true", "speed_rad_s", "T_R_true_s", "R_S_true_ohm"]
    arr = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[head.index(c) for c in names])
    return {c: arr[:, k] for k, c in enumerate(names)}


def record_text(d, theta):
    m = np.column_stack([d[c] for c in COLS[:-1]] + [theta])
    lines = [",".join(COLS)]
    # 9 significant digits: the angle to 1e-8 rad over the record, the samples as the sim wrote them
    lines += [",".join("%.9g" % x for x in row) for row in m]
    return "\n".join(lines) + "\n"


def run(runmod, sim, rep, work, jobs, quick, say):
    """runmod: the study's run module (point, sim_args, run_sim, replay_args, run_replay)."""
    pts = [runmod.point("4kw", 50, 100, 3001), runmod.point("4kw", 50, 25, 3002)]
    if not quick:
        pts.append(runmod.point("4kw", 100, 100, 3003))
    dur = 8.0 if quick else 12.0
    out = []
    for p in pts:
        path = os.path.join(work, p["name"] + "_angle.csv")
        runmod.run_sim(sim, runmod.sim_args(p, dur, False), path)
        d = load(path)
        os.remove(path)
        tr_true, rs_true = float(np.mean(d["T_R_true_s"])), float(np.mean(d["R_S_true_ohm"]))

        def one(var, p=p, d=d, tr_true=tr_true, rs_true=rs_true):
            name, group, fn = var
            rows = runmod.run_replay(rep, runmod.replay_args(p, 1.0), "-", stdin=record_text(d, fn(d)))
            rows = [r for r in rows if r["tr_reason"] != "warmup"]
            fin = [r for r in rows if math.isfinite(float(r["T_R_s"]))]
            val = [r for r in rows if r["tr_valid"] == "1"]
            reasons = {}
            for r in rows:
                if r["tr_valid"] != "1":
                    reasons[r["tr_reason"]] = reasons.get(r["tr_reason"], 0) + 1

            def med(rs, key, truth):
                return float(np.median([100 * (float(r[key]) / truth - 1) for r in rs])) if rs else float("nan")
            return dict(point=p["name"], slip_hz=p["slip_hz"], f_hz=p["f_hz"], variant=name, group=group,
                        windows=len(rows), tr_valid=len(val) / len(rows) if rows else float("nan"),
                        e_tr_all=med(fin, "T_R_s", tr_true), e_tr_valid=med(val, "T_R_s", tr_true),
                        e_rs_all=med(fin, "R_S_ohm", rs_true),
                        pe_med=float(np.median([100 * float(r["pe_k2_rel"]) for r in fin])) if fin else float("nan"),
                        reasons="; ".join(f"{k} {n}" for k, n in sorted(reasons.items(), key=lambda kv: -kv[1])))

        with ThreadPoolExecutor(max_workers=jobs) as ex:
            out += list(ex.map(one, variants(p)))
        say(f"angle: {p['name']} done")
    return out


def markdown(tab):
    def f(x, fmt):
        return "–" if x != x else fmt % x
    pts = []
    for r in tab:
        if r["point"] not in pts:
            pts.append(r["point"])
    head = ("12-s steady recordings (11 windows of 1 s after the warm-up), the angle replaced as "
            "tools/studies/integration/angle.py describes; T_R error against the simulator's "
            "(median over the windows with a finite estimate, and over the valid ones).\n\n")
    out = [head]
    for pt in pts:
        rows = [r for r in tab if r["point"] == pt]
        out.append("**%s** (f_e %.1f Hz, slip %.2f Hz, i.e. %.1f %% of f_e)\n" % (
            pt, rows[0]["f_hz"], rows[0]["slip_hz"], 100 * rows[0]["slip_hz"] / rows[0]["f_hz"]))
        out.append("| angle | T_R valid | T_R error, all / valid [%] | R_S error, all [%] | PE index K2, median [%] | refused as |")
        out.append("|---|---|---|---|---|---|")
        for r in rows:
            out.append("| %s | %.0f %% | %s / %s | %s | %s | %s |" % (
                r["variant"], 100 * r["tr_valid"], f(r["e_tr_all"], "%+.2f"), f(r["e_tr_valid"], "%+.2f"),
                f(r["e_rs_all"], "%+.1f"), f(r["pe_med"], "%.1f"), r["reasons"] or "–"))
        out.append("")
    return "\n".join(out) + "\n"
