#!/usr/bin/python3
"""imest demo: windows tables, figures and summary from the raw run.

Usage: /usr/bin/python3 tools/demo/make_results.py OUT_DIR [--timings FILE]

Reads OUT_DIR/raw/ (written by imest-demo and imest-monitor, see tools/demo/README.md):
  <exp>_direct.csv        per window: the library's result, the simulator's truth, drive state
  <exp>_monitor.csv       per window: what imest-monitor decoded from <exp>.candump.log
  <exp>_monitor.log       imest-monitor's stderr (events and the summary line)
  exp1_wave.csv           exp1 waveforms, measured and simulated with the identified parameters
  exp1_identified.csv     which exp1 window gave the identified parameters
Writes OUT_DIR/{windows.csv, exp1_windows.csv, ifoc_fixed_windows.csv,
ifoc_adaptive_windows.csv, exp2_avg30.csv, exp2_avg120.csv, fig*.png, summary.md}.
Plots with matplotlib's Agg backend (Debian python3-matplotlib).
"""
import csv
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

EXPS = ["exp1", "exp2", "ifoc_fixed", "ifoc_adaptive"]
WIN_FILE = {"exp2": "windows.csv", "exp1": "exp1_windows.csv",
            "ifoc_fixed": "ifoc_fixed_windows.csv", "ifoc_adaptive": "ifoc_adaptive_windows.csv"}
RATED_TORQUE = 2.064
GREY = "0.55"


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
        for key in ("n_roots", "n_admissible", "slip_ratio", "i_rms_a", "used_samples", "flags",
                    "speed_rad_s", "torque_nm", "load_nm", "i_phase_rms_a", "temp_stator_c",
                    "temp_rotor_c", "torque_ref_nm", "torque_err_rms_nm", "psi_r_wb",
                    "psi_ref_wb", "ifoc_T_R_s"):
            row[key] = d[key]
        rows.append(row)
    return rows, mismatches, missing, len(mon)


def write_rows(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def arrays(rows):
    a = {}
    for key in rows[0]:
        if key in ("experiment", "status"):
            a[key] = np.array([r[key] for r in rows])
        else:
            a[key] = np.array([fnum(r[key]) for r in rows])
    a["valid"] = a["valid"] == 1
    return a


def block_avg(a, period):
    """Paper eq. after Fig. 6: average of the valid 1-s estimates in consecutive blocks."""
    k = np.floor(a["t_end_s"] / period + 1e-9).astype(int)
    out = []
    for b in range(0, int(k.max()) + 1 if len(k) else 0):
        sel = k == b
        v = sel & a["valid"]
        n_all, n_v = int(sel.sum()), int(v.sum())
        if n_all == 0:
            continue
        row = {"t_end_s": (b + 1) * period, "n_windows": n_all, "n_valid": n_v}
        for key, tkey in (("T_R_s", "T_R_true_s"), ("R_S_ohm", "R_S_true_ohm")):
            row[key] = float(np.mean(a[key][v])) if n_v else math.nan
            # truth over the same windows the average uses (all of the block if none valid)
            row[tkey] = float(np.mean(a[tkey][v if n_v else sel]))
        out.append(row)
    return out


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
                label=f"invalid window ({int(inv.sum())})" if label else None)


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


def fig_estimates(path, a, key, tkey, ylabel, title, note):
    t = a["t_end_s"] / 60.0
    fig, ax = plt.subplots(figsize=(10, 4.8))
    v = a["valid"]
    ax.plot(t[v], a[key][v], ".", ms=2.5, color="tab:blue", label=f"estimate, valid 1-s window ({int(v.sum())})")
    ax.plot(t, a[tkey], "-", color="k", lw=1.4, label="truth (window mean of the simulator)")
    lo, hi = robust_ylim(ax, a[key][v], a[tkey])
    mark_clipped(ax, t[v], a[key][v], lo, hi)
    mark_invalid(ax, t, v)
    ax.set_xlabel("time [min]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8, framealpha=0.9, title=note, title_fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_blocks(path, a, blocks, period, key, tkey, ylabel, title, note):
    te = np.array([b["t_end_s"] for b in blocks]) / 60.0
    ts = te - period / 60.0
    y = np.array([b[key] for b in blocks])
    fig, ax = plt.subplots(figsize=(10, 4.8))
    ok = np.isfinite(y)
    ax.hlines(y[ok], ts[ok], te[ok], color="tab:blue", lw=2.2 if period < 60 else 2.8,
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
    ax.set_xlabel("time [min]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8, framealpha=0.9, title=note, title_fontsize=8)
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
    # Fig. 2: voltages
    fig, axs = plt.subplots(2, 1, figsize=(10, 6.0))
    for ax, tmax in zip(axs, (1.0, 0.05)):
        s = t <= tmax
        ax.plot(t[s], wave["u_alpha_v"][s], lw=0.7 if tmax > 0.5 else 1.2, label=r"$u_{Sa}$")
        ax.plot(t[s], wave["u_beta_v"][s], lw=0.7 if tmax > 0.5 else 1.2, label=r"$u_{Sb}$")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("voltage [V]")
        ax.grid(alpha=0.3)
    axs[0].set_title("Exp. 1 (cf. paper Fig. 2): sampled two-phase voltages, 60 Hz 230 V applied at rest "
                     "through the PWM inverter", fontsize=10)
    axs[1].set_title("zoom on the first 50 ms (measured = carrier-period mean of the commanded "
                     "volt-seconds, 12-bit ADC)", fontsize=9)
    axs[0].legend(loc="upper right", fontsize=8)
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


def fig_closed_loop(path, fx, ad):
    fig, axs = plt.subplots(4, 1, figsize=(10, 11), sharex=True)
    for a, name, col in ((fx, "IFOC, $T_R$ fixed at the cold value", "tab:red"),
                         (ad, "IFOC, $T_R$ from the estimator", "tab:green")):
        t = a["t_end_s"] / 60.0
        axs[0].plot(t, a["torque_nm"] - a["torque_ref_nm"], lw=1.0, color=col, label=name)
        axs[1].plot(t, 100.0 * (a["psi_r_wb"] / a["psi_ref_wb"] - 1.0), lw=1.0, color=col, label=name)
        axs[2].plot(t, a["i_phase_rms_a"], lw=1.0, color=col, label=name)
        axs[3].plot(t, a["ifoc_T_R_s"], lw=1.0, color=col, label="controller's $T_R$: " + name.split(", ")[1])
    axs[3].plot(ad["t_end_s"] / 60.0, ad["T_R_true_s"], "k-", lw=1.2, label="true $T_R$ (adaptive run)")
    axs[3].plot(fx["t_end_s"] / 60.0, fx["T_R_true_s"], "k:", lw=1.2, label="true $T_R$ (fixed run)")
    axs[0].set_ylabel("torque error\n$T_e - T_{e,ref}$ [N m]")
    axs[1].set_ylabel("rotor-flux error\n$|\\psi_R|/\\psi_{ref} - 1$ [%]")
    axs[2].set_ylabel("stator current\n(phase rms) [A]")
    axs[3].set_ylabel("$T_R$ [s]")
    axs[3].set_xlabel("time [min]")
    axs[0].set_title("Beyond the paper: the heat run (30 Hz / 850 r/min, 2.064 N m) under IFOC speed control\n"
                     "(1-s window means; first 5 s = start-up)", fontsize=10)
    for ax in axs:
        ax.grid(alpha=0.3)
    for ax in axs[:2]:
        ax.axhline(0, color="0.6", lw=0.6)
    axs[0].legend(loc="best", fontsize=8)
    axs[3].legend(loc="best", fontsize=8)
    # the start-up transient would dwarf the hour: clip the first 5 s
    for ax, key in ((axs[0], None), (axs[1], None)):
        ys = []
        for a in (fx, ad):
            sel = a["t_end_s"] > 5
            if key is None and ax is axs[0]:
                ys.append((a["torque_nm"] - a["torque_ref_nm"])[sel])
            else:
                ys.append(100.0 * (a["psi_r_wb"] / a["psi_ref_wb"] - 1.0)[sel])
        y = np.concatenate(ys)
        y = y[np.isfinite(y)]
        if len(y):
            lo, hi = min(np.min(y), 0), max(np.max(y), 0)
            pad = 0.15 * (hi - lo) + 1e-6
            ax.set_ylim(lo - pad, hi + pad)
    sel = np.concatenate([a["i_phase_rms_a"][a["t_end_s"] > 5] for a in (fx, ad)])
    if len(sel):
        pad = 0.2 * (np.max(sel) - np.min(sel)) + 0.01
        axs[2].set_ylim(np.min(sel) - pad, np.max(sel) + pad)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --------------------------------------------------------------------------------------


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
        v = a["valid"]
        dur = a["t_end_s"][-1]
        sub = f"exp. 2: 30 Hz V/f, 2.064 N m, {dur / 60:.0f} min, PWM inverter, 12-bit sensors"
        st = err_stats(a["T_R_s"][v], a["T_R_true_s"][v])
        figs.append(os.path.join(out, "fig05_tr_1s.png"))
        fig_estimates(figs[-1], a, "T_R_s", "T_R_true_s", "$T_R$ [s]",
                      f"$T_R$ estimated each second (cf. paper Fig. 5)\n{sub}", stats_note(*st))
        st = err_stats(a["R_S_ohm"][v], a["R_S_true_ohm"][v])
        figs.append(os.path.join(out, "fig08_rs_1s.png"))
        fig_estimates(figs[-1], a, "R_S_ohm", "R_S_true_ohm", "$R_S$ [Ω]",
                      f"$R_S$ estimated each second (cf. paper Fig. 8)\n{sub}", stats_note(*st))
        for per, ftr, frs in ((30, "fig06_tr_30s.png", "fig09_rs_30s.png"),
                              (120, "fig07_tr_120s.png", "fig10_rs_120s.png")):
            b = res["exp2"][f"b{per}"]
            if not b:
                continue
            y = np.array([x["T_R_s"] for x in b])
            tt = np.array([x["T_R_true_s"] for x in b])
            figs.append(os.path.join(out, ftr))
            fig_blocks(figs[-1], a, b, per, "T_R_s", "T_R_true_s", "$T_R$ [s]",
                       f"$T_R$ averaged over {per} s (cf. paper Fig. {6 if per == 30 else 7})\n{sub}",
                       stats_note(*err_stats(y, tt)))
            y = np.array([x["R_S_ohm"] for x in b])
            tt = np.array([x["R_S_true_ohm"] for x in b])
            figs.append(os.path.join(out, frs))
            fig_blocks(figs[-1], a, b, per, "R_S_ohm", "R_S_true_ohm", "$R_S$ [Ω]",
                       f"$R_S$ averaged over {per} s (cf. paper Fig. {9 if per == 30 else 10})\n{sub}",
                       stats_note(*err_stats(y, tt)))
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
    if "ifoc_fixed" in res and "ifoc_adaptive" in res:
        figs.append(os.path.join(out, "fig11_ifoc_closed_loop.png"))
        fig_closed_loop(figs[-1], res["ifoc_fixed"]["a"], res["ifoc_adaptive"]["a"])

    # ---------------- summary
    md.append("# imest demo: results\n")
    md.append("Simulated motor (imsim: the paper's 0.5 hp motor, 10 kHz sine-triangle PWM inverter, "
              "12-bit ADCs with 1 LSB noise, current-sensor offsets of +40/-25/+10 mA, 4096-count encoder, copper heating), imest in the loop as "
              "firmware runs it (float32 ISR call per 4 kHz sample with the wrapped encoder angle, "
              "background call per 1-s window), every window published over the CAN port as a "
              "`candump -L` log and decoded back with `imest-monitor`. Errors are "
              "|estimate / truth - 1|, truth = the simulator's parameter averaged over the window's "
              "samples (over the same windows for the 30-s / 120-s averages). Only valid windows count.\n")
    md.append("## Estimation error\n")
    md.append("| experiment | estimate | n | T_R mean err % | T_R max err % | R_S mean err % | R_S max err % | T_R bias % | R_S bias % |")
    md.append("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for exp in EXPS:
        if exp not in res:
            continue
        a = res[exp]["a"]
        v = a["valid"]
        levels = [("1 s", a["T_R_s"][v], a["T_R_true_s"][v], a["R_S_ohm"][v], a["R_S_true_ohm"][v])]
        for per in (30, 120):
            b = res[exp].get(f"b{per}")
            if b:
                levels.append((f"{per} s avg",
                               np.array([x["T_R_s"] for x in b]), np.array([x["T_R_true_s"] for x in b]),
                               np.array([x["R_S_ohm"] for x in b]), np.array([x["R_S_true_ohm"] for x in b])))
        for name, tr, trt, rs, rst in levels:
            s1, s2 = err_stats(tr, trt), err_stats(rs, rst)
            md.append(f"| {exp} | {name} | {s1[0]} | {s1[1]:.2f} | {s1[3]:.2f} | {s2[1]:.2f} | {s2[3]:.2f} "
                      f"| {s1[4]:+.2f} | {s2[4]:+.2f} |")
    md.append("")
    md.append("## Windows: valid / invalid by status, telemetry\n")
    md.append("| experiment | windows | valid | invalid (by status) | CAN windows decoded | lost frames | corrupted | repeated | incomplete | decode = library |")
    md.append("|---|---:|---:|---|---:|---:|---:|---:|---:|---|")
    for exp, n, nmon, missing, mism in check:
        a = res[exp]["a"]
        rep = res[exp]["rep"]
        stat = {}
        for s, v in zip(a["status"], a["valid"]):
            if not v:
                stat[s] = stat.get(s, 0) + 1
        inv = ", ".join(f"{k} {c}" for k, c in sorted(stat.items(), key=lambda kv: -kv[1])) or "none"

        def g(k):
            return "n/a" if rep[k] is None else str(rep[k])
        md.append(f"| {exp} | {n} | {int(a['valid'].sum())} | {inv} | {nmon} | {g('lost')} | {g('corrupted')} "
                  f"| {g('repeated')} | {g('incomplete')} | {'yes' if mism == 0 and missing == 0 else f'{mism} mismatches, {missing} missing'} |")
    md.append("")
    if ident is not None:
        a = res["exp1"]["a"]
        md.append("## Experiment 1 (run-up): identified parameters\n")
        md.append(f"- window {ident['seq']} ({ident['source']}; status {ident['status']}): "
                  f"T_R = {ident['T_R_s']:.5f} s (truth {a['T_R_true_s'][0]:.5f} s), "
                  f"R_S = {ident['R_S_ohm']:.4f} Ω (truth {a['R_S_true_ohm'][0]:.4f} Ω); "
                  f"paper: T_R = 0.12 s, R_S = 5.04 Ω")
        for i in range(len(a["t_end_s"])):
            md.append(f"- window {int(a['seq'][i])}: status {a['status'][i]}, T_R {a['T_R_s'][i]:.5g} s, "
                      f"R_S {a['R_S_ohm'][i]:.5g} Ω, E_I {a['E_I'][i]:.4g}, pe_k2_rel {a['pe_k2_rel'][i]:.4g}")
        if exp1_rel is not None:
            md.append(f"- motor simulated with these parameters and the same inverter voltages: "
                      f"rms(i_Sa measured - simulated) = {100 * exp1_rel:.2f} % of rms(i_Sa) over 0-1 s")
        md.append("")
    if "ifoc_fixed" in res and "ifoc_adaptive" in res:
        md.append("## Beyond the paper: IFOC heat run, controller T_R fixed vs from the estimator\n")
        md.append("Torque error = electromagnetic torque - controller's torque reference (1-s means), in "
                  "N m and in % of the rated 2.064 N m; flux error = |psi_R| / psi_ref - 1. "
                  "'whole run' = t > 5 s (after start-up); 'last 5 min' = the end of the heat run.\n")
        md.append("| run | span | mean abs torque err [N m] | [% rated] | max abs torque err [N m] | mean flux err % | stator current [A rms] | controller T_R [s] | true T_R [s] | valid windows |")
        md.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for exp, label in (("ifoc_fixed", "T_R fixed (cold)"), ("ifoc_adaptive", "T_R from imest")):
            a = res[exp]["a"]
            tend = a["t_end_s"][-1]
            for span, sel in (("whole run", a["t_end_s"] > 5),
                              ("last 5 min", a["t_end_s"] > max(tend - 300, 5))):
                te = np.abs(a["torque_nm"] - a["torque_ref_nm"])[sel]
                fe = 100 * (a["psi_r_wb"] / a["psi_ref_wb"] - 1)[sel]
                md.append(f"| {label} | {span} | {np.nanmean(te):.4f} | {100 * np.nanmean(te) / RATED_TORQUE:.2f} "
                          f"| {np.nanmax(te):.4f} | {np.nanmean(fe):+.2f} | {np.nanmean(a['i_phase_rms_a'][sel]):.3f} "
                          f"| {np.nanmean(a['ifoc_T_R_s'][sel]):.4f} | {np.nanmean(a['T_R_true_s'][sel]):.4f} "
                          f"| {int(a['valid'][sel].sum())} / {int(sel.sum())} |")
        md.append("")
    md.append("## Files\n")
    md.append("- `windows.csv`: exp. 2, one row per 1-s window (values as decoded from the CAN log; "
              "`via_can` = 1), truth, drive state; `exp1_windows.csv`, `ifoc_fixed_windows.csv`, "
              "`ifoc_adaptive_windows.csv`: the same for the other runs")
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
