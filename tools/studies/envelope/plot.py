# SPDX-License-Identifier: Apache-2.0
"""The coverage map of the envelope benchmark (coverage.png): motor x frequency x load.

Top row T_R, bottom row R_S; one panel per motor, frequency (% of rated) across, load (% of
rated torque) up. Colour: share of the cell's windows with the parameter valid and within its
goal (1 % T_R, 3 % R_S). Marks: an open circle where a window was valid and marginally wrong
(T_R 2-10 %, R_S 5-25 %), a red cross where one was valid and grossly wrong. The dashed frame
is the goal region (load >= 25 %, frequency >= 15 %). Grid points only (goal sensors).
"""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import analyse  # noqa: E402
import motors  # noqa: E402


def coverage_map(rows, path, title):
    grid = [w for w in rows if w["family"] == "grid"]
    names = [m["name"] for m in motors.MOTORS if any(w["motor"] == m["name"] for w in grid)]
    if not names:
        return False
    freqs = sorted({w["f_pct"] for w in grid})
    loads = sorted({w["load_pct"] for w in grid})
    fig, axes = plt.subplots(2, len(names), figsize=(2.1 * len(names) + 1.4, 5.4), squeeze=False,
                             sharex=True, sharey=True, constrained_layout=True)
    cmap = plt.get_cmap("RdYlGn")
    for row, (key, vkey, lo, hi, label) in enumerate(
            (("tr_good", "tr_valid", analyse.TR_MARG, analyse.TR_GROSS, "T_R valid, within 1 %"),
             ("rs_good", "rs_valid", analyse.RS_MARG, analyse.RS_GROSS, "R_S valid, within 3 %"))):
        ekey = "e_tr" if row == 0 else "e_rs"
        for col, name in enumerate(names):
            ax = axes[row][col]
            img = np.full((len(loads), len(freqs)), np.nan)
            for i, ld in enumerate(loads):
                for j, f in enumerate(freqs):
                    ws = [w for w in grid if w["motor"] == name and w["f_pct"] == f and w["load_pct"] == ld]
                    if not ws:
                        continue
                    img[i, j] = sum(w[key] for w in ws) / len(ws)
                    errs = [abs(w[ekey]) for w in ws if w[vkey]]
                    if any(not (e <= hi) for e in errs):
                        ax.plot(j, i, "x", color="#b00000", ms=9, mew=2.2)
                    elif any(e > lo for e in errs):
                        ax.plot(j, i, "o", mfc="none", mec="black", ms=8, mew=1.2)
            im = ax.imshow(img, origin="lower", cmap=cmap, vmin=0.0, vmax=1.0, aspect="auto",
                           interpolation="nearest")
            # goal region frame
            j0 = next(j for j, f in enumerate(freqs) if f >= 15) - 0.5
            i0 = next(i for i, ld in enumerate(loads) if ld >= 25) - 0.5
            ax.add_patch(plt.Rectangle((j0, i0), len(freqs) - 0.5 - j0, len(loads) - 0.5 - i0,
                                       fill=False, ls="--", lw=1.2, ec="#2040c0"))
            ax.set_xticks(range(len(freqs)))
            ax.set_xticklabels([str(f) for f in freqs], fontsize=7)
            ax.set_yticks(range(len(loads)))
            ax.set_yticklabels([str(x) for x in loads], fontsize=7)
            if row == 0:
                ax.set_title(name, fontsize=10)
            if row == 1:
                ax.set_xlabel("frequency, % of rated", fontsize=8)
            if col == 0:
                ax.set_ylabel(f"{label}\nload, % of rated", fontsize=8)
    fig.colorbar(im, ax=axes, shrink=0.8, aspect=30, label="share of windows")
    fig.suptitle(title + "   (o valid, 2-10 % / 5-25 % off;  x valid, grossly off;  dashed: goal region)",
                 fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
