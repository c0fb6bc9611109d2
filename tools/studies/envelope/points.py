# SPDX-License-Identifier: Apache-2.0
"""The sampling design of the envelope benchmark: which operating points are simulated.

A full factorial (6 motors x 8 frequencies x 6 loads x 3 sensor sets x 4 encoders x inputs) is
about 7000 recordings; the design keeps what the goals need:

* grid: every motor x frequency (5..100 % of rated) x load (10..150 % of rated torque) with the
  goal sensors (12-bit ADCs with 1 LSB noise, 16384-count encoder, phase-voltage input). Its
  part with load >= 25 % and frequency >= 15 % is the goal region, sampled on every point.
* sweeps: one dimension at a time away from the goal sensors (ideal or 16-bit ADCs; 1024, 4096
  or 65536 counts; the duty-cycle input with an ideal inverter and with dead time and device
  drops whose model is given; measured voltages of a sine source), each on a sub-grid of every motor x 4 frequencies x 3 loads
  that reaches the envelope's corners (5 % frequency, 10 % load).

The reduced form (CTest) is a handful of points from both.

The real-motor design (`real_design`, `run --real`) is a separate measurement, outside the goal
region and the gate: the 4, 11 and 37 kW motors with the simulator's real-motor effects
(main-flux saturation, iron loss, double cage; each alone, all three, and all three on the
duty-cycle input with dead time), and the same points on the linear motor as the control, at
25-100 % of rated frequency x 25-100 % of rated torque, with the goal sensors; and field
weakening (1.5x rated frequency at the rated voltage, 25-100 % of rated power) on the linear,
the saturating and the all-effects motor. The estimator gets what the library's commissioning
gives (`motors.library_commissioning`: imest-commission --apply-args).
"""
import motors

FREQS = [5, 10, 15, 25, 40, 60, 80, 100]      # % of rated electrical frequency
LOADS = [10, 25, 50, 75, 100, 150]            # % of rated torque
SWEEP_FREQS = [5, 15, 40, 100]
SWEEP_LOADS = [10, 25, 100]
GOAL = dict(sensors="12bit", encoder=16384, input="phase")

# One-at-a-time variants around the goal sensors: (family, changes)
SWEEPS = [
    ("sensors_ideal", dict(sensors="ideal")),
    ("sensors_16bit", dict(sensors="16bit")),
    ("encoder_1024", dict(encoder=1024)),
    ("encoder_4096", dict(encoder=4096)),
    ("encoder_65536", dict(encoder=65536)),
    ("duty_ideal", dict(input="duty")),
    ("duty_inverter", dict(input="duty_inv")),
    # measured voltages of a smooth source (a line-fed motor, or a drive whose voltage channel is
    # filtered): the sine supply, the estimator told so (--voltage-kind smooth)
    ("sine_source", dict(input="sine")),
]

# Dead time and device drops of the duty_inv variant (an IGBT inverter), given to the estimator.
INVERTER = dict(dead_time=2e-6, v_switch=1.0, r_switch=0.02, v_diode=0.8, r_diode=0.01)
# The inputs whose drive has that inverter: its duty cycles with the model given (duty_inv), or
# its phase voltages measured through an anti-alias filter of AA_HZ (phase_inv).
INVERTER_INPUTS = ("duty_inv", "phase_inv")
AA_HZ = 800.0


# Real-motor families: (family, imest-sim flags, input). --real-motor sizes the three effects per
# preset (sim/README.md, Real-motor effects); the flags after it switch the others off.
REAL_FAMILIES = [
    ("real_linear", "", "phase"),
    ("real_sat", "--real-motor --iron-loss 0 --rotor single", "phase"),
    ("real_ironloss", "--real-motor --saturation 0 --rotor single", "phase"),
    ("real_deepbar", "--real-motor --saturation 0 --iron-loss 0", "phase"),
    ("real_all", "--real-motor", "phase"),
    ("real_all_duty", "--real-motor", "duty_inv"),
    # measured phase voltages on the same inverter (dead time and drops in the measured volt-
    # seconds, through an 800 Hz anti-alias filter): the inverter's harmonics reach the motor
    # whichever input the estimator reads, and the double cage answers them with another rotor
    # impedance than the single cage's (the duty input's refusals are that, not its voltage)
    ("real_all_vmeas", "--real-motor", "phase_inv"),
    # a speed-controlled IFOC driving the inverter (IFOC_FAMILIES)
    ("real_ifoc_duty", "--real-motor", "duty_inv"),
    # field weakening: above base speed at the rated voltage, constant power (FIELD_WEAKENING)
    ("real_fw_linear", "", "phase"),
    ("real_fw_sat", "--real-motor --iron-loss 0 --rotor single", "phase"),
    ("real_fw_all", "--real-motor", "phase"),
]
REAL_MOTORS = ["0.4kw", "4kw", "11kw", "37kw"]  # --real-motor needs a preset's nameplate
REAL_FREQS = [25, 50, 100]
REAL_LOADS = [25, 50, 100]
# The field-weakening families' points: FW_FREQ % of rated frequency at the rated voltage (the
# voltage limit; the flux falls as 1/f), loads of FW_POWERS % of rated power (the torque
# FW_POWERS % x f_n / f of rated: the constant-power range of a drive).
FIELD_WEAKENING = {"real_fw_linear", "real_fw_sat", "real_fw_all"}
# The closed-loop families: a speed-controlled IFOC (its T_R the motor's data-sheet value, the
# slip relation's error with the effects uncorrected, as a drive runs before any estimate)
# drives the inverter with dead time and drops, and the estimator reads its duties; the closed
# loop's own ripple and the current loops' response to the inverter's error are in the data
# (imest-sim --supply ifoc --start steady at the point's speed and load).
IFOC_FAMILIES = {"real_ifoc_duty"}
FW_FREQ = 150
FW_POWERS = [25, 50, 75, 100]



def unique_seeded(points, seed0):
    """One recording per name (a sweep point equal to a grid point is simulated once), seeded
    seed0, seed0 + 1, ... in order."""
    seen, uniq = set(), []
    for p in points:
        if p["name"] not in seen:
            seen.add(p["name"])
            uniq.append(p)
    for k, p in enumerate(uniq):
        p["seed"] = seed0 + k
    return uniq

def in_goal(p):
    return (p["sensors"] == GOAL["sensors"] and p["encoder"] == GOAL["encoder"] and
            p["input"] == GOAL["input"] and p["load_pct"] >= 25 and p["f_pct"] >= 15)


def _point(family, m, f_pct, load_pct, **kw):
    p = dict(family=family, motor=m["name"], f_pct=f_pct, load_pct=load_pct)
    p.update(GOAL)
    p.update(kw)
    return p


def _finish(pts, seed0=1000, family_in_name=False):
    """Drop points the motor cannot run at, name the rest, one recording per name, seeds."""
    out = []
    for p in pts:
        m = motors.by_name(p["motor"], real="effects" in p)
        inv = INVERTER if p["input"] in INVERTER_INPUTS else None  # the drive makes up its error
        if "power_pct" in p:
            f_hz, vll, load, i_ab, wm = motors.field_weakening_point(m, p["f_pct"], p["power_pct"])
        else:
            f_hz, vll, load, i_ab, wm = motors.operating_point(m, p["f_pct"], p["load_pct"], inv, m["vdc"])
        if wm <= 0.0:
            continue
        p.update(f_hz=f_hz, vll=vll, load_nm=load, speed_rad_s=wm, goal=in_goal(p))
        p["name"] = ("{family}_" if family_in_name else "").format(**p) + \
            "{motor}_f{f_pct}_l{load_pct}_{sensors}_e{encoder}_{input}".format(**p)
        out.append(p)
    return unique_seeded(out, seed0)


def real_design():
    """The real-motor points (dicts with `effects`, the imest-sim flags); never in the goal
    region (goal False), so never in the envelope's summary lines or its gate."""
    pts = []
    for fam, effects, inp in REAL_FAMILIES:
        for name in REAL_MOTORS:
            if fam in FIELD_WEAKENING:  # load_pct: the torque in % of rated, rounded
                grid = [(FW_FREQ, round(pw * 100 / FW_FREQ), dict(power_pct=pw)) for pw in FW_POWERS]
            else:
                grid = [(f, ld, {}) for f in REAL_FREQS for ld in REAL_LOADS]
            for f, ld, kw in grid:
                p = _point(fam, motors.by_name(name, real=True), f, ld, input=inp, **kw)
                p["effects"] = effects
                pts.append(p)
    out = _finish(pts, seed0=5000, family_in_name=True)
    keys = sorted({(p["motor"], p["f_pct"], p["load_pct"]) for p in out})
    for p in out:  # the same noise at the same operating point in every family
        p["goal"] = False
        p["seed"] = 5000 + keys.index((p["motor"], p["f_pct"], p["load_pct"]))
    return out


def design(full=True):
    """List of operating points (dicts), each a recording."""
    pts = []
    if full:
        for m in motors.MOTORS:
            for f in FREQS:
                for ld in LOADS:
                    pts.append(_point("grid", m, f, ld))
        for fam, ch in SWEEPS:
            for m in motors.MOTORS:
                for f in SWEEP_FREQS:
                    for ld in SWEEP_LOADS:
                        pts.append(_point(fam, m, f, ld, **ch))
    else:
        mm = {m["name"]: m for m in motors.MOTORS}
        for name in ("0.4kw", "4kw", "11kw", "37kw", "75kw"):
            pts.append(_point("grid", mm[name], 60, 50))
        pts.append(_point("grid", mm["2.2kw"], 100, 100))
        pts.append(_point("grid", mm["4kw"], 5, 10))
        pts.append(_point("grid", mm["37kw"], 15, 25))
        pts.append(_point("encoder_1024", mm["0.4kw"], 40, 100, encoder=1024))
        pts.append(_point("encoder_4096", mm["11kw"], 100, 100, encoder=4096))
        pts.append(_point("duty_inverter", mm["4kw"], 40, 25, input="duty_inv"))
    # drop points the motor cannot run at: slip above the supply frequency (the rotor would
    # turn backwards: small motors at 5 % frequency and high load)
    out = []
    for k, p in enumerate(pts):
        m = next(x for x in motors.MOTORS if x["name"] == p["motor"])
        inv = INVERTER if p["input"] == "duty_inv" else None  # the drive makes up its error
        f_hz, vll, load, i_ab, wm = motors.operating_point(m, p["f_pct"], p["load_pct"], inv, m["vdc"])
        if wm <= 0.0:
            continue
        p.update(f_hz=f_hz, vll=vll, load_nm=load, speed_rad_s=wm, goal=in_goal(p))
        p["name"] = "{motor}_f{f_pct}_l{load_pct}_{sensors}_e{encoder}_{input}".format(**p)
        out.append(p)
    return unique_seeded(out, 1000)
