# SPDX-License-Identifier: Apache-2.0
"""The Markdown report of the envelope benchmark (results.md)."""
import math
from collections import Counter, defaultdict

import analyse
import motors
import points


def _pct(a, b):
    return f"{100.0 * a / b:.0f}" if b else "–"


def _e(x, nd=2):
    return f"{x:+.{nd}f}" if math.isfinite(x) else "–"


def _names(rows, key):
    return [m["name"] for m in motors.MOTORS if any(r[key] == m["name"] for r in rows)]


def _q(xs, p):
    xs = sorted(x for x in xs if math.isfinite(x))
    return xs[int(round(p * (len(xs) - 1)))] if xs else math.nan


def _sel(rows, **kw):
    return [w for w in rows if all(w[k] == v for k, v in kw.items())]


def evidence(rows):
    """Tables behind the diagnosis: the validity evidence against motor size, sensors and
    encoders, and the systematic errors the verdicts do not see."""
    L = ["## Evidence\n"]
    names = _names(rows, "motor")
    goal = [w for w in rows if w["goal"]]
    L.append("**E_I of accurate windows** (goal region, |e_TR| <= 1 % and |e_RS| <= 3 %, valid or "
             "not): median / 90th percentile, and the share above 3 (`max_ei`, `high_residual`).\n")
    L.append("| " + " | ".join(["motor"] + names) + " |")
    L.append("|---" * (len(names) + 1) + "|")
    cells = []
    for n in names:
        ei = [w["E_I"] for w in goal if w["motor"] == n and abs(w["e_tr"]) <= 0.01 and abs(w["e_rs"]) <= 0.03]
        cells.append(f"{_q(ei, .5):.2g} / {_q(ei, .9):.2g}, {_pct(sum(e > 3 for e in ei), len(ei))} % (n {len(ei)})"
                     if ei else "–")
    L.append("| E_I | " + " | ".join(cells) + " |\n")

    L.append("**slip_ratio as reported** (median, goal sensors, frequency >= 15 %) by load; the "
             "zero-slip test refuses below `min_slip_ratio` (0.1).\n")
    loads = sorted({w["load_pct"] for w in rows if w["family"] == "grid"})
    L.append("| load % | " + " | ".join(names) + " |")
    L.append("|---" * (len(names) + 1) + "|")
    for ld in loads:
        L.append(f"| {ld} | " + " | ".join(
            f"{analyse.median([w['slip_ratio'] for w in _sel(rows, family='grid', motor=n, load_pct=ld) if w['f_pct'] >= 15]):.3g}"
            for n in names) + " |")
    L.append("")

    fams = ["sensors_ideal", "sensors_16bit", "grid", "encoder_65536", "encoder_4096", "encoder_1024"]
    fams = [f for f in fams if any(w["family"] == f for w in rows)]
    for title, f_pct, ld, key, fmt in (
            ("**pe_k2_rel** (median) at 40 % frequency, 25 % load: noise and encoder against the "
             "threshold `max_pe_k2_rel` 0.1", 40, 25, "pe_k2_rel", "{:.3g}"),
            ("**R_S error** (median of all windows, %) at 40 % frequency, 100 % load: the encoder",
             40, 100, "e_rs", "{:+.1f}"),
            ("**R_S error** (median of all windows, %) at rated frequency, 25 % load", 100, 25, "e_rs",
             "{:+.1f}")):
        if not fams:
            break
        L.append(title + ".\n")
        L.append("| variant | " + " | ".join(names) + " |")
        L.append("|---" * (len(names) + 1) + "|")
        for fam in fams:
            cells = []
            for n in names:
                v = analyse.median([w[key] for w in _sel(rows, family=fam, motor=n, f_pct=f_pct, load_pct=ld)])
                cells.append(fmt.format(100 * v if key == "e_rs" else v) if math.isfinite(v) else "–")
            L.append(f"| {fam} | " + " | ".join(cells) + " |")
        L.append("")

    spans = [w["span_s"] for w in goal if math.isfinite(w["span_s"])]
    if spans:
        L.append("**Effective window length** (`span_s`, s) of the goal region's windows with T_R "
                 "valid: median / max; and of those refused.\n")
        L.append("| | " + " | ".join(names) + " |")
        L.append("|---" * (len(names) + 1) + "|")
        for label, ok in (("T_R valid", 1), ("T_R refused", 0)):
            cells = []
            for n in names:
                s = [w["span_s"] for w in goal if w["motor"] == n and w["tr_valid"] == ok]
                cells.append(f"{_q(s, .5):.3g} / {_q(s, 1):.3g}" if s else "–")
            L.append(f"| {label} | " + " | ".join(cells) + " |")
        L.append("")

    ideal = [w for w in rows if w["family"] == "sensors_ideal"]
    if ideal:
        L.append("**Systematic R_S error with ideal sensors** (median %, phase-voltage input: exact "
                 "volt-seconds of each sample period, exact currents and angle) by frequency and "
                 "load: what no noise explains.\n")
        fl = sorted({(w["f_pct"], w["load_pct"]) for w in ideal})
        L.append("| motor | " + " | ".join(f"f {f} %, load {ld} %" for f, ld in fl) + " |")
        L.append("|---" * (len(fl) + 1) + "|")
        for n in names:
            L.append(f"| {n} | " + " | ".join(
                _e(100 * analyse.median([w["e_rs"] for w in _sel(ideal, motor=n, f_pct=f, load_pct=ld)]), 1)
                for f, ld in fl) + " |")
        L.append("")
    return L


def comparison(summary, table, base_dir):
    """Before/after against an earlier run's summary.json and points.csv (e.g. the committed
    baseline): the summary lines and, per motor, the goal region's coverage."""
    import csv
    import json
    import os
    sj, pc = os.path.join(base_dir, "summary.json"), os.path.join(base_dir, "points.csv")
    if not (os.path.exists(sj) and os.path.exists(pc)):
        return []
    old = json.load(open(sj))
    olds = old["summary"]
    # the top of the tree: this file is tools/studies/envelope/report.py
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    shown = os.path.relpath(os.path.abspath(base_dir), root)
    L = [f"## Against `{shown}`\n",
         f"Earlier run: {old['meta']['form']} form, {old['meta']['points']} recordings, "
         f"{olds['windows']} windows.\n", "| line | earlier | now |", "|---|---|---|"]
    for k, v in summary.items():
        o = olds.get(k)
        if o is None:
            continue
        fmt = "{:.4f}" if isinstance(v, float) else "{}"
        L.append(f"| `{k}` | {fmt.format(o)} | {fmt.format(v)} |")
    L.append("")
    with open(pc) as f:
        prev = list(csv.DictReader(f))
    L.append("Goal region per motor, T_R good % / R_S good % (earlier -> now):\n")
    L.append("| motor | earlier | now |")
    L.append("|---|---|---|")
    for name in [m["name"] for m in motors.MOTORS]:
        cells = []
        for rows_, get in ((prev, lambda r, k: int(r[k])), (table, lambda r, k: int(r[k]))):
            g = [r for r in rows_ if r["motor"] == name and str(r["goal"]) in ("1", "True")]
            n = sum(get(r, "windows") for r in g)
            cells.append(f"{_pct(sum(get(r, 'tr_good') for r in g), n)} / {_pct(sum(get(r, 'rs_good') for r in g), n)}"
                         if n else "–")
        L.append(f"| {name} | {cells[0]} | {cells[1]} |")
    L.append("")
    return L


def render(summary, rows, table, meta):
    L = []
    add = L.append
    add("# Operating envelope of imest: results\n")
    add(f"Run: {meta['form']} form on `{meta.get('source', '?')}`, {meta['points']} recordings of "
        f"{meta['duration']:g} s, "
        f"{len(rows)} steady-state windows (the first {meta['skip']} window(s) of each recording "
        f"dropped), {meta['wall_s']:.0f} s wall on {meta['jobs']} jobs. imest-replay "
        f"{'writes' if meta['per_param'] else 'does not write'} `tr_valid`/`rs_valid`"
        f"{'' if meta['per_param'] else ' (both judged by `valid`)'}; duty-cycle input "
        f"{'run' if meta['duty'] else 'not run (imest-replay has no `--voltage duty`)'}.\n")
    if meta.get("not_held"):
        add(f"Left out, the motor did not hold its operating point (it stalled or reversed): "
            f"{', '.join(meta['not_held'])}.\n")
    if meta.get("replay_args"):
        add(f"Extra imest-replay options: `{meta['replay_args']}`.\n")
    add("## Summary\n")
    add("```")
    for k, v in summary.items():
        add(f"{k} {v:.4f}" if isinstance(v, float) else f"{k} {v}")
    add("```\n")
    if meta.get("compare"):
        L += comparison(summary, table, meta["compare"])
    add("Goal region: 12-bit ADCs (1 LSB noise), 16384-count encoder, phase-voltage input, load "
        ">= 25 %, frequency >= 15 % of rated. `coverage_tr`: share of its windows with T_R valid "
        "and within 1 %; `coverage_rs`: R_S valid and within 3 %. `false_valid_gross`: windows of "
        "the whole run with T_R valid and > 10 % off or R_S valid and > 25 % off. "
        "`false_valid_marginal`: share of the goal region's windows with a valid verdict whose "
        "valid estimate is 2-10 % (T_R) or 5-25 % (R_S) off.\n")

    goal = [w for w in rows if w["goal"]]
    add("## Goal region per motor\n")
    add("| motor | windows | T_R valid % | T_R valid and within 1 % | R_S valid % | R_S valid and "
        "within 3 % | gross false-valid | marginal false-valid | median e_TR % (all windows) | "
        "median e_RS % (all) |")
    add("|---|---|---|---|---|---|---|---|---|---|")
    for name in _names(goal, "motor"):
        ws = [w for w in goal if w["motor"] == name]
        add(f"| {name} | {len(ws)} | {_pct(sum(w['tr_valid'] for w in ws), len(ws))} | "
            f"{_pct(sum(w['tr_good'] for w in ws), len(ws))} | "
            f"{_pct(sum(w['rs_valid'] for w in ws), len(ws))} | "
            f"{_pct(sum(w['rs_good'] for w in ws), len(ws))} | {sum(w['fv_gross'] for w in ws)} | "
            f"{sum(w['fv_marginal'] for w in ws)} | "
            f"{_e(100 * analyse.median([w['e_tr'] for w in ws]))} | "
            f"{_e(100 * analyse.median([w['e_rs'] for w in ws]))} |")
    add("")

    grid = [t for t in table if t["family"] == "grid"]
    if grid:
        add("## Grid (goal sensors) per motor: frequency x load\n")
        add("Each cell: T_R good / R_S good / windows, then the median estimate error of all "
            "windows (valid or not) `e_TR, e_RS` in %, then the commonest reason T_R is refused. "
            "Bold: goal region. `!` marks a valid window that is wrong (marginal or gross).\n")
        for name in _names(grid, "motor"):
            m = next(x for x in motors.MOTORS if x["name"] == name)
            add(f"### {name} (rated {m['f']:g} Hz, {m['t_nm']:g} N m)\n")
            loads = sorted({t["load_pct"] for t in grid if t["motor"] == name})
            add("| f % \\ load % | " + " | ".join(str(x) for x in loads) + " |")
            add("|---" * (len(loads) + 1) + "|")
            for f in sorted({t["f_pct"] for t in grid if t["motor"] == name}):
                cells = []
                for ld in loads:
                    t = next((t for t in grid if t["motor"] == name and t["f_pct"] == f and
                              t["load_pct"] == ld), None)
                    if t is None:
                        cells.append("(not run)")
                        continue
                    why = t["tr_refused"].split(";")[0].rsplit(" ", 1)[0] if t["tr_refused"] else ""
                    c = (f"{t['tr_good']}/{t['rs_good']}/{t['windows']} "
                         f"{_e(t['e_tr_med_pct'], 1)},{_e(t['e_rs_med_pct'], 1)} {why}")
                    if t["fv_gross"] or t["fv_marginal"]:
                        c += " !"
                    cells.append(f"**{c.strip()}**" if t["goal"] else c.strip())
                add(f"| {f} | " + " | ".join(cells) + " |")
            add("")

    sweeps = [w for w in rows if w["family"] != "grid"]
    if sweeps:
        add("## One-at-a-time sweeps\n")
        add("Each away from the goal sensors in one dimension, on every motor at frequencies "
            f"{', '.join(str(x) for x in points.SWEEP_FREQS)} % and loads "
            f"{', '.join(str(x) for x in points.SWEEP_LOADS)} %; the reference row is the grid "
            "on the same sub-grid. Cells: T_R good % / R_S good % / false-valid (gross+marginal) "
            "windows.\n")
        fams = ["grid"] + [f for f, _ in points.SWEEPS if any(w["family"] == f for w in rows)]
        names = _names(rows, "motor")
        add("| variant | " + " | ".join(names) + " | all |")
        add("|---" * (len(names) + 2) + "|")
        for fam in fams:
            ws_f = [w for w in rows if w["family"] == fam and w["f_pct"] in points.SWEEP_FREQS and
                    w["load_pct"] in points.SWEEP_LOADS]
            cells = []
            for name in names + [None]:
                ws = [w for w in ws_f if name is None or w["motor"] == name]
                if not ws:
                    cells.append("–")
                    continue
                cells.append(f"{_pct(sum(w['tr_good'] for w in ws), len(ws))} / "
                             f"{_pct(sum(w['rs_good'] for w in ws), len(ws))} / "
                             f"{sum(w['fv_gross'] for w in ws)}+{sum(w['fv_marginal'] for w in ws)}")
            add(f"| {'grid (reference)' if fam == 'grid' else fam} | " + " | ".join(cells) + " |")
        add("")

    add("## Why T_R and R_S are refused (goal region)\n")
    for key, label in (("tr_reason", "T_R"), ("rs_reason", "R_S")):
        c = Counter(w[key] for w in goal if not w[key.replace("reason", "valid")])
        add(f"* {label}: " + (", ".join(f"`{k}` {v}" for k, v in c.most_common()) or "none refused"))
    add("")
    add("Refused but right (goal region, all refusals): T_R within 1 % in "
        f"{sum(1 for w in goal if not w['tr_valid'] and abs(w['e_tr']) <= 0.01)} of "
        f"{sum(1 for w in goal if not w['tr_valid'])} refused windows; R_S within 3 % in "
        f"{sum(1 for w in goal if not w['rs_valid'] and abs(w['e_rs']) <= 0.03)} of "
        f"{sum(1 for w in goal if not w['rs_valid'])}.\n")

    bad = [t for t in table if t["fv_gross"] or t["fv_marginal"]]
    add("## Valid and wrong\n")
    if not bad:
        add("No window was valid and more than 2 % (T_R) or 5 % (R_S) off.\n")
    else:
        add("| point | family | windows | gross | marginal | median e_TR % | median e_RS % | "
            "median pe_k2_rel | median E_I |")
        add("|---|---|---|---|---|---|---|---|---|")
        for t in sorted(bad, key=lambda t: (-t["fv_gross"], -t["fv_marginal"], t["name"])):
            add(f"| {t['name']} | {t['family']} | {t['windows']} | {t['fv_gross']} | "
                f"{t['fv_marginal']} | {_e(t['e_tr_med_pct'])} | {_e(t['e_rs_med_pct'])} | "
                f"{t['pe_k2_med']:.3g} | {t['ei_med']:.3g} |")
        add("")
    L += evidence(rows)
    add("## Motors\n")
    add("| motor | n_p | L_S [H] | sigma | R_S [ohm] | T_R [s] | rated | source |")
    add("|---|---|---|---|---|---|---|---|")
    for m in motors.MOTORS:
        c = motors.constants(m)
        add(f"| {m['name']} | {c['np']} | {c['ls']:.5g} | {c['sigma']:.4g} | {c['rs']:.4g} | "
            f"{c['tr']:.4g} | {m['vll']:g} V, {m['f']:g} Hz, {m['t_nm']:g} N m | {m['source']} |")
    add("")
    return "\n".join(L)


def _w(x):
    return f"{100.0 * x:+.2f} %" if math.isfinite(x) else ("–" if x != x else "not a number")


def _real_row(label, s):
    return (f"| {label} | {s['windows']} | {s['tr_valid']} | {s['tr_within']} | **{s['tr_wrong']}** | "
            f"{_w(s['tr_worst'])} | {s['tr_wrong_lrrr']} | {_w(s['tr_worst_lrrr'])} | {s['rs_valid']} | "
            f"{s['rs_within']} | **{s['rs_wrong']}** | {_w(s['rs_worst'])} |")


REAL_HEAD = ["| family | windows | T_R valid | T_R valid, within 2 % | T_R valid, > 2 % off | worst valid "
             "e_TR | against L_R/R_R: T_R valid, > 2 % off | worst valid e_TR against L_R/R_R | R_S valid | "
             "R_S valid, within 5 % | R_S valid, > 5 % off | worst valid e_RS |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]

# The families the goals are read over (the real-motor effects; the linear ones are controls).
REAL_CONTROLS = ("real_linear", "real_fw_linear")
# the input column of the real-motor families' table
INPUT_LABEL = {"duty_inv": "duty cycle, 2 µs dead time + drops, model given",
               "phase_inv": "phase voltage measured on that inverter (800 Hz anti-alias filter)"}


def real_goals(fam, rows):
    """The goals of the real-motor table as (goal, figure, met) rows, over the windows of every
    family but the linear controls."""
    ws = [w for w in rows if w["family"] in fam and w["family"] not in REAL_CONTROLS]
    s = analyse.real_stats(ws) if ws else None
    if not s:
        return []
    n = s["windows"]
    wrong = s["tr_wrong"] + s["rs_wrong"]
    fw = {f: sum(w["tr_valid"] for w in rows if w["family"] == f)
          for f in fam if f in points.FIELD_WEAKENING and f not in REAL_CONTROLS}
    g = [("no window valid with T_R more than 2 % off what the IFOC needs, or R_S more than 5 % off",
          f"{s['tr_wrong']} T_R + {s['rs_wrong']} R_S windows of {n}", wrong == 0),
         ("T_R valid and within 2 % in at least 60 % of the windows",
          f"{100.0 * s['tr_within'] / n:.1f} % ({s['tr_within']} of {n})", s["tr_within"] >= 0.6 * n),
         ("R_S valid and within 5 % in at least 30 % of the windows",
          f"{100.0 * s['rs_within'] / n:.1f} % ({s['rs_within']} of {n})", s["rs_within"] >= 0.3 * n)]
    if fw:
        g.append(("field weakening valid, not only refused (T_R valid in every field-weakening family)",
                  ", ".join(f"{f} {v} T_R valid" for f, v in fw.items()), all(v > 0 for v in fw.values())))
    return g


def render_real(fam, rows, table, meta):
    """real-motor.md: the real-motor families against the product promise (a valid T_R within
    2 % of what the IFOC needs, a valid R_S within 5 %)."""
    L = ["# Operating envelope of imest: real-motor effects\n"]
    L.append(f"Run: real-motor design on `{meta['source']}`, {meta['points']} recordings of "
             f"{meta['duration']:g} s, {len(rows)} steady-state windows (the first {meta['skip']} "
             f"window(s) of each recording dropped), {meta['wall_s']:.0f} s wall on {meta['jobs']} "
             "jobs." + (f" Extra imest-replay options: `{meta['replay_args']}`." if meta["replay_args"] else "")
             + "\n")
    if meta["not_held"]:
        L.append("Left out, the motor did not hold its operating point: " + ", ".join(meta["not_held"]) + ".\n")
    L.append("Motors " + ", ".join(points.REAL_MOTORS) + "; frequency " +
             ", ".join(map(str, points.REAL_FREQS)) + " % of rated; load " +
             ", ".join(map(str, points.REAL_LOADS)) + " % of rated torque; field weakening "
             f"(`real_fw_*`): {points.FW_FREQ} % of rated frequency at the rated voltage, "
             + ", ".join(map(str, points.FW_POWERS)) + " % of rated power; goal sensors (12-bit ADCs, "
             "1 LSB noise, 16384 counts). Truth: the simulator's `T_R_ifoc_s` (the T_R for which an "
             "IFOC's slip relation holds in the steady state, sim/README.md; without the effects "
             "`T_R_true_s`) and `R_S_true_ohm`, averaged per window; the T_R errors against the "
             "effective L_R/R_R (`T_R_true_s`) are given beside them. Constants given to the "
             "estimator: what the library's commissioning fills (`imest-commission --apply-args`, "
             "i.e. imest_comm_apply(), on the same motor with the same effects; table at the end).\n")
    L.append("| family | imest-sim flags | input |")
    L.append("|---|---|---|")
    for f, eff, inp in points.REAL_FAMILIES:
        if f in fam:
            eff = (eff + " --supply ifoc").strip() if f in points.IFOC_FAMILIES else eff
            L.append(f"| {f} | `{eff or '(linear motor)'}` | "
                     f"{INPUT_LABEL.get(inp, 'phase voltage')} |")
    goals = real_goals(fam, rows)
    if goals:
        L.append("\n## Goals (over every family but the linear controls " +
                 ", ".join(f"`{f}`" for f in REAL_CONTROLS) + ")\n")
        L.append("| goal | figure | met |")
        L.append("|---|---|---|")
        for g, fig, ok in goals:
            L.append(f"| {g} | {fig} | {'met' if ok else '**not met**'} |")
    L.append("\n## Against the promise (no valid T_R more than 2 % off, no valid R_S more than 5 % off)\n")
    L += REAL_HEAD
    for f, s in fam.items():
        L.append(_real_row(f, s))
    L.append("\nThe bold columns are the confident wrong numbers: windows the estimator marked valid "
             "whose estimate is outside the promise.\n")

    L.append("## Per motor\n")
    L += REAL_HEAD
    for f in fam:
        for n in points.REAL_MOTORS:
            ws = _sel(rows, family=f, motor=n)
            if ws:
                L.append(_real_row(f"{f}, {n}", analyse.real_stats(ws)))
    L.append("")

    L.append("## Median error of all windows (valid or not), e_TR / e_RS in %, by frequency x load\n")
    L.append("In brackets: windows with T_R valid / R_S valid, of the point's windows.\n")
    fl = sorted({(w["f_pct"], w["load_pct"]) for w in rows})
    for n in points.REAL_MOTORS:
        if not _sel(rows, motor=n):
            continue
        L.append(f"**{n}**\n")
        L.append("| f %, load % | " + " | ".join(fam) + " |")
        L.append("|---" * (len(fam) + 1) + "|")
        for fp, ld in fl:
            cells = []
            for f in fam:
                ws = _sel(rows, family=f, motor=n, f_pct=fp, load_pct=ld)
                if not ws:
                    cells.append("–")
                    continue
                cells.append(f"{_e(100 * analyse.median([w['e_tr'] for w in ws]), 1)} / "
                             f"{_e(100 * analyse.median([w['e_rs'] for w in ws]), 1)}"
                             f" ({sum(w['tr_valid'] for w in ws)}/{sum(w['rs_valid'] for w in ws)} of {len(ws)})")
            L.append(f"| {fp}, {ld} | " + " | ".join(cells) + " |")
        L.append("")

    wrong = [r for r in rows if (r["tr_valid"] and not abs(r["e_tr"]) <= analyse.REAL_TR)
             or (r["rs_valid"] and not abs(r["e_rs"]) <= analyse.REAL_RS)]
    L.append(f"## Valid and outside the promise: {len(wrong)} windows\n")
    if wrong:
        byp = defaultdict(list)
        for w in wrong:
            byp[w["name"]].append(w)
        L.append("| recording | windows | valid T_R > 2 % off | e_TR (median of those) | valid R_S > 5 % off "
                 "| e_RS (median of those) |")
        L.append("|---|---|---|---|---|---|")
        for name, ws in sorted(byp.items()):
            t = [w["e_tr"] for w in ws if w["tr_valid"] and not abs(w["e_tr"]) <= analyse.REAL_TR]
            r = [w["e_rs"] for w in ws if w["rs_valid"] and not abs(w["e_rs"]) <= analyse.REAL_RS]
            L.append(f"| {name} | {len(ws)} | {len(t)} | {_w(analyse.median(t)) if t else '–'} | {len(r)} | "
                     f"{_w(analyse.median(r)) if r else '–'} |")
        L.append("")

    if wrong:
        L.append("## The largest valid-and-wrong windows per family, against their bounds\n")
        L.append("The error bound a valid verdict stated (`tr_bound_rel`, `rs_bound_rel`) against the "
                 "error it had: the bound missed by the difference.\n")
        L.append("| family | recording | window | e_TR | T_R bound | e_TR against L_R/R_R | e_RS | R_S bound | "
                 "pe_k2_rel | E_I |")
        L.append("|---|---|---|---|---|---|---|---|---|---|")
        for f in fam:
            def size(w):
                a = abs(w["e_tr"]) / analyse.REAL_TR if w["tr_valid"] else 0.0
                b = abs(w["e_rs"]) / analyse.REAL_RS if w["rs_valid"] else 0.0
                return max(a, b)
            for w in sorted((w for w in wrong if w["family"] == f), key=size, reverse=True)[:3]:
                L.append(f"| {f} | {w['name'][len(f) + 1:]} | {w['seq']} | "
                         f"{_w(w['e_tr']) + (' (valid)' if w['tr_valid'] else '')} | "
                         f"{_w(w['tr_bound_rel'])} | {_w(w['e_tr_lrrr'])} | "
                         f"{_w(w['e_rs']) + (' (valid)' if w['rs_valid'] else '')} | {_w(w['rs_bound_rel'])} | "
                         f"{w['pe_k2_rel']:.3g} | {w['E_I']:.3g} |")
        L.append("")

    L.append("## Refusals\n")
    L.append("| family | T_R refused (reasons) | R_S refused (reasons) |")
    L.append("|---|---|---|")
    for f in fam:
        ws = _sel(rows, family=f)
        tr = Counter(w["tr_reason"] for w in ws if not w["tr_valid"])
        rs = Counter(w["rs_reason"] for w in ws if not w["rs_valid"])
        L.append(f"| {f} | " + ", ".join(f"`{k}` {v}" for k, v in tr.most_common()) + " | " +
                 ", ".join(f"`{k}` {v}" for k, v in rs.most_common()) + " |")
    L.append("")

    L.append("## Constants given to the estimator (imest-commission --apply-args)\n")
    L.append("Sigma \"data sheet\": commissioning flags the rotor deep-bar (its sigma*L_S at the "
             "test frequency is the rotor's high-frequency one) and leaves sigma to the data sheet: "
             "the motor's, with imest-replay's default uncertainty.\n")
    L.append("| motor, family | L_S [H] | L_S uncertainty | sigma | sigma uncertainty | R_S [ohm] | "
             "T_R nominal [s] | curve points | cached in |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for k, c in meta["constants"].items():
        sg = f"{c['sigma']:.5g} | {c['sigma_unc']:.3g}" if c.get("sigma") is not None else "data sheet | default"
        tr = f"{c['tr']:.5g}" if c.get("tr") else "–"
        L.append(f"| {k} | {c['ls']:.6g} | {c['ls_unc']:.3g} | {sg} | {c['rs']:.5g} | {tr} | {c['curve']} | "
                 f"commissioning/{c['source']} |")
    L.append("")
    return "\n".join(L)
