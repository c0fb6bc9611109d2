# SPDX-License-Identifier: Apache-2.0
"""The motors of the envelope benchmark and the supply voltage of each operating point.

Each motor runs on the drive the simulator's presets model (PWM inverter, space-vector
modulation, firmware timing, one sample per 8 kHz carrier period, 12-bit sensors with ranges of
about 2.5x the rated peak current). Where a motor has no preset of its own it is given to
imest-sim as overrides of the 4kw preset (its drive), with its own sensor ranges and bus.

The supply of an operating point (frequency, load torque) is a sine of the voltage that keeps
the rotor flux at its rated value: the ideal IR-compensated V/f of a drive. A plain linear V/f
would weaken the field at low frequency (the stator resistance drop) and stall the small motors
at 5 % of rated frequency under load.
"""
import math

# name, kW, sim preset, extra imest-sim flags, rated V_ll [V] at rated f [Hz], rated torque [N m],
# bus [V], source. Motor constants in the flags are the simulator's (L_S, L_R, sigma, R_S, T_R).
MOTORS = [
    dict(name="0.4kw", kw=0.37, preset="4kw",
         flags="--pole-pairs 2 --ls 0.2908 --lr 0.2908 --sigma 0.096 --rs 5.04 --tr 0.12 "
               "--j 1.2e-3 --b 1e-4 --i-range 6 --u-range 250",
         vll=230.0, f=60.0, t_nm=2.064, vdc=340.0,
         source="the paper's motor (Wang et al. 2007; J and b assumed as in sim/), on a 340 V bus"),
    dict(name="2.2kw", kw=2.2, preset="4kw",
         flags="--pole-pairs 2 --ls 0.245 --lr 0.224 --sigma 0.085714 --rs 3.7 --tr 0.106667 "
               "--j 0.015 --b 9.7e-4 --i-range 18",
         vll=390.0, f=50.0, t_nm=14.6, vdc=560.0,
         source="2.2 kW, 400 V, 50 Hz, 5 A, 14.6 N m: the inverse-Gamma parameters of the "
                "induction machine in the open-source drive simulator motulator (Aalto "
                "University): R_s 3.7, R_R 2.1 ohm, L_sgm 21 mH, L_M 224 mH, J 0.015 kg m^2 "
                "(b assumed 1 % of rated power)"),
    dict(name="4kw", kw=4.0, preset="4kw", flags="", vll=390.0, f=50.0, t_nm=26.5, vdc=560.0,
         source="sim preset 4kw (Simscape 5 HP 400 V 50 Hz)"),
    dict(name="11kw", kw=11.0, preset="11kw", flags="", vll=390.0, f=50.0, t_nm=72.0, vdc=560.0,
         source="sim preset 11kw (a set common in simulation studies; origin not traced)"),
    dict(name="37kw", kw=37.0, preset="37kw", flags="", vll=390.0, f=50.0, t_nm=240.0, vdc=560.0,
         source="sim preset 37kw (Simscape 50 HP 400 V 50 Hz)"),
    dict(name="75kw", kw=75.0, preset="75kw", flags="", vll=390.0, f=50.0, t_nm=485.0, vdc=560.0,
         source="sim preset 75kw (Simscape 100 HP 400 V 50 Hz), standing in for 55 kW"),
]

# Motors of the real-motor design only (points.real_design). The paper's 0.4 kW motor as the
# simulator's exp1 preset (--real-motor sizes its effects from it: the paper's 230 V, 60 Hz,
# 2.064 N m) with the envelope's 0.4 kW drive given as flags (the 4kw preset's drive on a 340 V
# bus with its own sensor ranges); the motor constants are exp1's, stated for constants().
REAL_ONLY = [
    dict(name="0.4kw", kw=0.37, preset="exp1",
         flags="--pole-pairs 2 --ls 0.2908 --lr 0.2908 --sigma 0.096 --rs 5.04 --tr 0.12 "
               "--j 1.2e-3 --b 1e-4 --supply pwm --carrier-hz 8000 --modulation svpwm "
               "--timing firmware --fs 8000 --i-range 6 --u-range 250 --vdc-range 800",
         vll=230.0, f=60.0, t_nm=2.064, vdc=340.0,
         source="the paper's motor as the simulator's exp1 preset (its real-motor sizes), on the "
                "0.4 kW envelope motor's drive"),
]

def by_name(name, real=False):
    """The motor called name: of MOTORS, or for the real-motor design of REAL_ONLY first."""
    return next(m for m in (REAL_ONLY if real else []) + MOTORS if m["name"] == name)


# Constants of the presets, as sim/src/motors.c converts them (T equivalent -> L_S, sigma, T_R).
_PRESET = {
    "4kw": (1.405, 1.395, 5.839e-3, 172.2e-3, 26.5, 4000.0),
    "11kw": (0.2761, 0.1645, 2.191e-3, 76.14e-3, 72.0, 11000.0),
    "37kw": (0.08233, 0.0503, 0.724e-3, 27.11e-3, 240.0, 37000.0),
    "75kw": (0.03552, 0.02092, 0.335e-3, 15.1e-3, 485.0, 75000.0),
}


def _flag(flags, name):
    toks = flags.split()
    return float(toks[toks.index(name) + 1]) if name in toks else None


def constants(m):
    """Motor constants (n_p, L_S, L_R, sigma, R_S, T_R, b) of a motor of MOTORS."""
    if m["flags"]:
        f = m["flags"]
        return dict(np=int(_flag(f, "--pole-pairs")), ls=_flag(f, "--ls"), lr=_flag(f, "--lr"),
                    sigma=_flag(f, "--sigma"), rs=_flag(f, "--rs"), tr=_flag(f, "--tr"),
                    b=_flag(f, "--b"))
    rs, rr, lls, lm, t_nm, p_w = _PRESET[m["preset"]]
    l = lm + lls
    wn = p_w / t_nm
    return dict(np=2, ls=l, lr=l, sigma=1.0 - lm * lm / (l * l), rs=rs, tr=l / rr,
                b=0.01 * p_w / (wn * wn))


def _point(c, psi, f_hz, load_nm, phasors=False):
    """Stator voltage (alpha-beta amplitude = V_ll rms), current and speed of the steady state
    with rotor flux psi, electrical frequency f_hz and load torque load_nm (friction added)."""
    we = 2.0 * math.pi * f_hz
    m_h = math.sqrt((1.0 - c["sigma"]) * c["ls"] * c["lr"])
    wm = we / c["np"]
    for _ in range(50):  # T_e = load + b w: fixed point in the speed (b is tiny)
        te = load_nm + c["b"] * wm
        wsl = te * c["lr"] / (c["np"] * psi * psi * c["tr"])
        wm_new = (we - wsl) / c["np"]
        if abs(wm_new - wm) < 1e-12 * max(1.0, abs(wm)):
            break
        wm = wm_new
    i = psi * (1.0 + 1j * wsl * c["tr"]) / m_h
    # u = sigma L_S di/dt + R_S i + (M/L_R) dpsi/dt in the stator frame (steady rotation at we):
    # the stator equation of the model, di/dt = u/(sigma L_S) - gamma i + beta (1/T_R - j n w) psi
    sls = c["sigma"] * c["ls"]
    gamma = c["rs"] / sls + (1.0 - c["sigma"]) / (c["sigma"] * c["tr"])
    beta = m_h / (sls * c["lr"])
    u = sls * (1j * we * i + gamma * i - beta * (1.0 / c["tr"] - 1j * c["np"] * wm) * psi)
    return (u, i, wm) if phasors else (abs(u), abs(i), wm)


def flux_at(m, vll, f_hz, load_nm):
    """Rotor flux of the linear model at supply voltage vll, frequency f_hz and load torque
    load_nm (bisection)."""
    c = constants(m)
    lo, hi = 1e-3, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        v, _, _ = _point(c, mid, f_hz, load_nm)
        lo, hi = (mid, hi) if v < vll else (lo, mid)
    return 0.5 * (lo + hi)


def rated_flux(m):
    """Rotor flux of the motor at its rated voltage, frequency and torque."""
    return flux_at(m, m["vll"], m["f"], m["t_nm"])


def field_weakening_point(m, f_pct, power_pct):
    """(f_hz, V_ll, load_nm, i_ab, speed_rad_s) above base speed: f_pct % of rated frequency
    (> 100) at the rated voltage (the voltage limit: the flux falls as 1/f) and a load of
    power_pct % of the rated torque x f_n / f (constant power: power_pct % of rated power)."""
    c = constants(m)
    f_hz = m["f"] * f_pct / 100.0
    load = m["t_nm"] * power_pct / 100.0 * 100.0 / f_pct
    psi = flux_at(m, m["vll"], f_hz, load)
    u, i, wm = _point(c, psi, f_hz, load)
    return f_hz, u, load, i, wm


def operating_point(m, f_pct, load_pct, inv=None, vdc=560.0, f_carrier=8000.0):
    """(f_hz, V_ll, load_nm, i_ab, speed_rad_s) at f_pct % of rated frequency and load_pct % of
    rated torque, with the rotor flux at its rated value; i_ab is the alpha-beta current
    amplitude (sqrt 3 x the phase rms).

    With inv (dead_time, v_switch, r_switch, v_diode, r_diode) the commanded voltage also makes
    up the inverter's mean voltage error, as a drive that holds its flux does: per leg a
    square wave of t_d f_c V_dc + the drop, in phase with the current, whose fundamental is
    4/pi of it (sqrt(3/2) x that in alpha-beta), plus the slope times the current. Without
    it a 3 us dead time stalls the small motors at 10 Hz under full load."""
    c = constants(m)
    psi = rated_flux(m)
    f_hz = m["f"] * f_pct / 100.0
    load = m["t_nm"] * load_pct / 100.0
    u, i, wm = _point(c, psi, f_hz, load, phasors=True)
    if inv:
        e = inv["dead_time"] * f_carrier * vdc + 0.5 * (inv["v_switch"] + inv["v_diode"])
        r = 0.5 * (inv["r_switch"] + inv["r_diode"])
        u = u + (math.sqrt(1.5) * 4.0 / math.pi * e / abs(i) + r) * i
    return f_hz, abs(u), load, abs(i), wm


def rated_current(m):
    return operating_point(m, 100.0, 100.0)[3]


COMMISSION_PRESET = {"0.4kw": "exp1"}  # imest-commission's preset of a motor (default: its own)


def library_commissioning(m, effects, commission, cache_dir, inverter_flags):
    """What the library's commissioning gives the estimator for motor m with the imest-sim
    real-motor flags `effects` (the same flags imest-commission takes): imest-commission
    --apply-args (the config imest_comm_apply() fills, as imest-replay options) on the preset
    with those effects, on a drive with the inverter of inverter_flags. Cached in
    a file per motor and effects in cache_dir (run once per motor and family). Returns dict: `args` (the
    constants' options), `inverter` (the inverter model's), and the values for the tables (np,
    ls, sigma or None when commissioning leaves it to the data sheet, ls_unc, sigma_unc, rs, tr,
    curve = the magnetising curve's points)."""
    import os
    import subprocess
    tag = "_".join(t.lstrip("-").replace(":", "") for t in effects.split()) or "linear"
    path = os.path.join(cache_dir, f"{m['name']}_{tag}.txt")
    if not os.path.exists(path):
        os.makedirs(cache_dir, exist_ok=True)
        cmd = [commission, "--preset", COMMISSION_PRESET.get(m["name"], m["preset"])] + \
            effects.split() + list(inverter_flags) + ["--apply-args"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()}")
        with open(path + ".tmp", "w") as f:
            f.write(f"# {' '.join(cmd[1:])}\n" + r.stdout)
        os.replace(path + ".tmp", path)
    with open(path) as f:
        lines = [line.split() for line in f if line.strip() and not line.startswith("#")]
    args, inv = lines[0], lines[1]
    opt = {args[k]: args[k + 1] for k in range(0, len(args) - 1, 2)}
    return dict(args=args, inverter=inv, np=int(opt["--pole-pairs"]), ls=float(opt["--ls"]),
                sigma=float(opt["--sigma"]) if "--sigma" in opt else None,
                ls_unc=float(opt["--ls-uncertainty"]),
                sigma_unc=float(opt["--sigma-uncertainty"]) if "--sigma-uncertainty" in opt else None,
                rs=float(opt["--rs"]), tr=float(opt["--tr-nominal"]) if "--tr-nominal" in opt else None,
                curve=len(opt["--ls-curve"].split(",")) if "--ls-curve" in opt else 0,
                source=os.path.basename(path))


def commissioning(m, effects, sim):
    """The constants a user's commissioning gives for motor m (a preset of MOTORS) with the
    imest-sim real-motor flags `effects`: n_p, L_S, sigma, R_S, T_R (dict as constants()).

    A standstill test gives R_S at ambient (the preset's R_S; the runs are at ambient) and the
    leakages; a no-load test at the drive's rated voltage and frequency gives L_S = L_ls + L_m
    with L_m the static magnetising inductance at the no-load flux. L_m is read from the
    simulator itself: its `lm_h` column (the static L_m(|psi_m|)) in the steady state on an
    ideal sine at m's V_ll and f, no load, ideal sensors. L_R = L_lr + L_m with the preset's
    (DC) leakage L_lr = L_ls, sigma = 1 - L_m^2 / (L_S L_R). T_R nominal is the linear model's
    (the preset's L_R / R_R with its M). Without effects: constants(m)."""
    import os
    import subprocess
    import tempfile
    c = constants(m)
    if not effects.split() or m["flags"]:
        return c
    lls = _PRESET[m["preset"]][2]
    fd, path = tempfile.mkstemp(suffix=".csv")
    os.close(fd)
    try:
        subprocess.run([sim, "--preset", m["preset"]] + effects.split() +
                       ["--supply", "sine", "--timing", "ideal", "--start", "steady", "--vll", f"{m['vll']:g}",
                        "--freq", f"{m['f']:g}", "--load-nm", "0", "--ideal-sensors", "--no-thermal",
                        "--duration", "0.02", "--no-progress", "--out", path],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(path) as f:
            head = f.readline().strip().split(",")
            k = head.index("lm_h")
            lm = [float(line.split(",")[k]) for line in f if line.strip()]
    finally:
        os.remove(path)
    lm = sum(lm) / len(lm)
    ls = lls + lm
    return dict(np=c["np"], ls=ls, lr=ls, sigma=1.0 - lm * lm / (ls * ls), rs=c["rs"], tr=c["tr"],
                b=c["b"], lm=lm)
