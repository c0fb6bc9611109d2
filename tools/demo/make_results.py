#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""imest demo: windows tables, figures and summary from the raw run.

Usage: /usr/bin/python3 tools/demo/make_results.py OUT_DIR [--timings FILE]

Reads OUT_DIR/raw/ (written by imest-demo and imest-monitor, see tools/demo/README.md):
  <exp>_direct.csv        per window: the library's result, the simulator's truth, drive state
  <exp>_monitor.csv       per window: what imest-monitor decoded from <exp>.candump.log
  <exp>_monitor.log       imest-monitor's stderr (events and the summary line)
  exp1_wave.csv           exp1 waveforms, measured and simulated with the identified parameters
  exp1_identified.csv     which exp1 window gave the identified parameters
Writes OUT_DIR/{windows.csv, exp1_windows.csv, ifoc_fixed_windows.csv,
ifoc_adaptive_windows.csv, ifoc11_*_windows.csv, duty4kw_windows.csv, exp2_avg30.csv, exp2_avg120.csv, fig*.png, summary.md}.
Plots with matplotlib's Agg backend (Debian python3-matplotlib).
"""
import csv
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.patches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

EXPS = ["exp1", "exp2", "ifoc_fixed", "ifoc_adaptive", "ifoc11_fixed", "ifoc11_adaptive", "duty4kw"]
WIN_FILE = {"exp2": "windows.csv", "exp1": "exp1_windows.csv",
            "ifoc_fixed": "ifoc_fixed_windows.csv", "ifoc_adaptive": "ifoc_adaptive_windows.csv",
            "ifoc11_fixed": "ifoc11_fixed_windows.csv", "ifoc11_adaptive": "ifoc11_adaptive_windows.csv",
            "duty4kw": "duty4kw_windows.csv"}
# The duty-cycle run (tools/demo/demo.c, duty4kw): imsim preset 4kw, V/f at its rated point
# (390 V, 50 Hz), 75 % of rated torque, heating 6x faster over a sixth of the duration.
DUTY = dict(exp="duty4kw", fig="fig14_duty_4kw.png", rated=26.5, load_rel=0.75, time_x=6.0)
RATED_TORQUE = 2.064
GREY = "0.55"
# The demo's set-up (tools/demo/demo.c, imsim's defaults and the paper's motor): the
# encoder and the sampling rate place the quantisation pattern of the angle, the motor
# constants turn the IFOC's torque reference into its current commands.
ENCODER_COUNTS = 4096
FS_HZ = 4000.0
FILTER_HZ = 100.0          # imest's front-end Butterworth
ALIAS_ZONE_HZ = 200.0      # encoder pattern below this: R_S biased (tools/demo/README.md)
POLE_PAIRS = 2
LR_H = 0.2908
# The IFOC pairs: the paper's motor (fig11) and the 11 kW drive at half load (fig12; imsim
# preset 11kw, heating 6x faster over a sixth of the duration: tools/demo/demo.c).
IFOC_PAIRS = [
    dict(fixed="ifoc_fixed", adaptive="ifoc_adaptive", fig="fig11_ifoc_closed_loop.png",
         rated=RATED_TORQUE, lr=LR_H, np=POLE_PAIRS, time_x=1.0,
         title="the heat run (30 Hz / 850 r/min, 2.064 N m)", motor="the paper's motor"),
    dict(fixed="ifoc11_fixed", adaptive="ifoc11_adaptive", fig="fig12_ifoc_11kw.png",
         rated=72.0, lr=0.078331, np=2, time_x=6.0,
         title="an 11 kW drive (rated speed, 36 N m = half load; heating 6x faster, time scaled)",
         motor="the 11 kW drive at half load"),
]

# What each verdict means, for the summary (README, "When is a window valid").
REASON_TEXT = {
    "warmup": "filters still settling (start of the record or after a fault)",
    "input_fault": "a non-finite or absurd sample",
    "adc_saturation": "a sample reached the ADC range",
    "encoder_fault": "an angle step beyond the speed limit",
    "no_current": "stator current below min_current_a",
    "standstill": "rotor at rest without AC excitation",
    "zero_slip": "rotor currents ~0, as without load at constant speed: T_R not observable",
    "numeric": "non-finite or degenerate window sums",
    "no_root": "no admissible stationary point",
    "not_minimum": "Hessian not positive definite at the selected point",
    "poorly_determined": "parametric error index of K2 above max_pe_k2_rel (too little slip "
                         "or excitation in the window)",
    "high_residual": "E_I above max_ei",
    "rs_out_of_range": "R_S outside [rs_min_ohm, rs_max_ohm]",
}


def fnum(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return math.nan


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# --------------------------------------------------------------------------------------
# Windows: CAN-decoded values joined with the truth


def monitor_report(path):
    """Counts from imest-monitor's summary line (stderr)."""
    rep = {"frames": None, "windows": None, "incomplete": None, "lost": None, "repeated": None,
           "corrupted": None, "estimator gaps": None, "malformed lines": None, "events": 0}
    if not os.path.exists(path):
        return rep
    with open(path) as f:
        text = f.read()
    for line in text.splitlines():
        if "summary:" in line:
            for key in list(rep):
                m = re.search(re.escape(key) + r" (\d+)", line)
                if m:
                    rep[key] = int(m.group(1))
        elif line.startswith("imest-monitor:"):
            rep["events"] += 1
    return rep


def build_windows(raw, exp):
    direct = read_csv(os.path.join(raw, f"{exp}_direct.csv"))
    mon_path = os.path.join(raw, f"{exp}_monitor.csv")
    mon = {}
    if os.path.exists(mon_path):
        for r in read_csv(mon_path):
            if r.get("seq", "") != "":
                mon[int(r["seq"])] = r
    rows, mismatches, missing = [], 0, 0
    for d in direct:
        seq = int(d["seq"])
        m = mon.get(seq)
        row = {"experiment": exp, "seq": seq, "t_end_s": d["t_end_s"]}
        if m is not None and m.get("frames", "").upper() == "0X3F":  # all 6 frames (port/README.md)
            src = m
            row["via_can"] = 1
            # the bus carries float32: compare with the library's double, rounded
            for key in ("T_R_s", "R_S_ohm"):
                a, b = fnum(m[key]), float(np.float32(fnum(d[key])))
                if not (a == b or (math.isnan(a) and math.isnan(b))
                        or abs(a - b) <= 1e-6 * abs(b)):
                    mismatches += 1
            if m["valid"] != d["valid"] or m["status"] != d["status"]:
                mismatches += 1
        else:
            src = d
            row["via_can"] = 0
            missing += 1
        for key in ("T_R_s", "R_S_ohm", "valid", "status"):
            row[key] = src[key]
        row["T_R_true_s"] = d["T_R_true_s"]
        row["R_S_true_ohm"] = d["R_S_true_ohm"]
        tr, rs = fnum(row["T_R_s"]), fnum(row["R_S_ohm"])
        trt, rst = fnum(d["T_R_true_s"]), fnum(d["R_S_true_ohm"])
        row["T_R_err_pct"] = "%.4f" % (100 * (tr / trt - 1)) if tr == tr else "nan"
        row["R_S_err_pct"] = "%.4f" % (100 * (rs / rst - 1)) if rs == rs else "nan"
        for key in ("E_I", "pe_k1_rel", "pe_k2_rel"):
            row[key] = src[key]
        # Per-parameter verdicts: from the library's result (the CAN frames carry only the
        # window's verdict); an older demo without them: both equal the window's.
        for key, fallback in (("tr_valid", "valid"), ("tr_reason", "status"),
                              ("rs_valid", "valid"), ("rs_reason", "status")):
            row[key] = d.get(key, d[fallback])
        for key in ("n_roots", "n_admissible", "slip_ratio", "i_rms_a", "used_samples", "flags",
                    "speed_rad_s", "torque_nm", "load_nm", "i_phase_rms_a", "temp_stator_c",
                    "temp_rotor_c", "torque_ref_nm", "torque_err_rms_nm", "psi_r_wb",
                    "psi_ref_wb", "ifoc_T_R_s"):
            row[key] = d[key]
        # the T_R tracker's output after this window (imest_tracker.h; the adaptive runs' controller
        # uses it from the next window on), when the demo wrote it
        for key in ("tr_bound_rel", "trk_T_R_s", "trk_state", "trk_age_s", "trk_bound_rel", "rs_bound_rel"):
            if key in d:
                row[key] = d[key]
        # the temperatures from this window's R_S and T_R (imest_temperature.h), when written
        for key in TEMP_KEYS:
            if key in d:
                row[key] = d[key]
        rows.append(row)
    return rows, mismatches, missing, len(mon)


TEMP_KEYS = ("est_stator_c", "est_stator_uncert_k", "est_stator_valid", "est_rotor_c",
             "est_rotor_uncert_k", "est_rotor_valid")


TEMP_SOURCE = {"stator": "rs_valid", "rotor": "tr_valid"}


def temp_stats(a, by_estimate=False):
    """Per body: (valid windows, windows, mean |err| K, max |err| K, mean signed err K, mean
    uncertainty K) of the estimated temperature against the simulator's, over the windows whose
    temperature is valid (by_estimate: whose R_S or T_R is valid, the tolerance aside)."""
    out = {}
    for body in ("stator", "rotor"):
        ok = a[TEMP_SOURCE[body]] if by_estimate else a[f"est_{body}_valid"] == 1
        ok = ok & np.isfinite(a[f"est_{body}_c"])
        err = a[f"est_{body}_c"][ok] - a[f"temp_{body}_c"][ok]
        if len(err) == 0:
            out[body] = (0, len(ok), math.nan, math.nan, math.nan, math.nan)
        else:
            out[body] = (len(err), len(ok), float(np.mean(np.abs(err))), float(np.max(np.abs(err))),
                         float(np.mean(err)), float(np.mean(a[f"est_{body}_uncert_k"][ok])))
    return out


def fig_temperatures(path, a, sub):
    """The heat run's stator and rotor temperatures from the estimates (valid windows) against
    the simulator's thermal truth, and their errors with the stated uncertainty."""
    fig, axs = plt.subplots(2, 2, figsize=(12, 7), sharex=True)
    t = a["t_end_s"] / 60.0
    for col, (body, tol) in enumerate((("stator", 3.0), ("rotor", 5.0))):
        ok = a[f"est_{body}_valid"] == 1
        est_ok = a[TEMP_SOURCE[body]] & ~ok  # the estimate valid, its temperature's uncertainty too large
        ax = axs[0][col]
        ax.plot(t, a[f"temp_{body}_c"], "k-", lw=1.2, label="simulator (truth)")
        ax.plot(t[ok], a[f"est_{body}_c"][ok], ".", ms=2, label="estimated, valid windows")
        if est_ok.any():
            ax.plot(t[est_ok], a[f"est_{body}_c"][est_ok], ".", ms=2, color="tab:orange",
                    label=f"estimated, {TEMP_SOURCE[body]} but uncertainty > {tol:g} K")
        ax.set_ylabel(f"{body} temperature [°C]")
        ax.set_title(f"{body}: resistance method from {'R_S' if body == 'stator' else 'T_R'}")
        ax.legend(loc="lower right", fontsize=8)
        ax = axs[1][col]
        err = a[f"est_{body}_c"] - a[f"temp_{body}_c"]
        ax.plot(t[ok], err[ok], ".", ms=2, label="error (valid windows)")
        if est_ok.any():
            ax.plot(t[est_ok], err[est_ok], ".", ms=2, color="tab:orange", label=f"error ({TEMP_SOURCE[body]} only)")
        u = a[f"est_{body}_uncert_k"]
        sel = ok | est_ok
        ax.plot(t[sel], u[sel], "-", color="0.6", lw=0.8, label="± stated uncertainty")
        ax.plot(t[sel], -u[sel], "-", color="0.6", lw=0.8)
        ax.axhline(tol, color="r", ls=":", lw=0.8, label=f"goal ±{tol:g} K")
        ax.axhline(-tol, color="r", ls=":", lw=0.8)
        ax.set_ylabel("estimated − true [K]")
        ax.set_xlabel("time [min]")
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle(f"Motor temperatures from the estimates (imest_temperature.h)\n{sub}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def temperature_section(a):
    st = temp_stats(a)
    md = ["## Stator and rotor temperatures (exp. 2, imest_temperature.h)\n",
          "Each window's R_S and T_R turned into temperatures by the resistance method, referenced "
          "to the motor's cold R_S and T_R at the simulator's ambient (k = 1/alpha - t_amb for both "
          "bodies: the simulator heats the rotor with copper's coefficient too). Error = estimated "
          "- simulator, over the windows whose temperature is valid (estimate valid and stated "
          "uncertainty within 3 K stator, 5 K rotor).\n",
          "| body | valid / windows | mean abs error [K] | max abs error [K] | mean signed [K] | "
          "mean stated uncertainty [K] | goal | met |",
          "|---|---:|---:|---:|---:|---:|---:|---|"]
    se = temp_stats(a, by_estimate=True)
    for body, goal in (("stator", 3.0), ("rotor", 5.0)):
        for label, s in ((body, st[body]), (f"{body}, every window with {TEMP_SOURCE[body]}", se[body])):
            n, tot, mean, mx, bias, unc = s
            if n == 0:  # no number to show: say why, as the other tables do
                why = ("no valid window: the stated uncertainty is above the tolerance"
                       if label == body else "no valid window")
                md.append(f"| {label} | 0 / {tot} | – | – | – | – | ±{goal:g} K | {why} |")
                continue
            met = "yes" if mx <= goal else "no"
            md.append(f"| {label} | {n} / {tot} | {mean:.2f} | {mx:.2f} | {bias:+.2f} | {unc:.2f} | "
                      f"±{goal:g} K | {met} |")
    md.append("")
    md.append("A temperature is valid only where its stated uncertainty is within the tolerance: the "
              "second row of each body shows the error where the estimate is valid whatever the "
              "uncertainty (the stator's is mostly rs_bound_rel, which the estimator states "
              "conservatively).\n")
    return md


def write_rows(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def arrays(rows):
    a = {}
    for key in rows[0]:
        if key in ("experiment", "status", "tr_reason", "rs_reason"):
            a[key] = np.array([r[key] for r in rows])
        else:
            a[key] = np.array([fnum(r[key]) for r in rows])
    for key in ("valid", "tr_valid", "rs_valid"):
        a[key] = a[key] == 1
    # where the encoder's quantisation pattern lies in the sampled band (see encoder_alias_hz)
    a["counts_per_sample"] = a["speed_rad_s"] * ENCODER_COUNTS / (2 * math.pi * FS_HZ)
    a["enc_alias_hz"] = encoder_alias_hz(a["counts_per_sample"])
    return a


def encoder_alias_hz(cps):
    """Frequency of the strongest low-frequency line of the angle's quantisation error.

    At c counts per sample the error of a floor-quantised angle is the sawtooth frac(c k + phi)
    (one count peak to peak). When c is near an integer or a half-integer it repeats almost
    every sample or every second sample, and its slow part is a sawtooth of +-1/2 or +-1/4
    count at fs * |c - round(c)| or fs * |2c - round(2c)| (the other fractions p/q give
    +-1/(2q) count, less). Below about 2x the front end's cut-off it passes into the speed
    channel (tools/demo/README.md, "R_S and the encoder")."""
    cps = np.asarray(cps, dtype=float)
    f1 = FS_HZ * np.abs(cps - np.round(cps))
    f2 = FS_HZ * np.abs(2 * cps - np.round(2 * cps))
    return np.minimum(f1, f2)


def spans(t, sel):
    """Contiguous runs of sel as (start, end) pairs of t."""
    out, start = [], None
    for i, s_ in enumerate(sel):
        if s_ and start is None:
            start = i
        if start is not None and (not s_ or i == len(sel) - 1):
            end = i if s_ else i - 1
            out.append((t[start], t[end]))
            start = None
    return out


def reason_counts(reasons, ok):
    """'zero_slip 1, poorly_determined 1' for the windows that are not ok."""
    c = {}
    for r, v in zip(reasons, ok):
        if not v:
            c[r] = c.get(r, 0) + 1
    return sorted(c.items(), key=lambda kv: (-kv[1], kv[0]))


def block_avg(a, period):
    """Paper eq. after Fig. 6: average of the valid 1-s estimates in consecutive blocks."""
    k = np.floor(a["t_end_s"] / period + 1e-9).astype(int)
    out = []
    for b in range(0, int(k.max()) + 1 if len(k) else 0):
        sel = k == b
        n_all = int(sel.sum())
        if n_all == 0:
            continue
        row = {"t_end_s": (b + 1) * period, "n_windows": n_all,
               "n_valid": int((sel & a["valid"]).sum())}
        # T_R from the windows whose T_R is valid, R_S from those whose R_S is valid
        for key, tkey, okkey, nkey in (("T_R_s", "T_R_true_s", "tr_valid", "n_tr_valid"),
                                       ("R_S_ohm", "R_S_true_ohm", "rs_valid", "n_rs_valid")):
            v = sel & a[okkey]
            n_v = int(v.sum())
            row[nkey] = n_v
            row[key] = float(np.mean(a[key][v])) if n_v else math.nan
            # truth over the same windows the average uses (all of the block if none valid)
            row[tkey] = float(np.mean(a[tkey][v if n_v else sel]))
        out.append(row)
    return out


def why_none(a, okkey, rkey, top=2):
    """What a summary cell says when a run has no valid window for a parameter: its most common
    reason(s), e.g. 'no valid window: 599/600 rs_uncertain, 1/600 warmup'."""
    n = len(a[okkey])
    rc = reason_counts(a[rkey], a[okkey])
    if not rc:
        return "no window"
    return "no valid window: " + ", ".join(f"{c}/{n} {r}" for r, c in rc[:top])


def stat_cells(s, why, fmt=("{:.2f}", "{:.2f}", "{:+.2f}"), idx=(1, 3, 4)):
    """Cells of err_stats s (n first, then the statistics at idx); with no valid value the first
    statistic's cell gives the reason (why) and the others a dash, never 'nan'."""
    if s[0] == 0:
        return [str(0), why] + ["–"] * (len(idx) - 1)
    return [str(s[0])] + [f.format(s[i]) for f, i in zip(fmt, idx)]


def err_stats(est, true):
    """(n, mean |err| %, 95th percentile |err| %, max |err| %, mean signed err %)."""
    r = 100.0 * (np.asarray(est) / np.asarray(true) - 1.0)
    r = r[np.isfinite(r)]
    if len(r) == 0:
        return (0, math.nan, math.nan, math.nan, math.nan)
    e = np.abs(r)
    return (len(e), float(np.mean(e)), float(np.percentile(e, 95)), float(np.max(e)), float(np.mean(r)))


# --------------------------------------------------------------------------------------
# Figures


def mark_invalid(ax, t, valid, label=True):
    inv = ~valid
    if inv.any():
        ax.plot(t[inv], np.full(inv.sum(), 0.03), "x", color=GREY, ms=4, mew=0.8,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"window not valid ({int(inv.sum())})" if label else None)


def robust_ylim(ax, values, truth, pad_frac=0.15):
    v = values[np.isfinite(values)]
    lo = min(np.min(truth), np.percentile(v, 1) if len(v) else np.min(truth))
    hi = max(np.max(truth), np.percentile(v, 99) if len(v) else np.max(truth))
    pad = (hi - lo) * pad_frac + 1e-12
    lo, hi = lo - 1.6 * pad, hi + pad  # room at the bottom for the invalid markers
    ax.set_ylim(lo, hi)
    return lo, hi


def mark_clipped(ax, t, y, lo, hi):
    above, below = y > hi, y < lo
    if above.any():
        ax.plot(t[above], np.full(above.sum(), 0.985), "^", color="tab:red", ms=4,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"valid, above the axis ({int(above.sum())})")
    if below.any():
        ax.plot(t[below], np.full(below.sum(), 0.09), "v", color="tab:red", ms=4,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"valid, below the axis ({int(below.sum())})")


def shade_encoder_zone(ax, a, label=True):
    """Grey band where the encoder's quantisation pattern aliases into the band."""
    zone = a["enc_alias_hz"] < ALIAS_ZONE_HZ
    t = a["t_end_s"] / 60.0
    for i, (t0, t1) in enumerate(spans(t, zone & (a["t_end_s"] > 5))):
        ax.axvspan(t0 - 1 / 120, t1, color="tab:orange", alpha=0.12, lw=0,
                   label=(f"encoder pattern aliased below {ALIAS_ZONE_HZ:.0f} Hz "
                          f"(~{np.median(a['counts_per_sample'][zone]):.2f} counts/sample)"
                          if label and i == 0 else None))


def err_panel(ax, t, err, ok, reasons=None, what="window", pad_frac=0.2, min_half=0.1):
    """Estimate / truth - 1 in %, valid points only; the not-valid ones as grey x at the
    bottom, counted (with their reasons) in the legend."""
    e = err[ok]
    ax.axhline(0, color="k", lw=0.8)
    ax.plot(t[ok], e, ".", ms=2.5, color="tab:blue")
    f = e[np.isfinite(e)]
    lo = min(np.percentile(f, 0.5), 0) if len(f) else -min_half
    hi = max(np.percentile(f, 99.5), 0) if len(f) else min_half
    pad = pad_frac * (hi - lo) + 1e-9
    lo, hi = min(lo - 1.6 * pad, -min_half), max(hi + pad, min_half)
    ax.set_ylim(lo, hi)
    mark_clipped(ax, t[ok], e, lo, hi)
    inv = ~ok
    if inv.any():
        why = ""
        if reasons is not None:
            why = ": " + ", ".join(f"{r} {n}" for r, n in reason_counts(reasons, ok))
        ax.plot(t[inv], np.full(inv.sum(), 0.03), "x", color=GREY, ms=4, mew=0.8,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"{what} not valid, not plotted ({int(inv.sum())}{why})")
    ax.set_ylabel("error [%]\nestimate / truth - 1")
    ax.grid(alpha=0.3)
    return lo, hi


def fig_estimates(path, a, key, tkey, okkey, reasonkey, ylabel, title, note, encoder=False):
    t = a["t_end_s"] / 60.0
    fig, (ax, ae) = plt.subplots(2, 1, figsize=(10, 7.0), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 2]})
    v = a[okkey]
    ax.plot(t[v], a[key][v], ".", ms=2.5, color="tab:blue", label=f"estimate, valid 1-s window ({int(v.sum())})")
    ax.plot(t, a[tkey], "-", color="k", lw=1.4, label="truth (window mean of the simulator)")
    lo, hi = robust_ylim(ax, a[key][v], a[tkey])
    mark_clipped(ax, t[v], a[key][v], lo, hi)
    mark_invalid(ax, t, v)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8, framealpha=0.9, title=note, title_fontsize=8)
    err_panel(ae, t, 100.0 * (a[key] / a[tkey] - 1.0), v, a[reasonkey])
    if encoder:
        shade_encoder_zone(ae, a)
        shade_encoder_zone(ax, a, label=False)
    ae.set_xlabel("time [min]")
    ae.legend(loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_blocks(path, a, blocks, period, key, tkey, nkey, ylabel, title, note, encoder=False):
    te = np.array([b["t_end_s"] for b in blocks]) / 60.0
    ts = te - period / 60.0
    y = np.array([b[key] for b in blocks])
    ytrue = np.array([b[tkey] for b in blocks])
    nv = np.array([b[nkey] for b in blocks])
    fig, (ax, ae) = plt.subplots(2, 1, figsize=(10, 7.0), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 2]})
    ok = np.isfinite(y)
    lw = 2.2 if period < 60 else 2.8
    ax.hlines(y[ok], ts[ok], te[ok], color="tab:blue", lw=lw,
              label=f"{period:.0f}-s average of the valid 1-s estimates (over its block)")
    ax.plot((ts[ok] + te[ok]) / 2, y[ok], "o", ms=2.5 if period < 60 else 3.5, color="tab:blue")
    ax.plot(a["t_end_s"] / 60.0, a[tkey], "-", color="k", lw=1.0,
            label="truth (1-s window means of the simulator)")
    lo, hi = robust_ylim(ax, y[ok], a[tkey], pad_frac=0.2)
    mark_clipped(ax, (ts[ok] + te[ok]) / 2, y[ok], lo, hi)
    if (~ok).any():
        ax.plot((ts[~ok] + te[~ok]) / 2, np.full((~ok).sum(), 0.03), "x", color=GREY, ms=5,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"block without a valid window ({int((~ok).sum())})")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8, framealpha=0.9, title=note, title_fontsize=8)
    # error of each block's average against the truth over the same windows
    e = 100.0 * (y / ytrue - 1.0)
    ae.hlines(e[ok], ts[ok], te[ok], color="tab:blue", lw=lw)
    lo, hi = err_panel(ae, (ts + te) / 2, e, ok, what="block without a valid window:")
    nw = np.array([b["n_windows"] for b in blocks])
    part = ok & (nv < nw)
    if part.any():
        ae.plot((ts[part] + te[part]) / 2, e[part], "o", mfc="none", mec="tab:red", ms=6,
                label=f"block with not-valid windows left out ({int(part.sum())}; "
                      f"{int((nw - nv)[part].sum())} windows)")
    if encoder:
        shade_encoder_zone(ae, a)
        shade_encoder_zone(ax, a, label=False)
    ae.set_xlabel("time [min]")
    if ae.get_legend_handles_labels()[0]:
        ae.legend(loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def stats_note(n, mean, p95, mx, bias):
    return f"|error|: mean {mean:.2f} %, 95th pct {p95:.2f} %, max {mx:.2f} % (n = {n}); bias {bias:+.2f} %"


def fig_exp1(out, wave, ident, exp1rows):
    t = wave["t_s"]
    tr_id, rs_id = ident["T_R_s"], ident["R_S_ohm"]
    if str(ident["valid"]) == "1":
        how = (f"identified in window {ident['seq']} (valid): T_R = {tr_id:.4f} s, "
               f"R_S = {rs_id:.3f} Ω")
    else:
        how = (f"{ident['source']}, status {ident['status']}: T_R = {tr_id:.4f} s, "
               f"R_S = {rs_id:.3f} Ω")
    files = []
    # Fig. 2: voltages. 60 periods in a second draw a solid band, so the top panel shows what
    # changes over the second, the amplitude (the voltage vector's length, one period's mean, and
    # its envelope), with a few periods from mid-run as an inset; the bottom panel the start.
    fig, axs = plt.subplots(2, 1, figsize=(10, 6.4))
    ua, ub = wave["u_alpha_v"], wave["u_beta_v"]
    s = t <= 1.0
    mag = np.hypot(ua, ub)
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    n = max(1, int(round(1.0 / (60.0 * dt))))  # one 60 Hz period of samples
    mean_mag = np.convolve(mag, np.ones(n) / n, mode="same")
    ax = axs[0]
    ax.fill_between(t[s], -mag[s], mag[s], color="tab:blue", alpha=0.12, lw=0,
                    label=r"envelope $\pm|u_S|$, $|u_S| = \sqrt{u_{Sa}^2 + u_{Sb}^2}$ per sample")
    ax.plot(t[s], mean_mag[s], color="tab:blue", lw=1.2, label=r"$|u_S|$, mean over one 60 Hz period")
    ax.axhline(0, color="0.6", lw=0.6)
    mid = float(np.median(mean_mag[s & (t > 0.1)])) if (s & (t > 0.1)).any() else float(np.max(mag))
    ax.set_ylim(-1.9 * mid, 1.45 * mid)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("voltage [V]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ins = ax.inset_axes([0.55, 0.04, 0.43, 0.42])
    z = (t >= 0.5) & (t <= 0.55)
    ins.plot(t[z], ua[z], lw=1.0, label=r"$u_{Sa}$")
    ins.plot(t[z], ub[z], lw=1.0, label=r"$u_{Sb}$")
    ins.set_title("0.50-0.55 s (3 periods)", fontsize=7, pad=2)
    ins.tick_params(labelsize=6)
    ins.grid(alpha=0.3)
    ins.legend(loc="upper right", fontsize=6, ncol=2)
    ax.indicate_inset_zoom(ins, edgecolor="0.4")
    ax2 = axs[1]
    s = t <= 0.05
    ax2.plot(t[s], ua[s], lw=1.2, label=r"$u_{Sa}$")
    ax2.plot(t[s], ub[s], lw=1.2, label=r"$u_{Sb}$")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("voltage [V]")
    ax2.grid(alpha=0.3)
    ax2.legend(loc="upper right", fontsize=8)
    axs[0].set_title("Exp. 1 (cf. paper Fig. 2): sampled two-phase voltages, 60 Hz 230 V applied at rest "
                     "through the PWM inverter:\nthe amplitude over the run-up (inset: three periods)",
                     fontsize=10)
    axs[1].set_title("zoom on the first 50 ms (measured = carrier-period mean of the commanded "
                     "volt-seconds, 12-bit ADC)", fontsize=9)
    fig.tight_layout()
    p = os.path.join(out, "fig02_exp1_voltages.png")
    fig.savefig(p, dpi=110)
    plt.close(fig)
    files.append(p)
    # Fig. 3: current and simulated current
    fig, axs = plt.subplots(2, 1, figsize=(10, 6.4))
    for ax, tmax in zip(axs, (1.0, 0.25)):
        s = t <= tmax
        ax.plot(t[s], wave["i_alpha_a"][s], lw=0.9, color="tab:blue", label=r"$i_{Sa}$ measured (12-bit ADC)")
        ax.plot(t[s], wave["i_alpha_sim_a"][s], lw=0.9, ls="--", color="tab:orange",
                label=r"$i_{Sa,sim}$: motor simulated with the identified $T_R$, $R_S$")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("current [A]")
        ax.grid(alpha=0.3)
    axs[0].set_title("Exp. 1 (cf. paper Fig. 3): phase-a current (two-phase equivalent) and its "
                     "simulated response", fontsize=10)
    axs[1].set_title("zoom on the first 0.25 s", fontsize=9)
    axs[0].legend(loc="upper right", fontsize=8)
    d = wave["i_alpha_a"] - wave["i_alpha_sim_a"]
    rel = math.sqrt(np.mean(d[t <= 1.0] ** 2) / np.mean(wave["i_alpha_a"][t <= 1.0] ** 2))
    axs[0].text(0.01, 0.97, how + f"\nrms(measured - simulated) / rms(measured) over 0-1 s: {100 * rel:.2f} %",
                transform=axs[0].transAxes, fontsize=8, va="top",
                bbox=dict(fc="white", ec="0.8", alpha=0.9))
    fig.tight_layout()
    p = os.path.join(out, "fig03_exp1_current.png")
    fig.savefig(p, dpi=110)
    plt.close(fig)
    files.append(p)
    # Fig. 4: speed
    fig, ax = plt.subplots(figsize=(10, 4.2))
    ax.plot(t, wave["speed_enc_rad_s"], lw=1.0, color="tab:blue", label=r"$\omega$ from the encoder (4096 counts, 5 ms difference)")
    ax.plot(t, wave["speed_sim_rad_s"], lw=1.0, ls="--", color="tab:orange",
            label=r"$\omega_{sim}$: motor simulated with the identified $T_R$, $R_S$")
    ax.plot(t, wave["speed_true_rad_s"], lw=0.8, ls=":", color="k", label=r"$\omega$ true (simulator)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("mechanical speed [rad/s]")
    ax.set_title("Exp. 1 (cf. paper Fig. 4): speed during the run-up", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    ax.text(0.01, 0.97, how, transform=ax.transAxes, fontsize=8, va="top",
            bbox=dict(fc="white", ec="0.8", alpha=0.9))
    fig.tight_layout()
    p = os.path.join(out, "fig04_exp1_speed.png")
    fig.savefig(p, dpi=110)
    plt.close(fig)
    files.append(p)
    return files, rel


def detuning_ratio(a, lr=LR_H, n_p=POLE_PAIRS):
    """T_e / T_e,ref of an IFOC whose T_R is off, in steady state with ideal current control.

    The controller commands i_d = psi_ref / M and i_q = T_ref L_R / (n_p M psi_ref) and the
    slip i_q / (T_R,ctrl i_d). With k = T_R,ctrl / T_R and r = i_q / i_d the rotor flux
    settles at M i / (1 + j r / k) (rotor frame of the controller), which gives
    T_e / T_ref = k (1 + r^2) / (k^2 + r^2): above 1 while 1 < k < r^2, 1 at k = r^2, below
    1 beyond. Returns (ratio, k, r)."""
    k = a["ifoc_T_R_s"] / a["T_R_true_s"]
    r = a["torque_ref_nm"] * lr / (n_p * a["psi_ref_wb"] ** 2)
    return k * (1 + r ** 2) / (k ** 2 + r ** 2), k, r


def torque_sign_change(a, lr=LR_H, n_p=POLE_PAIRS):
    """First sign change (after start-up) of the 1-min smoothed torque error: (t_s, k, r^2)."""
    e = a["torque_nm"] - a["torque_ref_nm"]
    sel = np.isfinite(e) & (a["t_end_s"] > 60)
    t, e = a["t_end_s"][sel], e[sel]
    n = min(61, len(e))
    if n < 3:
        return None
    sm = np.convolve(e, np.ones(n) / n, mode="valid")
    tt = t[n // 2: n // 2 + len(sm)]
    z = np.where(np.sign(sm[:-1]) * np.sign(sm[1:]) < 0)[0]
    if len(z) == 0:
        return None
    i = int(np.argmin(np.abs(a["t_end_s"] - tt[z[0]])))
    _, k, r = detuning_ratio(a, lr, n_p)
    return a["t_end_s"][i], float(k[i]), float(r[i] ** 2)


def sym_ylim(ax, ys, min_half):
    y = np.concatenate(ys)
    y = y[np.isfinite(y)]
    lo, hi = (min(np.min(y), 0), max(np.max(y), 0)) if len(y) else (0.0, 0.0)
    pad = 0.15 * (hi - lo)
    ax.set_ylim(min(lo - pad, -min_half), max(hi + pad, min_half))


def tr_error_panel(ax, fx, ad, tx):
    """The T_R panel's lines differ by a fraction of a percent, so the estimate hides under the
    truth: here the difference itself, estimate / truth - 1 in %. Dots: each valid window's
    estimate (both runs run the estimator; only the adaptive one feeds it to the controller);
    line: the adaptive controller's T_R, which holds the last valid estimate. The fixed
    controller's T_R error (its cold value against the warming rotor) is in the legend only:
    on this axis it would hide the estimator's."""
    ax.axhline(0, color="k", lw=0.8)
    ys = []
    for a, name, col in ((fx, "T_R fixed run", "tab:red"), (ad, "T_R from the estimator run", "tab:green")):
        t = tx * a["t_end_s"] / 60.0
        ok = a["tr_valid"] & (a["t_end_s"] > 5)
        e = 100.0 * (a["T_R_s"] / a["T_R_true_s"] - 1.0)
        ax.plot(t[ok], e[ok], ".", ms=2.5, color=col,
                label=f"estimate, valid window ({int(ok.sum())}), {name.replace('T_R', '$T_R$')}")
        ys.append(e[ok])
    sel = ad["t_end_s"] > 5
    ce = 100.0 * (ad["ifoc_T_R_s"] / ad["T_R_true_s"] - 1.0)
    ax.plot(tx * ad["t_end_s"][sel] / 60.0, ce[sel], "-", color="darkgreen", lw=1.0,
            label="controller's $T_R$, run with $T_R$ from the estimator (the last valid estimate: a window behind)")
    ys.append(ce[sel])
    fe = 100.0 * (fx["ifoc_T_R_s"] / fx["T_R_true_s"] - 1.0)
    fe = fe[np.isfinite(fe)]
    y = np.concatenate(ys)
    y = y[np.isfinite(y)]
    lo, hi = (min(float(np.percentile(y, 0.5)), 0.0), max(float(np.percentile(y, 99.5)), 0.0)) if len(y) else (0.0, 0.0)
    span = max(hi - lo, 0.1)
    # the lower part of the axis is the legend's, so that it covers no point
    ax.set_ylim(lo - 0.9 * span, hi + 0.15 * span)
    if len(fe):
        ax.plot([], [], "-", color="tab:red", lw=1.0,
                label=f"controller's $T_R$, fixed run: off the axis, up to {fe.max():+.1f} %")
    ax.set_ylabel("$T_R$ error [%]\nestimate / truth - 1")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower center", ncol=2, fontsize=7, framealpha=0.9)


# Colours of the verdict timeline: valid green, each reason its own colour (fixed, so that the
# same reason looks the same in every run; an unlisted one takes the next of VERDICT_SPARE).
VERDICT_COLOURS = {
    "valid": "tab:green", "warmup": "0.75", "zero_slip": "tab:orange", "standstill": "gold",
    "no_current": "0.45", "poorly_determined": "tab:purple", "high_residual": "tab:red",
    "no_root": "tab:brown", "not_minimum": "tab:pink", "tr_uncertain": "tab:cyan",
    "rs_uncertain": "tab:blue", "constants_mismatch": "olive", "wiring_mismatch": "black",
    "input_fault": "darkred", "adc_saturation": "magenta", "encoder_fault": "navy",
    "numeric": "0.2", "rs_out_of_range": "saddlebrown", "gain_mismatch": "teal",
    "constants_uncertain": "darkkhaki", "transient": "sandybrown",
}
VERDICT_SPARE = ["lightcoral", "khaki", "lightsteelblue", "plum", "darkseagreen"]


def verdict_labels(a, key_valid, key_reason):
    return np.where(a[key_valid], "valid", a[key_reason])


def fig_verdicts(path, res):
    """One panel per run: two rows of bars (T_R, R_S), one bar per window, coloured by its
    verdict: valid or the reason it is not. Runs of the same verdict are drawn as one bar; a
    run of not-valid windows too short to see at the run's time scale gets a marker on top."""
    runs = [e for e in EXPS if e in res]
    fig, axs = plt.subplots(len(runs), 1, figsize=(10, 1.25 * len(runs) + 1.3), squeeze=False)
    used = {}
    spare = iter(VERDICT_SPARE)
    for ax, exp in zip(axs[:, 0], runs):
        a = res[exp]["a"]
        te = a["t_end_s"]
        minutes = te[-1] > 120
        scale = 60.0 if minutes else 1.0
        start = np.concatenate([[0.0], te[:-1]])
        counts = []
        for row, (kv, kr, name) in enumerate((("tr_valid", "tr_reason", "T_R"), ("rs_valid", "rs_reason", "R_S"))):
            lab = verdict_labels(a, kv, kr)
            y = 1 - row
            i = 0
            while i < len(lab):
                j = i
                while j + 1 < len(lab) and lab[j + 1] == lab[i]:
                    j += 1
                c = VERDICT_COLOURS.get(lab[i])
                if c is None:
                    c = VERDICT_COLOURS[lab[i]] = next(spare, "0.6")
                ax.broken_barh([(start[i] / scale, (te[j] - start[i]) / scale)], (y - 0.4, 0.8),
                               facecolors=c, lw=0)
                if lab[i] != "valid" and te[j] - start[i] < 0.006 * te[-1]:
                    # too narrow to see at this scale: a marker on top of the bar
                    ax.plot([0.5 * (start[i] + te[j]) / scale], [y + 0.3], "v", color=c, ms=5,
                            mec="k", mew=0.4, clip_on=False)
                i = j + 1
            for v in lab:
                used[v] = used.get(v, 0) + 1
            counts.append(f"{name} valid {int(a[kv].sum())}/{len(lab)}")
        ax.set_yticks([1, 0])
        ax.set_yticklabels(["$T_R$", "$R_S$"])
        ax.set_ylim(-0.6, 1.6)
        ax.set_xlim(0, te[-1] / scale)
        ax.set_title(f"{exp}: " + ", ".join(counts), fontsize=9, loc="left", pad=3)
        ax.set_xlabel("time [min]" if minutes else "time [s]", fontsize=8, labelpad=1)
        ax.tick_params(labelsize=8)
        ax.grid(axis="x", alpha=0.3)
    order = ["valid"] + sorted((k for k in used if k != "valid"), key=lambda k: -used[k])
    handles = [matplotlib.patches.Patch(color=VERDICT_COLOURS[k], label=f"{k} ({used[k]})") for k in order if k in used]
    fig.legend(handles=handles, loc="lower center", ncol=min(5, len(handles)), fontsize=8, frameon=False,
               title="verdict of each window (count over all runs and both rows)", title_fontsize=8)
    fig.suptitle("Verdicts per window: valid, or the reason it is not (README, \"When is a window valid\")",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.04 + 0.025 * ((len(handles) + 4) // 5), 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_closed_loop(path, fx, ad, pair=IFOC_PAIRS[0]):
    rated, tx = pair["rated"], pair["time_x"]
    fig, axs = plt.subplots(5, 1, figsize=(10, 13.5), sharex=True,
                            gridspec_kw={"height_ratios": [1, 1, 1, 1, 0.9]})
    # current relative to the tuned drive: the adaptive run's mean after start-up
    i0 = float(np.nanmean(ad["i_phase_rms_a"][ad["t_end_s"] > 5]))
    after = {}
    for a, name, col in ((fx, "IFOC, $T_R$ fixed at the cold value", "tab:red"),
                         (ad, "IFOC, $T_R$ from the estimator", "tab:green")):
        t = tx * a["t_end_s"] / 60.0
        sel = a["t_end_s"] > 5  # the start-up transient would dwarf the hour
        te = 100.0 * (a["torque_nm"] - a["torque_ref_nm"]) / rated
        fe = 100.0 * (a["psi_r_wb"] / a["psi_ref_wb"] - 1.0)
        di = 100.0 * (a["i_phase_rms_a"] / i0 - 1.0)
        axs[0].plot(t[sel], te[sel], lw=1.0, color=col, label=name)
        axs[1].plot(t[sel], fe[sel], lw=1.0, color=col, label=name)
        axs[2].plot(t[sel], di[sel], lw=1.0, color=col, label=name)
        axs[3].plot(t, a["ifoc_T_R_s"], lw=1.0, color=col, label="controller's $T_R$: " + name.split(", ")[1])
        after[id(a)] = (te[sel], fe[sel], di[sel])
    ratio, k, r = detuning_ratio(fx, pair["lr"], pair["np"])
    sel = fx["t_end_s"] > 5
    axs[0].plot(tx * fx["t_end_s"][sel] / 60.0,
                (100.0 * fx["torque_ref_nm"] * (ratio - 1.0) / rated)[sel], "k--", lw=1.0,
                label=r"steady-state detuning: $T_{ref}\,(k(1+r^2)/(k^2+r^2) - 1)$, "
                      r"$k = T_{R,ctrl}/T_R$, $r = i_q/i_d$")
    sc = torque_sign_change(fx, pair["lr"], pair["np"])
    if sc is not None:
        axs[0].axvline(tx * sc[0] / 60.0, color="0.4", lw=0.8, ls=":")
        # the data are above zero before the change and below after: the text goes below-left
        axs[0].annotate(f"sign change at {tx * sc[0] / 60:.1f} min:\n$k$ = {sc[1]:.3f} $\\approx$ $r^2$ = {sc[2]:.3f}",
                        xy=(tx * sc[0] / 60.0, 0), xytext=(-170, -50), textcoords="offset points", fontsize=8,
                        arrowprops=dict(arrowstyle="->", color="0.3", lw=0.8),
                        bbox=dict(fc="white", ec="0.8", alpha=0.9))
    axs[3].plot(tx * ad["t_end_s"] / 60.0, ad["T_R_true_s"], "k-", lw=1.2, label="true $T_R$ (adaptive run)")
    axs[3].plot(tx * fx["t_end_s"] / 60.0, fx["T_R_true_s"], "k:", lw=1.2, label="true $T_R$ (fixed run)")
    axs[0].set_ylabel(f"torque error\n$(T_e - T_{{e,ref}})$ / {rated:g} N m [%]")
    axs[1].set_ylabel("rotor-flux error\n$|\\psi_R|/\\psi_{ref} - 1$ [%]")
    axs[2].set_ylabel(f"stator current\nchange [%] of {i0:.3f} A rms")
    axs[3].set_ylabel("$T_R$ [s]")
    tr_error_panel(axs[4], fx, ad, tx)
    axs[4].set_xlabel("time [min]" if tx == 1.0 else f"heating time [min] (= motor time x {tx:g})")
    axs[0].set_title(f"Beyond the paper: {pair['title']} under IFOC speed control\n"
                     "(1-s window means from t = 5 s; the speed loop holds $T_e$ at the load, so the reference "
                     "absorbs the detuning)", fontsize=10)
    for ax in axs[:4]:
        ax.grid(alpha=0.3)
    for ax in axs[:3]:
        ax.axhline(0, color="0.6", lw=0.6)
    sym_ylim(axs[0], [v[0] for v in after.values()], 0.5)   # at least +-0.5 % of rated torque
    sym_ylim(axs[1], [v[1] for v in after.values()], 2.0)
    sym_ylim(axs[2], [v[2] for v in after.values()], 1.0)   # at least +-1 % of the current
    for ax in axs[:3]:
        ax.legend(loc="best", fontsize=8)
    axs[3].legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def read_commission(raw, name):
    """raw/<name>.csv of imest-demo's commissioning runs: {quantity: row}, or None."""
    path = os.path.join(raw, f"{name}.csv")
    if not os.path.exists(path):
        return None
    return {r["quantity"]: r for r in read_csv(path)}


def fig_duty(path, a, comm):
    """The duty-cycle run: T_R and R_S against the truth over time, each with its error panel
    (valid windows only, like fig05 / fig08)."""
    t = a["t_end_s"] / 60.0
    fig, axs = plt.subplots(4, 1, figsize=(10, 12.0), sharex=True,
                            gridspec_kw={"height_ratios": [3, 2, 3, 2]})
    inv = ""
    if comm is not None and comm.get("valid", {}).get("identified") == "1":
        inv = (f"commissioned inverter: dead time {1e6 * fnum(comm['dead_time']['identified']):.3f} µs, "
               f"drops {fnum(comm['v_switch']['identified']):.3f} V / {fnum(comm['v_diode']['identified']):.3f} V "
               f"+ {1e3 * fnum(comm['r_switch']['identified']):.1f} / {1e3 * fnum(comm['r_diode']['identified']):.1f} mΩ, "
               f"stated uncertainty {100 * fnum(comm['uncertainty']['identified']):.0f} %")
    title = (f"No voltage sensors: the estimator on the duty cycles and V_dc (imest_isr_duty), 4 kW drive\n"
             f"V/f 390 V 50 Hz (rated speed), {100 * DUTY['load_rel']:.0f} % of rated torque, heating "
             f"{DUTY['time_x']:g}x faster (time axis: motor time)\n{inv}")
    for row, (key, tkey, okkey, rkey, label) in enumerate((
            ("T_R_s", "T_R_true_s", "tr_valid", "tr_reason", "$T_R$ [s]"),
            ("R_S_ohm", "R_S_true_ohm", "rs_valid", "rs_reason", "$R_S$ [Ω]"))):
        ax, ae = axs[2 * row], axs[2 * row + 1]
        v = a[okkey]
        ax.plot(t[v], a[key][v], ".", ms=2.5, color="tab:blue",
                label=f"estimate, valid 1-s window ({int(v.sum())} of {len(v)})")
        ax.plot(t, a[tkey], "-", color="k", lw=1.4, label="truth (window mean of the simulator)")
        lo, hi = robust_ylim(ax, a[key][v], a[tkey])
        mark_clipped(ax, t[v], a[key][v], lo, hi)
        mark_invalid(ax, t, v)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        s_ = err_stats(a[key][v], a[tkey][v])
        note = stats_note(*s_) if s_[0] else why_none(a, okkey, rkey)
        bkey = okkey.replace("valid", "bound_rel")
        if not s_[0] and bkey in a and np.isfinite(a[bkey]).any():
            note += f"\n(its error bound {100 * np.nanmedian(a[bkey]):.1f} % > tolerance: README, When is a window valid)"
        ax.legend(loc="best", fontsize=8, framealpha=0.9, title=note, title_fontsize=8)
        err_panel(ae, t, 100.0 * (a[key] / a[tkey] - 1.0), v, a[rkey])
        ae.legend(loc="upper right", fontsize=8, framealpha=0.9)
    axs[0].set_title(title, fontsize=9)
    axs[-1].set_xlabel("time [min]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def duty_commission_rows(comm):
    """The duty-cycle run's commissioning: its state and what it reported (constants, inverter)."""
    md = []
    state = comm["state"]["identified"]
    ok = comm["valid"]["identified"] == "1"
    md.append(f"Commissioning: state **{state}**"
              + (f" ({comm['reason']['identified']})" if comm["reason"]["identified"] != "none" else "")
              + f", {fnum(comm['time_s']['identified']):.1f} s."
              + ("" if ok else " **It did not complete: the run used the true constants and devices.**") + "\n")
    md.append("| what commissioning reported | identified | true | error |")
    md.append("|---|---:|---:|---:|")
    for key, label, scale, unit in (("R_S", "R_S (winding + min(r_sw, r_d))", 1.0, "Ω"),
                                    ("L_S", "L_S", 1e3, "mH"), ("sigma", "σ", 1.0, ""),
                                    ("T_R", "T_R (nominal)", 1e3, "ms"),
                                    ("dead_time", "inverter: dead time", 1e6, "µs"),
                                    ("v_threshold", "inverter: device drops (V_sw0 + V_d0) / 2", 1.0, "V"),
                                    ("r_slope_diff", "inverter: slopes r_sw - r_d", 1e3, "mΩ")):
        if key not in comm:
            continue
        i, t = fnum(comm[key]["identified"]), fnum(comm[key]["true"])
        md.append(f"| {label} | {i * scale:.5g} {unit} | {t * scale:.5g} {unit} | "
                  + (f"{100 * (i / t - 1):+.2f} % |" if t else "|"))
    if "v_switch" in comm:
        g = {k: fnum(comm[k]["identified"]) for k in ("v_switch", "v_diode", "r_switch", "r_diode")}
        t = {k: fnum(comm[k]["true"]) for k in ("v_switch", "v_diode", "r_switch", "r_diode")}
        md.append(f"| inverter: the model applied, V_sw0 / V_d0, r_sw / r_d | {g['v_switch']:.3f} / {g['v_diode']:.3f} V, "
                  f"{1e3 * g['r_switch']:.1f} / {1e3 * g['r_diode']:.1f} mΩ | {t['v_switch']:.3g} / {t['v_diode']:.3g} V, "
                  f"{1e3 * t['r_switch']:.3g} / {1e3 * t['r_diode']:.3g} mΩ | drops split evenly (not separable "
                  "at standstill); the common slope min(r_sw, r_d) is in R_S |")
    if "uncertainty" in comm:
        md.append(f"| inverter: the model's stated uncertainty | {100 * fnum(comm['uncertainty']['identified']):.1f} % "
                  f"| | |")
        md.append(f"| inverter: i_band (zero-crossing fade) | {fnum(comm['i_band']['identified']):.4g} A | | |")
        md.append(f"| inverter: model vs devices, max per-leg error | {fnum(comm['inverter_err_max']['identified']):.3f} V "
                  f"| | (\\|i\\| ≥ 2 i_band, duty 0.05-0.95) |")
    return md


def duty_section(raw, a):
    """The duty-cycle run: what its commissioning reported (constants and the inverter's model)
    and the estimation error with the identified constants against the true ones."""
    name = DUTY["exp"]
    comm = read_commission(raw, f"{name}_commission")
    md = ["## Without voltage sensors: the duty-cycle input (4 kW drive)\n",
          "A drive that knows its phase voltages only from its duty cycles: imsim preset 4kw behind an "
          "8 kHz IGBT inverter (firmware timing, 2 µs dead time, switch 1 V + 20 mΩ, diode 0.8 V + 10 mΩ, "
          "12-bit sensors with 1 % offsets and ±1 % gain errors, the 4096-count encoder). First the "
          "commissioning routine (`imest_commission.h`) runs closed loop on it (shaft free, no load); then "
          "the drive runs V/f at its rated point (390 V, 50 Hz: rated speed) at "
          f"{100 * DUTY['load_rel']:.0f} % of rated torque ({DUTY['load_rel'] * DUTY['rated']:.1f} N m), the "
          f"copper heating {DUTY['time_x']:g}x faster over 1/{DUTY['time_x']:g} of the duration. The estimator "
          "gets the identified constants and inverter model (`imest_comm_apply`), the currents corrected "
          "with the identified offsets and gains, and is fed the duties and the bus voltage "
          "(`imest_isr_duty`), never the phase voltages; telemetry over CAN as the other runs (fig14). "
          "This is where the product is expected to work: rated speed, 50-100 % load, a commissioned "
          "inverter (README, \"Commission, then estimate\": T_R valid on the 4 kW drive; R_S refused "
          "wherever the inverter model's stated uncertainty could move it by more than 5 %).\n"]
    if comm is None:
        md.append("No commissioning record (`--no-commission`): the estimator got the true constants and "
                  "devices.\n")
    else:
        md += duty_commission_rows(comm)
    md.append("")
    n = len(a["t_end_s"])
    slope = ""
    if comm is not None and "R_S_winding" in comm:
        slope = (", so R_S carries the device slope min(r_sw, r_d) that terminal measurements include, here "
                 f"{100 * fnum(comm['R_S']['true']) / fnum(comm['R_S_winding']['true']) - 100:+.2f} %")
    md.append(f"Estimation on the duty cycles, {n} windows of 1 s (error = estimate / truth - 1 over the valid "
              f"windows; the truth is the simulator's winding R_S{slope}):\n")
    md.append("| constants | parameter | valid windows | fraction valid | mean err % | max err % | bias % |")
    md.append("|---|---|---:|---:|---:|---:|---:|")
    tpath = os.path.join(raw, f"{name}_true_constants.csv")
    runs = [("identified constants" if comm is not None else "true constants (no commissioning)", a)]
    if os.path.exists(tpath):
        tr_rows = read_csv(tpath)
        b = {k: np.array([fnum(r[k]) for r in tr_rows]) for k in ("T_R_s", "T_R_true_s", "R_S_ohm", "R_S_true_ohm")}
        for k in ("tr_valid", "rs_valid"):
            b[k] = np.array([r[k] == "1" for r in tr_rows])
        for k in ("tr_reason", "rs_reason"):
            b[k] = np.array([r.get(k, r["status"]) for r in tr_rows])
        runs.append(("true constants and devices", b))
    for label, x in runs:
        for par, key, tkey, okkey, rkey in (("T_R", "T_R_s", "T_R_true_s", "tr_valid", "tr_reason"),
                                            ("R_S", "R_S_ohm", "R_S_true_ohm", "rs_valid", "rs_reason")):
            v = x[okkey]
            s_ = err_stats(x[key][v], x[tkey][v])
            cells = stat_cells(s_, why_none(x, okkey, rkey))
            md.append(f"| {label} | {par} | {cells[0]} / {len(v)} | {100 * v.sum() / max(len(v), 1):.1f} % "
                      f"| {cells[1]} | {cells[2]} | {cells[3]} |")
    if "rs_bound_rel" in a:
        b = a["rs_bound_rel"][np.isfinite(a["rs_bound_rel"])]
        if len(b):
            md.append("")
            md.append(f"R_S's error bound (`rs_bound_rel`: the inverter model's stated uncertainty, the timing, the "
                      f"PWM staircase) is {100 * np.median(b):.1f} % (median over the windows; {100 * np.min(b):.1f}-"
                      f"{100 * np.max(b):.1f} %) against `rs_tolerance` 5 %: where it is above, the window's R_S is "
                      "`rs_uncertain` and the drive must not use it (README, \"When is a window valid\").")
    md.append("")
    return md


def encoder_section(res):
    """R_S inside / outside the spans where the encoder pattern aliases into the band."""
    rows = []
    for exp in ("exp2", "ifoc_fixed", "ifoc_adaptive"):
        if exp not in res:
            continue
        a = res[exp]["a"]
        ok = a["rs_valid"] & (a["t_end_s"] > 5)
        zone = a["enc_alias_hz"] < ALIAS_ZONE_HZ
        e = 100.0 * (a["R_S_ohm"] / a["R_S_true_ohm"] - 1.0)
        cells = []
        for sel in (ok & zone, ok & ~zone):
            cells.append(f"{int(sel.sum())} | {np.mean(e[sel]):+.2f} | {np.max(e[sel]):+.2f}"
                         if sel.any() else "0 | | ")
        cps = a["counts_per_sample"][ok]
        cps_txt = f"{np.min(cps):.3f}-{np.max(cps):.3f}" if len(cps) else ""
        rows.append(f"| {exp} | {cps_txt} | {cells[0]} | {cells[1]} |")
    if not rows:
        return []
    return [
        "## R_S and the encoder\n",
        f"Windows whose encoder pattern aliases below {ALIAS_ZONE_HZ:.0f} Hz (counts per sample within "
        f"{ALIAS_ZONE_HZ / FS_HZ / 2:.3f} of a half-integer or {ALIAS_ZONE_HZ / FS_HZ:.3f} of an integer; "
        f"{ENCODER_COUNTS} counts, {FS_HZ:.0f} Hz) against the rest (valid R_S, t > 5 s):\n",
        "| run | counts / sample | n in zone | R_S bias % | R_S max err % | n outside | R_S bias % | R_S max err % |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
        *rows,
        "",
        "The hump of R_S in exp. 2 (13-21 min, up to +0.8 % in a 1-s window) is the encoder, not the "
        "estimator's maths: the heating rotor slows the motor through 14.5 counts per 4 kHz sample at "
        "16.7 min. A floor-quantised angle errs by the sawtooth frac(c k), one count peak to peak; near "
        "c = n + 1/2 it repeats every second sample, and what remains after the estimator's 100 Hz "
        "filter is a sawtooth of +-1/4 count at 4000 Hz x |2c - round(2c)|, i.e. a speed error. "
        "Measured by re-running exp. 2 with the angle given to imest quantised differently (same "
        "motor, same noise): over 13-21 min the R_S error is +0.32 % mean, +0.82 % max with 4096 "
        "counts, -0.12 % and +0.08 % with 65536 counts or the exact angle (T_R -0.024 % in all three). "
        "Binned by the pattern's frequency the R_S excess over the exact angle is +0.04 % below 10 Hz "
        "(exactly 14.5 counts/sample: the pattern stands still, no speed error), +0.72 % at 100-120 Hz, "
        "+0.39 % at 150-200 Hz, +0.07 % above 300 Hz; it follows the in-band speed-error power "
        "(correlation 0.84; 0.08 rad/s rms at the peak against 0.02 elsewhere). The IFOC runs hold "
        "850 r/min = 14.507 counts/sample for the whole hour (pattern at 54 Hz): their R_S carries "
        "+0.39 % from the encoder (+0.15 % against -0.24 % with the exact angle, first 15 min). "
        "Details: tools/demo/README.md, \"R_S and the encoder\".",
        "",
    ]


def ifoc11_section(fx, ad, pair):
    """The IFOC pair on the 11 kW drive: the table of ifoc_section and one summary line."""
    md = [f"## Beyond the paper's motor: IFOC on {pair['motor']}, controller T_R fixed vs from the "
          "estimator\n",
          "imsim preset 11kw (8 kHz PWM drive with firmware timing, 16384-count encoder, 12-bit ADCs of "
          "+-75 A), speed loop to rated speed from rest, 36 N m (half load) from 2.5 s; copper heating "
          f"{pair['time_x']:g}x faster over 1/{pair['time_x']:g} of the duration, so the rotor warms as in "
          "the heat run; the estimator as for the paper's motor with this motor's L_S, sigma and 8 kHz "
          f"(fig12). Spans in motor time; torque error in % of the rated {pair['rated']:g} N m.\n"]
    md += ifoc_table(fx, ad, pair["rated"], last_s=300.0 / pair["time_x"])
    last = []
    for a in (fx, ad):
        sel = a["t_end_s"] > a["t_end_s"][-1] - 300.0 / pair["time_x"]
        last.append(float(np.nanmean(np.abs(a["torque_nm"] - a["torque_ref_nm"])[sel])) * 100 / pair["rated"])
    nv, n = int(ad["tr_valid"][ad["t_end_s"] > 5].sum()), int((ad["t_end_s"] > 5).sum())
    md.append(f"ifoc11: mean |torque error| at the end {last[0]:.3f} % of rated with T_R fixed, "
              f"{last[1]:.3f} % with T_R from imest; T_R valid in {nv} of {n} windows"
              + (" (no valid window: the adaptive run keeps the cold T_R, as the fixed one)" if nv == 0 else "")
              + ".\n")
    return md


def ifoc_table(fx, ad, rated, last_s=300.0):
    md = ["| run | span | mean abs torque err [% rated] | max abs torque err [% rated] | mean flux err % "
          "| stator current [A rms] | controller T_R [s] | true T_R [s] | T_R valid windows |",
          "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for a, label in ((fx, "T_R fixed (cold)"), (ad, "T_R from imest")):
        tend = a["t_end_s"][-1]
        for span, sel in (("whole run", a["t_end_s"] > 5),
                          (f"last {last_s / 60:.3g} min", a["t_end_s"] > max(tend - last_s, 5))):
            te = 100 * np.abs(a["torque_nm"] - a["torque_ref_nm"])[sel] / rated
            fe = 100 * (a["psi_r_wb"] / a["psi_ref_wb"] - 1)[sel]
            md.append(f"| {label} | {span} | {np.nanmean(te):.3f} | {np.nanmax(te):.3f} | {np.nanmean(fe):+.2f} "
                      f"| {np.nanmean(a['i_phase_rms_a'][sel]):.3f} | {np.nanmean(a['ifoc_T_R_s'][sel]):.4f} "
                      f"| {np.nanmean(a['T_R_true_s'][sel]):.4f} | {int(a['tr_valid'][sel].sum())} / {int(sel.sum())} |")
    md.append("")
    return md


def ifoc_section(fx, ad):
    md = ["## Beyond the paper: IFOC heat run, controller T_R fixed vs from the estimator\n",
          "Torque error = electromagnetic torque - controller's torque reference (1-s means), in % of "
          "the rated 2.064 N m; flux error = |psi_R| / psi_ref - 1. 'whole run' = t > 5 s (after "
          "start-up); 'last 5 min' = the end of the heat run. The controller's T_R follows every "
          "valid window (imest-demo).\n"]
    md += ifoc_table(fx, ad, RATED_TORQUE)
    i0 = float(np.nanmean(ad["i_phase_rms_a"][ad["t_end_s"] > 5]))
    di = 100 * (fx["i_phase_rms_a"] / i0 - 1)
    te_ad = (100 * (ad["torque_nm"] - ad["torque_ref_nm"]) / RATED_TORQUE)[ad["t_end_s"] > 5]
    # why the fixed-T_R torque error changes sign: steady-state detuning
    ratio, k, r = detuning_ratio(fx)
    sel = fx["t_end_s"] > 5
    meas = 100 * (fx["torque_nm"] - fx["torque_ref_nm"]) / RATED_TORQUE
    pred = 100 * fx["torque_ref_nm"] * (ratio - 1) / RATED_TORQUE
    dev = float(np.sqrt(np.nanmean(((meas - pred)[sel]) ** 2))) if sel.any() else math.nan
    sc = torque_sign_change(fx)
    if sel.any():
        # the peak of the trend: 1-min running mean of the 1-s means
        n = min(61, int(sel.sum()))
        sm = np.full(len(meas), -np.inf)
        sm[np.where(sel)[0][n // 2: n // 2 + int(sel.sum()) - n + 1]] = np.convolve(
            meas[sel], np.ones(n) / n, mode="valid")
        i_pk = int(np.argmax(sm))
        md.append(
            "Why the fixed-T_R torque error changes sign: the speed loop holds T_e at the load "
            f"({np.nanmean(fx['torque_nm'][sel]):.3f} N m), so the detuning shows in the reference. "
            "The controller's slip i_q / (T_R,ctrl i_d) uses the cold T_R; with k = T_R,ctrl / T_R and "
            "r = i_q / i_d, in steady state T_e / T_ref = k (1 + r^2) / (k^2 + r^2), which is above 1 "
            f"for 1 < k < r^2 and below beyond. Here r^2 = (T_ref L_R / (n_p psi_ref^2))^2 = "
            f"{np.nanmin((r ** 2)[sel]):.3f}-{np.nanmax((r ** 2)[sel]):.3f} (i_q slightly above i_d at rated "
            f"load) while k grows from 1 to {np.nanmax(k):.3f} as the rotor heats: its 1-min mean peaks at "
            f"{sm[i_pk]:+.2f} % of rated ({fx['t_end_s'][i_pk] / 60:.0f} min, k = {k[i_pk]:.3f}; the "
            f"formula's maximum is at k = r = {np.sqrt(np.nanmean((r ** 2)[sel])):.3f}), "
            + (f"crosses zero at {sc[0] / 60:.1f} min where k = {sc[1]:.3f} and r^2 = {sc[2]:.3f}, "
               if sc is not None else "does not cross zero in this run, ")
            + f"and ends at {meas[-1]:+.2f} %. The formula follows the measured 1-s means to "
            f"{dev:.3f} % of rated rms (dashed line in fig11; the adaptive run's 1-s means scatter by "
            f"{np.nanstd(te_ad):.3f} %). The rotor flux meanwhile rises by "
            f"{100 * (fx['psi_r_wb'][-1] / fx['psi_ref_wb'][-1] - 1):.1f} % while the stator current "
            f"stays within {np.nanmax(np.abs(di[sel])):.2f} % of the tuned drive's "
            f"{i0:.3f} A (fig11).\n")
    return md


# --------------------------------------------------------------------------------------


def commission_section(raw, res):
    """The commissioning run (raw/commission.csv) and, per experiment, the estimation error with
    the identified constants (the runs) against a second estimator with the true constants on
    the same samples (raw/<exp>_true_constants.csv)."""
    path = os.path.join(raw, "commission.csv")
    if not os.path.exists(path):
        return ["## Constants\n", "The estimators got the simulator's true constants (`--no-commission`).\n"]
    rows = {r["quantity"]: r for r in read_csv(path)}

    def val(k):
        return rows[k]["identified"] if k in rows else "?"
    md = ["## Commissioning (before the runs)\n"]
    ok = val("valid") == "1"
    md.append(f"`imest_commission.h` run closed loop on the motor behind an 8 kHz inverter with firmware "
              f"timing, 2 us dead time and 1.0 V / 0.8 V device drops (12-bit sensors, the 4096-count encoder, "
              f"the shaft free to turn): state **{val('state')}**"
              + (f" ({val('reason')})" if val("reason") not in ("none", "?") else "")
              + f", {float(val('time_s')):.1f} s, peak phase current {float(val('i_peak_a')):.2f} A "
              f"(limit {float(rows['i_peak_a']['true']):.2f} A).\n")
    if not ok:
        md.append("**The routine did not complete: the runs below use the true constants.**\n")
        return md
    md.append("| constant | identified | true | error |")
    md.append("|---|---:|---:|---:|")
    for key, label, scale, unit in (("R_S", "R_S (winding + min(r_sw, r_d))", 1.0, "Ω"),
                                    ("R_S_winding", "R_S vs the winding alone", 1.0, "Ω"),
                                    ("L_S", "L_S", 1e3, "mH"), ("sigma", "σ", 1.0, ""),
                                    ("sigma_L_S", "σL_S", 1e3, "mH"), ("T_R", "T_R (nominal)", 1e3, "ms"),
                                    ("dead_time", "dead time", 1e6, "µs"), ("v_threshold", "device threshold", 1.0, "V")):
        if key not in rows:
            continue
        i, t = fnum(rows[key]["identified"]), fnum(rows[key]["true"])
        md.append(f"| {label} | {i * scale:.5g} {unit} | {t * scale:.5g} {unit} | {100 * (i / t - 1):+.3f} % |")
    md.append(f"| n_p, encoder direction | {val('pole_pairs')}, {val('encoder_dir')} | "
              f"{rows['pole_pairs']['true']}, {rows['encoder_dir']['true']} | |")
    md.append("")
    md.append("Every run's estimator got the identified n_p, L_S, σ, nominal R_S and T_R (its voltage input "
              "is the measured phase voltage, so the inverter model is not used). A second estimator with the "
              "true constants ran alongside on the same samples:\n")
    md.append("| experiment | constants | n T_R valid | T_R mean err % | T_R bias % | n R_S valid | R_S mean err % "
              "| R_S bias % |")
    md.append("|---|---|---:|---:|---:|---:|---:|---:|")
    for exp in EXPS:
        tpath = os.path.join(raw, f"{exp}_true_constants.csv")
        if exp not in res or not os.path.exists(tpath) or exp == DUTY["exp"]:
            continue  # the duty-cycle run has its own commissioning (duty_section)
        md += true_constants_rows(exp, res[exp]["a"], tpath)
    md.append("")
    return md


def true_constants_rows(exp, a, tpath):
    """Rows 'identified' (the run, a) and 'true' (the second estimator on the same samples,
    raw/<exp>_true_constants.csv): n valid, mean error, bias of T_R and R_S."""
    tr_rows = read_csv(tpath)
    b = {k: np.array([fnum(r[k]) for r in tr_rows]) for k in ("T_R_s", "T_R_true_s", "R_S_ohm", "R_S_true_ohm")}
    b["status"] = np.array([r["status"] for r in tr_rows])
    for k in ("tr_valid", "rs_valid"):
        b[k] = np.array([r[k] == "1" for r in tr_rows])
    for k in ("tr_reason", "rs_reason"):  # an older demo wrote the window's status only
        b[k] = np.array([r.get(k, r["status"]) for r in tr_rows])
    md = []
    for name, x in (("identified", a), ("true", b)):
        s1 = err_stats(x["T_R_s"][x["tr_valid"]], x["T_R_true_s"][x["tr_valid"]])
        s2 = err_stats(x["R_S_ohm"][x["rs_valid"]], x["R_S_true_ohm"][x["rs_valid"]])
        cells = (stat_cells(s1, why_none(x, "tr_valid", "tr_reason"), ("{:.2f}", "{:+.2f}"), (1, 4))
                 + stat_cells(s2, why_none(x, "rs_valid", "rs_reason"), ("{:.2f}", "{:+.2f}"), (1, 4)))
        md.append(f"| {exp} | {name} | " + " | ".join(cells) + " |")
    return md


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    out = argv[1]
    timings = None
    if "--timings" in argv:
        timings = argv[argv.index("--timings") + 1]
    raw = os.path.join(out, "raw")
    md = []
    figs = []
    res = {}
    check = []
    for exp in EXPS:
        if not os.path.exists(os.path.join(raw, f"{exp}_direct.csv")):
            continue
        rows, mism, missing, nmon = build_windows(raw, exp)
        if not rows:
            continue
        write_rows(os.path.join(out, WIN_FILE[exp]), rows)
        res[exp] = {"a": arrays(rows), "rep": monitor_report(os.path.join(raw, f"{exp}_monitor.log"))}
        check.append((exp, len(rows), nmon, missing, mism))

    # exp2 (and the IFOC runs): block averages
    for exp in ("exp2", "ifoc_fixed", "ifoc_adaptive"):
        if exp in res:
            res[exp]["b30"] = block_avg(res[exp]["a"], 30.0)
            res[exp]["b120"] = block_avg(res[exp]["a"], 120.0)
    if "exp2" in res:
        for per in (30, 120):
            b = res["exp2"][f"b{per}"]
            if b:
                write_rows(os.path.join(out, f"exp2_avg{per}.csv"),
                           [{k: ("%.9g" % v if isinstance(v, float) else v) for k, v in r.items()} for r in b])

    # ---------------- figures
    if "exp2" in res:
        a = res["exp2"]["a"]
        dur = a["t_end_s"][-1]
        sub = f"exp. 2: 30 Hz V/f, 2.064 N m, {dur / 60:.0f} min, PWM inverter, 12-bit sensors"
        # (figure numbers, estimate, truth, its verdict, label, paper's figures, shade encoder zone)
        for nums, key, tkey, okkey, label, sym, paper, enc in (
                ((5, 6, 7), "T_R_s", "T_R_true_s", "tr_valid", "$T_R$ [s]", "tr", (5, 6, 7), False),
                ((8, 9, 10), "R_S_ohm", "R_S_true_ohm", "rs_valid", "$R_S$ [Ω]", "rs", (8, 9, 10), True)):
            v = a[okkey]
            name = label.split(" ")[0]
            figs.append(os.path.join(out, f"fig{nums[0]:02d}_{sym}_1s.png"))
            fig_estimates(figs[-1], a, key, tkey, okkey, okkey.replace("valid", "reason"), label,
                          f"{name} estimated each second (cf. paper Fig. {paper[0]})\n{sub}",
                          stats_note(*err_stats(a[key][v], a[tkey][v])), encoder=enc)
            for per, num, pnum in ((30, nums[1], paper[1]), (120, nums[2], paper[2])):
                b = res["exp2"][f"b{per}"]
                if not b:
                    continue
                y = np.array([x[key] for x in b])
                tt = np.array([x[tkey] for x in b])
                figs.append(os.path.join(out, f"fig{num:02d}_{sym}_{per}s.png"))
                fig_blocks(figs[-1], a, b, per, key, tkey, "n_" + okkey, label,
                           f"{name} averaged over {per} s (cf. paper Fig. {pnum})\n{sub}",
                           stats_note(*err_stats(y, tt)), encoder=enc)
    exp1_rel = None
    ident = None
    if "exp1" in res and os.path.exists(os.path.join(raw, "exp1_wave.csv")):
        wrows = read_csv(os.path.join(raw, "exp1_wave.csv"))
        wave = {k: np.array([fnum(r[k]) for r in wrows]) for k in wrows[0]}
        ir = read_csv(os.path.join(raw, "exp1_identified.csv"))[0]
        ident = {"seq": ir["seq"], "status": ir["status"], "valid": ir["valid"],
                 "T_R_s": fnum(ir["T_R_s"]), "R_S_ohm": fnum(ir["R_S_ohm"]), "source": ir["source"]}
        f, exp1_rel = fig_exp1(out, wave, ident, res["exp1"]["a"])
        figs = f + figs
    for pair in IFOC_PAIRS:
        if pair["fixed"] in res and pair["adaptive"] in res:
            figs.append(os.path.join(out, pair["fig"]))
            fig_closed_loop(figs[-1], res[pair["fixed"]]["a"], res[pair["adaptive"]]["a"], pair)
    if DUTY["exp"] in res:
        figs.append(os.path.join(out, DUTY["fig"]))
        fig_duty(figs[-1], res[DUTY["exp"]]["a"], read_commission(raw, f"{DUTY['exp']}_commission"))
    if res:
        figs.append(os.path.join(out, "fig13_verdicts.png"))
        fig_verdicts(figs[-1], res)
    if "exp2" in res and "est_stator_c" in res["exp2"]["a"]:
        figs.append(os.path.join(out, "fig15_temperatures.png"))
        fig_temperatures(figs[-1], res["exp2"]["a"], sub)

    # ---------------- summary
    md.append("# imest demo: results\n")
    md.append("Simulated motor (imsim: the paper's 0.5 hp motor, 10 kHz sine-triangle PWM inverter, "
              "12-bit ADCs of +-20 A and +-400 V with 1 LSB rms noise, current-sensor offsets of "
              "+40/-25/+10 mA, 4096-count encoder, copper heating), imest in the loop as "
              "firmware runs it (float32 ISR call per 4 kHz sample with the wrapped encoder angle, "
              "background call per 1-s window), every window published over the CAN port as a "
              "`candump -L` log and decoded back with `imest-monitor`. Errors are "
              "|estimate / truth - 1|, truth = the simulator's parameter averaged over the window's "
              "samples (over the same windows for the 30-s / 120-s averages). Only valid estimates "
              "count: T_R statistics use the windows whose T_R is valid (`tr_valid`), R_S statistics "
              "those whose R_S is valid (`rs_valid`); the windows left out and why are counted below.\n")
    md += commission_section(raw, res)
    md.append("## Estimation error\n")
    md.append("n = valid 1-s windows, or 30-s / 120-s blocks with at least one valid window.\n")
    md.append("| experiment | estimate | n T_R | T_R mean err % | T_R max err % | T_R bias % "
              "| n R_S | R_S mean err % | R_S max err % | R_S bias % |")
    md.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for exp in EXPS:
        if exp not in res:
            continue
        a = res[exp]["a"]
        vt, vr = a["tr_valid"], a["rs_valid"]
        levels = [("1 s", a["T_R_s"][vt], a["T_R_true_s"][vt], a["R_S_ohm"][vr], a["R_S_true_ohm"][vr])]
        for per in (30, 120):
            b = res[exp].get(f"b{per}")
            if b:
                levels.append((f"{per} s avg",
                               np.array([x["T_R_s"] for x in b]), np.array([x["T_R_true_s"] for x in b]),
                               np.array([x["R_S_ohm"] for x in b]), np.array([x["R_S_true_ohm"] for x in b])))
        why_tr, why_rs = why_none(a, "tr_valid", "tr_reason"), why_none(a, "rs_valid", "rs_reason")
        for name, tr, trt, rs, rst in levels:
            cells = stat_cells(err_stats(tr, trt), why_tr) + stat_cells(err_stats(rs, rst), why_rs)
            md.append(f"| {exp} | {name} | " + " | ".join(cells) + " |")
    md.append("")
    md.append("## Windows: valid / not valid by reason, telemetry\n")
    md.append("| experiment | windows | valid | T_R not valid (reason count) | R_S not valid (reason count) "
              "| CAN windows decoded | lost frames | corrupted | repeated | incomplete | decode = library |")
    md.append("|---|---:|---:|---|---|---:|---:|---:|---:|---:|---|")
    seen = set()
    for exp, n, nmon, missing, mism in check:
        a = res[exp]["a"]
        rep = res[exp]["rep"]
        cells = []
        for okkey, rkey in (("tr_valid", "tr_reason"), ("rs_valid", "rs_reason")):
            rc = reason_counts(a[rkey], a[okkey])
            seen.update(r for r, _ in rc)
            cells.append(f"{int((~a[okkey]).sum())}: " + ", ".join(f"{r} {c}" for r, c in rc) if rc else "0")

        def g(k):
            return "n/a" if rep[k] is None else str(rep[k])
        md.append(f"| {exp} | {n} | {int(a['valid'].sum())} | {cells[0]} | {cells[1]} | {nmon} | {g('lost')} "
                  f"| {g('corrupted')} | {g('repeated')} | {g('incomplete')} "
                  f"| {'yes' if mism == 0 and missing == 0 else f'{mism} mismatches, {missing} missing'} |")
    md.append("")
    for r in sorted(seen):
        md.append(f"- `{r}`: {REASON_TEXT.get(r, 'see the README, When is a window valid')}")
    for exp, *_ in check:
        a = res[exp]["a"]
        bad = np.where(~a["valid"])[0]
        if 0 < len(bad) <= 5:
            md.append(f"- {exp}: " + "; ".join(
                f"window {int(a['seq'][i])} ({max(a['t_end_s'][i] - 1, 0):.0f}-{a['t_end_s'][i]:.0f} s, "
                f"speed {a['speed_rad_s'][i]:.1f} rad/s, load {a['load_nm'][i]:.2f} N m): {a['status'][i]}"
                for i in bad))
    md.append("")
    enc_md = encoder_section(res)
    md += enc_md
    if ident is not None:
        a = res["exp1"]["a"]
        md.append("## Experiment 1 (run-up): identified parameters\n")
        if str(ident["valid"]) == "1":
            md.append(f"- identified in window {ident['seq']} ({ident['source']}): "
                      f"T_R = {ident['T_R_s']:.5f} s (truth {a['T_R_true_s'][0]:.5f} s), "
                      f"R_S = {ident['R_S_ohm']:.4f} Ω (truth {a['R_S_true_ohm'][0]:.4f} Ω); "
                      f"paper: T_R = 0.12 s, R_S = 5.04 Ω")
        else:
            md.append(f"- NO valid window: the run-up is drawn with {ident['source']} "
                      f"(status {ident['status']}); these are not estimates")
        for i in range(len(a["t_end_s"])):
            if a["valid"][i]:
                md.append(f"- window {int(a['seq'][i])}: valid, T_R {a['T_R_s'][i]:.5g} s, "
                          f"R_S {a['R_S_ohm'][i]:.5g} Ω, E_I {a['E_I'][i]:.4g}, pe_k2_rel {a['pe_k2_rel'][i]:.4g}")
            else:
                # its numbers are in exp1_windows.csv with the verdict; not beside the valid ones
                md.append(f"- window {int(a['seq'][i])}: NOT valid, no estimate: {a['status'][i]} "
                          f"at {a['speed_rad_s'][i]:.1f} rad/s ({REASON_TEXT.get(a['status'][i], '')})")
        if exp1_rel is not None:
            md.append(f"- motor simulated with these parameters and the same inverter voltages: "
                      f"rms(i_Sa measured - simulated) = {100 * exp1_rel:.2f} % of rms(i_Sa) over 0-1 s")
        md.append("")
    if "ifoc_fixed" in res and "ifoc_adaptive" in res:
        md += ifoc_section(res["ifoc_fixed"]["a"], res["ifoc_adaptive"]["a"])
    p11 = IFOC_PAIRS[1]
    if p11["fixed"] in res and p11["adaptive"] in res:
        md += ifoc11_section(res[p11["fixed"]]["a"], res[p11["adaptive"]]["a"], p11)
    if DUTY["exp"] in res:
        md += duty_section(raw, res[DUTY["exp"]]["a"])
    if "exp2" in res and "est_stator_c" in res["exp2"]["a"]:
        md += temperature_section(res["exp2"]["a"])
    md.append("## Files\n")
    md.append("- `windows.csv`: exp. 2, one row per 1-s window (values as decoded from the CAN log; "
              "`via_can` = 1), truth, drive state; `exp1_windows.csv`, `ifoc_fixed_windows.csv`, "
              "`ifoc_adaptive_windows.csv`, `ifoc11_fixed_windows.csv`, `ifoc11_adaptive_windows.csv`, "
              "`duty4kw_windows.csv`: "
              "the same for the other runs")
    md.append("- `exp2_avg30.csv`, `exp2_avg120.csv`: 30-s / 120-s averages of the valid 1-s estimates")
    md.append("- figures: " + ", ".join(f"`{os.path.basename(f)}`" for f in figs))
    md.append("- `raw/`: CAN logs (`<exp>.candump.log`), imest-monitor output (`<exp>_monitor.csv`, "
              "`<exp>_monitor.log`), the library's results with truth (`<exp>_direct.csv`), exp. 1 "
              "waveforms (`exp1_wave.csv`)")
    md.append("")
    speed = os.path.join(raw, "imest-demo.txt")
    if os.path.exists(speed):
        md.append("## Simulation speed (imest-demo, runs in parallel threads)\n")
        md.append("| run | motor time [s] | windows | wall [s] | x real time |")
        md.append("|---|---:|---:|---:|---:|")
        cpu_line = None
        with open(speed) as f:
            for line in f:
                kv = dict(p.split("=", 1) for p in line.split() if "=" in p)
                if "simulate_cpu_s" in kv:
                    cpu_line = (f"\nAll runs together: {kv['simulate_wall_s']} s wall, {kv['simulate_cpu_s']} s CPU "
                                f"({kv.get('cpus', '?')} CPUs online; wall time grows when other work shares them).")
                if "experiment" in kv:
                    md.append(f"| {kv['experiment']} | {kv.get('motor_s')} | {kv.get('windows')} "
                              f"| {kv.get('wall_s')} | {kv.get('realtime_x')} |")
        if cpu_line:
            md.append(cpu_line)
        md.append("")
    if timings and os.path.exists(timings):
        md.append("## Wall time\n")
        md.append("| phase | wall [s] |")
        md.append("|---|---:|")
        with open(timings) as f:
            for line in f:
                p = line.rstrip("\n").split("\t")
                if len(p) == 2:
                    md.append(f"| {p[0]} | {p[1]} |")
        # tools/demo-run appends the last rows (figures, total): the table stays last
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
