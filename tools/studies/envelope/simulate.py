# SPDX-License-Identifier: Apache-2.0
"""One recording of the envelope benchmark: simulate it, replay it, average the truth per window.

The simulator writes a CSV to a temporary file; imest-replay reads it exactly as a user's log;
an awk pass averages the simulator's truth columns over the replay's windows (window k = data
rows k*N .. k*N+N-1, N samples per window). The CSV is deleted afterwards.
"""
import argparse
import os
import re
import subprocess
import sys

import motors
import points

FS_HZ = 8000.0  # the drive presets: one sample per 8 kHz carrier period

# tr_ifoc_s: the T_R an IFOC needs (T_R_ifoc_s, written with the real-motor effects on; without
# them it is T_R_true_s); tr_true_s: the effective L_R/R_R (T_R_true_s)
TRUTH_AWK = r"""
NR == 1 { for (j = 1; j <= NF; j++) col[$j] = j; ki = ("T_R_ifoc_s" in col) ? col["T_R_ifoc_s"] : col["T_R_true_s"]; next }
{ r = NR - 2; k = int(r / N); n[k]++;
  tr[k] += $col["T_R_true_s"]; rs[k] += $col["R_S_true_ohm"]; ti[k] += $ki;
  w[k] += $col["speed_rad_s"]; te[k] += $col["torque_nm"]; ld[k] += $col["load_nm"];
  if (k > kmax) kmax = k }
END { print "seq,tr_true_s,rs_true_ohm,speed_rad_s,torque_nm,load_nm,rows,tr_ifoc_s";
      for (k = 0; k <= kmax; k++) if (n[k] == N)
        printf "%d,%.9g,%.9g,%.7g,%.7g,%.7g,%d,%.9g\n", k, tr[k]/n[k], rs[k]/n[k], w[k]/n[k],
               te[k]/n[k], ld[k]/n[k], n[k], ti[k]/n[k] }
"""


def motor_of(p):
    """The motor of a point (a real-motor point's, with `effects`, from motors.REAL_ONLY first)."""
    return motors.by_name(p["motor"], real="effects" in p)


def sim_args(p, duration_s):
    m = motor_of(p)
    # the bus: the motor's, raised where the point needs more than the linear range (0.97 of
    # V_dc / sqrt 2 with space-vector modulation): 150 % load at rated frequency
    vdc = max(m["vdc"], p["vll"] * 2 ** 0.5 / 0.97)
    a = ["--preset", m["preset"]] + m["flags"].split() + p.get("effects", "").split()
    a += ["--no-thermal", "--start", "steady", "--vdc", f"{vdc:.1f}",
          "--freq", f"{p['f_hz']:.6g}", "--vll", f"{p['vll']:.6g}", "--load-nm", f"{p['load_nm']:.6g}",
          "--duration", f"{duration_s:g}", "--seed", str(p["seed"]),
          "--encoder-counts", str(p["encoder"]), "--no-progress"]
    if p["sensors"] == "ideal":
        a.append("--ideal-sensors")
    elif p["sensors"] == "16bit":
        a += ["--adc-bits", "16"]
    if p["input"] == "duty_inv":
        a += inverter_flags(points.INVERTER)
    elif p["input"] == "phase_inv":  # the measured voltage carries the dead time (--vmeas aa)
        a += inverter_flags(points.INVERTER) + ["--vmeas", "aa", "--aa-hz", f"{points.AA_HZ:g}"]
    elif p["input"] == "sine":  # a later --supply overrides the motor's PWM drive
        a += ["--supply", "sine", "--timing", "ideal"]
    if p.get("family") in points.IFOC_FAMILIES:  # the speed loop holds the point's speed
        a += ["--supply", "ifoc", "--speed-ref", f"{p['speed_rad_s'] * 30.0 / 3.141592653589793:.8g}"]
    return a


def inverter_flags(inv):
    """--dead-time ... --r-diode: the same flags for imest-sim (the inverter) and imest-replay
    (its model)."""
    return ["--dead-time", f"{inv['dead_time']:.6g}", "--v-switch", f"{inv['v_switch']:.6g}",
            "--r-switch", f"{inv['r_switch']:.6g}", "--v-diode", f"{inv['v_diode']:.6g}",
            "--r-diode", f"{inv['r_diode']:.6g}"]


def constants_uncertainty(p):
    """--ls-uncertainty, --sigma-uncertainty: 0 for the simulator's own constants (exact); for
    the study's own no-load commissioning (motors.commissioning, deadtime --real-motor) what
    imest_comm_apply() states for a rotating commissioning without fit quality (imest_commission.h:
    its floors, 0.2 % and 0.5 %). The library's commissioning (`args` in the constants) states its
    own."""
    if p.get("consts"):
        return ["--ls-uncertainty", "0.002", "--sigma-uncertainty", "0.005"]
    return ["--ls-uncertainty", "0", "--sigma-uncertainty", "0"]


def replay_args(p, extra=()):
    """The estimator's options: the motor's constants (with `consts` in the point: with `args`,
    what imest_comm_apply() fills (motors.library_commissioning), sigma from the data sheet
    (the motor's, with imest-replay's default uncertainty) where commissioning leaves it; else
    the study's no-load commissioning, with R_S and T_R nominal), how well they are known, the
    input (the duty-cycle input with the commissioned inverter model where there is one)."""
    c = p.get("consts") or motors.constants(motor_of(p))
    base = ["--from-rest", "no", "--quiet"]
    if c.get("args"):
        a = base + c["args"]
        if c["sigma"] is None:
            a += ["--sigma", f"{motors.constants(motor_of(p))['sigma']:.7g}"]
    else:
        a = ["--pole-pairs", str(c["np"]), "--ls", f"{c['ls']:.7g}", "--sigma", f"{c['sigma']:.7g}"] + \
            base + constants_uncertainty(p)
        if p.get("consts"):
            a += ["--rs", f"{c['rs']:.7g}", "--tr-nominal", f"{c['tr']:.7g}"]
    if p["input"] == "phase":
        # the phase voltage of the simulated drive is the volt-seconds of the sample period
        # that just ended: half a sample behind the currents
        a += ["--u-delay", f"{0.5 / FS_HZ:.9g}"]
        if "--rotor-hf-rr" in a:
            # a deep-bar rotor: the simulated drive's inverter is ideal (no dead time, no drops),
            # which the config says (its harmonics are 0); the bus is the motor's
            a += inverter_flags(dict.fromkeys(points.INVERTER, 0.0)) + \
                ["--inverter-vdc", f"{motor_of(p)['vdc']:g}"]
    elif p["input"] == "phase_inv":
        # the instantaneous phase voltages through the anti-alias filter (on the currents too),
        # which the estimator models on the angle
        a += ["--aa-hz", f"{points.AA_HZ:g}"]
        if "--rotor-hf-rr" in a and c.get("inverter"):
            # a deep-bar rotor: the commissioned inverter (and bus) size the dead time's harmonics
            a += c["inverter"]
    elif p["input"] == "sine":
        # the sine supply's voltage is its value at the sample instant: no delay, no staircase
        a += ["--voltage-kind", "smooth"]
    elif p["input"] == "duty_inv" and c.get("inverter"):
        a += ["--voltage", "duty"] + c["inverter"]
    else:
        inv = points.INVERTER if p["input"] == "duty_inv" else dict.fromkeys(points.INVERTER, 0.0)
        a += ["--voltage", "duty"] + inverter_flags(inv)
    return a + list(extra)


def simulate(sim, args, csv_path, lf):
    """imest-sim ARGS --out CSV; returns an error message or None."""
    r = subprocess.run([sim] + args + ["--out", csv_path], stdout=lf, stderr=lf)
    return None if r.returncode == 0 else f"imest-sim failed ({r.returncode})"


def replay_to(replay, args, csv_path, out_path, lf):
    """imest-replay ARGS CSV > OUT; returns an error message or None."""
    with open(out_path, "w") as out:
        r = subprocess.run([replay] + args + [csv_path], stdout=out, stderr=lf)
    return None if r.returncode == 0 else f"imest-replay failed ({r.returncode})"


def truth_to(csv_path, out_path, lf):
    """The simulator's truth averaged over each 1-s window of CSV, into OUT."""
    with open(out_path, "w") as out:
        r = subprocess.run(["awk", "-F,", "-v", f"N={int(round(FS_HZ))}", TRUTH_AWK, csv_path],
                           stdout=out, stderr=lf)
    return None if r.returncode == 0 else "truth averaging failed"


NOT_HELD = "not held"  # run_point's answer when the motor left its operating point


def held(p, truth_path):
    """Whether the recording kept its operating point: every window's mean speed positive and
    within 20 % of synchronous speed of the planned one. A drive that stalls (a small motor at
    5 % frequency under full load with dead time: the rotor stops and the passive load holds it
    at rest; imest-sim notes it) is not an operating point to estimate at."""
    m = motor_of(p)
    w_sync = 2.0 * 3.141592653589793 * p["f_hz"] / motors.constants(m)["np"]
    with open(truth_path) as f:
        next(f)
        speeds = [float(line.split(",")[3]) for line in f if line.strip()]
    return bool(speeds) and all(w > 0.0 and abs(w - p["speed_rad_s"]) <= 0.2 * w_sync for w in speeds)


def run_point(p, sim, replay, work, duration_s, extra_replay=(), keep=False):
    """Simulate and replay one point into work/<name>.{replay,truth}.csv; returns an error
    message, NOT_HELD (nothing replayed), or None."""
    name = p["name"]
    csv_path = os.path.join(work, name + ".sim.csv")
    log = os.path.join(work, name + ".log")
    truth = os.path.join(work, name + ".truth.csv")
    with open(log, "w") as lf:
        err = simulate(sim, sim_args(p, duration_s), csv_path, lf) or truth_to(csv_path, truth, lf)
        if not err and not held(p, truth):
            for path in (truth, os.path.join(work, name + ".replay.csv")):
                if os.path.exists(path):
                    os.remove(path)
            err = NOT_HELD
        elif not err:
            err = replay_to(replay, replay_args(p, extra_replay), csv_path,
                            os.path.join(work, name + ".replay.csv"), lf)
    if err and err != NOT_HELD:
        return f"{err}, see {log}"
    if not keep and os.path.exists(csv_path):
        os.remove(csv_path)
    return err


# the checkout's top: this file is tools/studies/envelope/simulate.py
_TOP = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def print_version(prog):
    """NAME VERSION (include/imest/imest_version.h) and the licence, as the compiled tools."""
    with open(os.path.join(_TOP, "include", "imest", "imest_version.h"), encoding="utf-8") as f:
        v = re.search(r'^#define IMEST_VERSION_STRING "([^"]+)"', f.read(), re.M).group(1)
    print("%s %s\nLicence: Apache License 2.0 <https://www.apache.org/licenses/LICENSE-2.0>" % (prog, v))


class ArgParser(argparse.ArgumentParser):
    """argparse with the messages of every imest tool: "NAME: unknown option '--x'" and
    "Try 'NAME --help'." on stderr, exit 2."""

    def error(self, message):
        m = re.match(r"unrecognized arguments: (\S+)", message)
        if m:
            message = "unknown option '%s'" % m.group(1)
        sys.stderr.write("%s: %s\nTry '%s --help'.\n" % (self.prog, message, self.prog))
        sys.exit(2)
