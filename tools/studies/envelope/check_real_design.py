#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""CTest check of the real-motor design (no simulation): it is a separate measurement, so no
real-motor point is in the envelope's designs (the goal region and the gate), every real point
is outside the goal region, each family covers its motors x frequencies x loads once, the same
operating point has the same noise seed in every family, field weakening is above rated
frequency at the rated voltage, and the effects reach imest-sim's arguments and the
commissioned constants (and inverter model) imest-replay's. Exit status: 0 passed, 1 failed."""
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
    size = {f: len(points.REAL_MOTORS) * (len(points.FW_POWERS) if f in points.FIELD_WEAKENING else
                                          len(points.REAL_FREQS) * len(points.REAL_LOADS)) for f in fams}
    check(len(real) == sum(size.values()), f"{len(real)} real points, expected {sum(size.values())}")
    check(len({p["name"] for p in real}) == len(real), "real point names not unique")
    check(not any(p["goal"] for p in real), "a real point in the goal region")
    for f in fams:
        check(sum(p["family"] == f for p in real) == size[f], f"family {f}: not {size[f]} points")
    fw = [p for p in real if p["family"] in points.FIELD_WEAKENING]
    check(all(p["f_pct"] > 100 and abs(p["vll"] - simulate.motor_of(p)["vll"]) < 1e-6 for p in fw),
          "field weakening: not above rated frequency at the rated voltage")
    seeds = {}
    for p in real:
        seeds.setdefault((p["motor"], p["f_pct"], p["load_pct"]), set()).add(p["seed"])
    check(all(len(s) == 1 for s in seeds.values()), "one operating point with several seeds")
    p = next(q for q in real if q["family"] == "real_sat")
    a = simulate.sim_args(p, 8.0)
    check("--real-motor" in a and a[a.index("--iron-loss") + 1] == "0", "real_sat: effects not in sim args")
    # the library's commissioning (imest-commission --apply-args) reaches imest-replay as it is;
    # without its sigma (a deep-bar rotor) the data sheet's, with the commissioned inverter model
    args = "--pole-pairs 2 --ls 0.2 --ls-uncertainty 0.003 --rs 1.5 --tr-nominal 0.12".split()
    inv = "--dead-time 2e-06 --v-switch 0.9 --r-switch 0.01 --v-diode 0.9 --r-diode 0".split()
    p = dict(p, consts=dict(args=args, inverter=inv, sigma=None))
    r = simulate.replay_args(p)
    check(r[r.index("--ls") + 1] == "0.2" and r[r.index("--rs") + 1] == "1.5" and
          r[r.index("--tr-nominal") + 1] == "0.12" and "--sigma" in r, "commissioned constants not in replay args")
    q = next(x for x in real if x["family"] == "real_ifoc_duty")
    a = simulate.sim_args(q, 8.0)
    last = len(a) - 1 - a[::-1].index("--supply")  # a later flag overrides the preset's
    check(a[last + 1] == "ifoc" and
          abs(float(a[a.index("--speed-ref") + 1]) - q["speed_rad_s"] * 30.0 / 3.141592653589793) < 1e-3,
          "real_ifoc_duty: no IFOC at the point's speed in sim args")
    q = next(x for x in real if x["input"] == "duty_inv")
    r = simulate.replay_args(dict(q, consts=dict(args=args, inverter=inv, sigma=None)))
    check(r[r.index("--v-switch") + 1] == "0.9", "duty input: not the commissioned inverter model")
    for f in fails:
        print(f"real design: {f}", file=sys.stderr)
    print("real design: " + ("FAILED" if fails else f"passed ({len(real)} points)"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
