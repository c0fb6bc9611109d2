#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""CTest check of the real-motor design (no simulation): it is a separate measurement, so no
real-motor point is in the envelope's designs (the goal region and the gate), every real point
is outside the goal region, each family covers its motors x frequencies x loads once, the same
operating point has the same noise seed in every family, and the effects reach imest-sim's
arguments and the commissioned constants imest-replay's. Exit status: 0 passed, 1 failed."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import points  # noqa: E402
import simulate  # noqa: E402


def main():
    fails = []

    def check(ok, what):
        if not ok:
            fails.append(what)

    for full in (False, True):
        check(not any(p["family"].startswith("real_") for p in points.design(full=full)),
              f"design(full={full}) has real-motor points")
    real = points.real_design()
    fams = [f for f, _, _ in points.REAL_FAMILIES]
    n = len(points.REAL_MOTORS) * len(points.REAL_FREQS) * len(points.REAL_LOADS)
    check(len(real) == len(fams) * n, f"{len(real)} real points, expected {len(fams) * n}")
    check(len({p["name"] for p in real}) == len(real), "real point names not unique")
    check(not any(p["goal"] for p in real), "a real point in the goal region")
    for f in fams:
        check(sum(p["family"] == f for p in real) == n, f"family {f}: not {n} points")
    seeds = {}
    for p in real:
        seeds.setdefault((p["motor"], p["f_pct"], p["load_pct"]), set()).add(p["seed"])
    check(all(len(s) == 1 for s in seeds.values()), "one operating point with several seeds")
    p = next(q for q in real if q["family"] == "real_sat")
    a = simulate.sim_args(p, 8.0)
    check("--real-motor" in a and a[a.index("--iron-loss") + 1] == "0", "real_sat: effects not in sim args")
    p = dict(p, consts=dict(np=2, ls=0.2, sigma=0.06, rs=1.5, tr=0.12))
    r = simulate.replay_args(p)
    check(r[r.index("--ls") + 1] == "0.2" and r[r.index("--rs") + 1] == "1.5" and
          r[r.index("--tr-nominal") + 1] == "0.12", "commissioned constants not in replay args")
    for f in fails:
        print(f"real design: {f}", file=sys.stderr)
    print("real design: " + ("FAILED" if fails else f"passed ({len(real)} points)"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
