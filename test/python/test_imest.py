#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""The Python module (python/imest) against imest-replay: the same log, the same settings, the
same windows, compared column by column to the digits replay prints. Logs from imest-sim (the
4 kW drive, which records both the phase voltages and the duty cycles with the DC bus); each
module run takes the arrays read back from the CSV replay reads. Also: the module's config
defaults against imest_config_default() printed by a C program, and bad inputs.

usage: test_imest.py --replay BIN --sim BIN --dump BIN --lib LIBIMEST_SO --work DIR [unittest args]
"""
import argparse
import math
import os
import subprocess
import sys
import unittest
import warnings

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))

ARGS = None
# the 4 kW preset (sim/README.md): the simulator's own constants, exact
MOTOR = ["--pole-pairs", "2", "--ls", "0.178039", "--sigma", "0.0645168", "--ls-uncertainty", "0", "--sigma-uncertainty", "0"]
MOTOR_CFG = dict(pole_pairs=2, ls_h=0.178039, sigma=0.0645168, ls_uncertainty=0.0, sigma_uncertainty=0.0)

# imest-replay's format of each column (tools/replay/replay.c print_row)
FORMATS = {
    "t_end_s": "%.6f", "T_R_s": "%.9g", "R_S_ohm": "%.9g", "E_I": "%.6g", "valid": "%d", "status": "%s",
    "seq": "%d", "K1": "%.9g", "K2": "%.9g", "pe_k1_rel": "%.6g", "pe_k2_rel": "%.6g", "H11": "%.6g",
    "H12": "%.6g", "H22": "%.6g", "hessian_pd": "%d", "n_roots": "%d", "n_admissible": "%d",
    "slip_ratio": "%.4g", "i_rms_a": "%.6g", "used_samples": "%d", "flags": "0x%x", "tr_valid": "%d",
    "rs_valid": "%d", "tr_reason": "%s", "rs_reason": "%s", "span_s": "%.6g", "windows": "%d",
    "tr_bound_rel": "%.6g", "rs_bound_rel": "%.6g",
}


def sh(cmd, **kw):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, **kw)
    if p.returncode != 0:
        raise AssertionError("%s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return p.stdout


def sim(name, *args):
    path = os.path.join(ARGS.work, name)
    if not os.path.exists(path):
        sh([ARGS.sim] + list(args) + ["--out", path])
    return path


def read_csv(path):
    import numpy as np
    return np.genfromtxt(path, delimiter=",", names=True, deletechars="")


def write_csv(path, d, names):
    """The columns `names` of d, as imest-sim writes numbers (%.9g)."""
    with open(path, "w") as f:
        f.write(",".join(names) + "\n")
        for row in zip(*(d[n] for n in names)):
            f.write(",".join("%.9g" % x for x in row) + "\n")


def replay(path, *opts):
    out = sh([ARGS.replay] + MOTOR + ["--quiet"] + list(opts) + [path])
    lines = out.strip().split("\n")
    header = lines[0].split(",")
    return header, [dict(zip(header, l.split(","))) for l in lines[1:]]


def is_nan_text(s):
    return s in ("nan", "-nan")


class Replay(unittest.TestCase):
    """The module's windows are replay's, to every printed digit."""

    @classmethod
    def setUpClass(cls):
        import numpy as np  # noqa: F401 (python3-numpy: tools/scripts/setup-deps test)
        import imest
        cls.imest = imest
        # 4 s at rated load, 50 Hz, 8 kHz, 12-bit sensors, 16384 counts; with 2 us dead time
        cls.ideal = sim("4kw.csv", "--preset", "4kw", "--duration", "4")
        cls.dt = sim("4kw_dt2.csv", "--preset", "4kw", "--duration", "4", "--dead-time", "2e-6")

    def same(self, path, rows, w, what, least=3):
        header, want = rows
        self.assertEqual(header[: len(FORMATS)], list(FORMATS), "replay's columns changed: update FORMATS")
        self.assertEqual(self.imest.columns()[: len(header)], header, "the module's first columns are replay's")
        self.assertGreaterEqual(len(want), least, "%s: too few windows to compare" % what)
        self.assertEqual(len(w), len(want), "%s: %d windows from the module, %d from replay" % (what, len(w), len(want)))
        for k, row in enumerate(want):
            for name in header:
                got = w[name][k]
                if is_nan_text(row[name]):
                    self.assertTrue(math.isnan(got), "%s window %d %s: module %r, replay nan" % (what, k, name, got))
                    continue
                text = FORMATS[name] % (got if FORMATS[name] == "%s" else got.item())
                self.assertEqual(text, row[name], "%s window %d column %s: module %s, replay %s"
                                 % (what, k, name, text, row[name]))

    def arrays(self, d, duty):
        kw = dict(t=d["t"], i=(d["i_a"], d["i_b"], d["i_c"]), theta=d["theta"])
        if duty:
            kw.update(duty=(d["d_a"], d["d_b"], d["d_c"]), vdc=d["v_dc"])
        else:
            kw.update(u=(d["u_a"], d["u_b"], d["u_c"]))
        return kw

    def test_phase_voltages(self):
        d = read_csv(self.ideal)
        w = self.imest.run(self.imest.Config(**MOTOR_CFG), **self.arrays(d, False))
        self.same(self.ideal, replay(self.ideal), w, "phase input")
        self.assertTrue(w["valid"][1:].all(), "the rated-load windows after the first are valid")

    def test_smooth_voltage_kind(self):
        # the setting reaches the library as replay's option does (the bounds shrink: rs_bound_rel
        # differs), and the duty input refuses it
        d = read_csv(self.ideal)
        w = self.imest.run(self.imest.Config(voltage_kind="smooth", **MOTOR_CFG), **self.arrays(d, False))
        self.same(self.ideal, replay(self.ideal, "--voltage-kind", "smooth"), w, "smooth phase input")
        stair = self.imest.run(self.imest.Config(**MOTOR_CFG), **self.arrays(d, False))
        self.assertTrue((w["rs_bound_rel"][1:] < stair["rs_bound_rel"][1:]).all())
        with self.assertRaises(ValueError) as cm:
            self.imest.run(self.imest.Config(voltage_kind="smooth", **MOTOR_CFG), **self.arrays(read_csv(self.dt), True))
        self.assertIn("voltage_kind", str(cm.exception))

    def test_duty_cycles_with_the_inverter_model(self):
        # the dead time given without its uncertainty: replay takes 0.2, and so must the module
        d = read_csv(self.dt)
        cfg = self.imest.Config(inverter_dead_time_s=2e-6, **MOTOR_CFG)
        w = self.imest.run(cfg, **self.arrays(d, True))
        self.same(self.dt, replay(self.dt, "--voltage", "duty", "--dead-time", "2e-6"), w, "duty input")
        self.assertTrue(w["tr_valid"][1:].all())

    def test_options(self):
        # half-second windows, another filter, a known R_S, centred PWM timing, a last partial
        # window (4 s = 8 windows; 3.8 s: 7 and one of 0.3 s, estimated because it is >= half)
        d = read_csv(self.dt)
        n = int(3.8 * 8000) + 1
        part = os.path.join(ARGS.work, "4kw_dt2_3p8.csv")
        names = ["t", "d_a", "d_b", "d_c", "v_dc", "i_a", "i_b", "i_c", "theta"]
        write_csv(part, {k: d[k][:n] for k in names}, names)
        d = read_csv(part)
        cfg = self.imest.Config(window_s=0.5, filter_hz=80, rs_nominal_ohm=1.4, pwm_timing="centred",
                                inverter_dead_time_s=2e-6, inverter_uncertainty=0.3, **MOTOR_CFG)
        w = self.imest.run(cfg, **self.arrays(d, True))
        self.same(part, replay(part, "--voltage", "duty", "--window", "0.5", "--filter-hz", "80", "--rs", "1.4",
                               "--pwm-timing", "centred", "--dead-time", "2e-6", "--inverter-uncertainty", "0.3"),
                  w, "options")
        self.assertEqual(len(w), 8)
        self.assertEqual(w["samples"][-1], int(0.3 * 8000) + 1)

    def test_clipped_currents_and_t_in_ms(self):
        # currents clipped at 90 % of their peak: replay's auto limit marks those windows
        # adc_saturation; t in milliseconds with the rate given (--fs)
        import numpy as np
        d = read_csv(self.ideal)
        names = ["t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta"]
        top = 0.9 * max(np.abs(d[k]).max() for k in ("i_a", "i_b", "i_c"))
        c = {k: d[k] for k in names}
        c["t"] = d["t"] * 1000.0 + 5.0
        c["i_b"] = np.clip(d["i_b"], -top, top)
        path = os.path.join(ARGS.work, "4kw_clipped_ms.csv")
        write_csv(path, c, names)
        d = read_csv(path)
        with warnings.catch_warnings(record=True) as notes:
            warnings.simplefilter("always")
            w = self.imest.run(self.imest.Config(**MOTOR_CFG), fs=8000, **self.arrays(d, False))
        self.assertTrue(any("i_b looks clipped" in str(x.message) for x in notes), [str(x.message) for x in notes])
        self.same(path, replay(path, "--fs", "8000"), w, "clipped, t in ms")
        self.assertIn("adc_saturation", list(w["status"]))
        self.assertAlmostEqual(w["t_end_s"][0], 0.005 + 0.999875, places=9)

    def test_start_at_rest_slow_log_last_window(self):
        # the paper's motor started direct on line from rest, logged at 1 kHz for 1.6 s: replay
        # finds the start at rest, lowers the speed limit to 2 fs, and estimates the last 0.6 s
        path = sim("exp1_1k.csv", "--preset", "exp1", "--duration", "1.6", "--fs", "1000")
        d = read_csv(path)
        motor = dict(pole_pairs=2, ls_h=0.2908, sigma=0.096, ls_uncertainty=0.0, sigma_uncertainty=0.0)
        w = self.imest.run(self.imest.Config(**motor), **self.arrays(d, False))
        out = sh([ARGS.replay, "--quiet", "--pole-pairs", "2", "--ls", "0.2908", "--sigma", "0.096", "--ls-uncertainty", "0",
                  "--sigma-uncertainty", "0", path])
        lines = out.strip().split("\n")
        header = lines[0].split(",")
        self.same(path, (header, [dict(zip(header, l.split(","))) for l in lines[1:]]), w, "exp1 at 1 kHz", least=2)
        self.assertEqual(len(w), 2)
        self.assertNotEqual(w["status"][0], "warmup", "started at rest: no warm-up")
        # the at-rest rule matters here (without it the first window is warm-up); without the
        # speed-limit rule the default 3000 rad/s would be refused at 1 kHz (at most 3 fs)
        other = self.imest.run(self.imest.Config(start_at_rest=0, **motor),
                               **self.arrays(d, False))
        self.assertNotEqual(other.tobytes(), w.tobytes())

    def test_run_frame(self):
        try:
            import pandas as pd
        except ImportError:
            self.skipTest("python3-pandas is not installed")
        df = pd.read_csv(self.ideal)   # has both inputs' columns: phase by default, as replay
        out = self.imest.run_frame(df, self.imest.Config(**MOTOR_CFG))
        self.assertIsInstance(out, pd.DataFrame)
        self.same(self.ideal, replay(self.ideal), out.to_records(index=False), "run_frame")
        duty = self.imest.run_frame(df, self.imest.Config(**MOTOR_CFG), voltage="duty")
        self.same(self.ideal, replay(self.ideal, "--voltage", "duty"), duty.to_records(index=False), "run_frame duty")


class Defaults(unittest.TestCase):
    def test_defaults_are_imest_config_default(self):
        import imest
        c_side = {}
        for line in sh([ARGS.dump]).strip().split("\n"):
            name, value = line.split(" ")
            c_side[name] = float.fromhex(value) if "0x" in value else int(value)
        py = imest.Config.defaults()
        self.assertEqual(sorted(py), sorted(c_side), "the module's fields are imest_config_t's")
        for name, value in c_side.items():
            self.assertEqual(py[name], value, name)
            self.assertEqual(type(py[name]), type(value), name)
        cfg = imest.Config()
        self.assertEqual(cfg.to_dict(), c_side)
        self.assertEqual(cfg.inverter_uncertainty, c_side["inverter.uncertainty"])
        self.assertEqual(cfg["inverter.uncertainty"], c_side["inverter.uncertainty"])
        self.assertEqual(cfg.given(), set())

    def test_version_is_the_library_header(self):
        import re
        import imest
        with open(os.path.join(HERE, "..", "..", "include", "imest", "imest_version.h")) as f:
            v = re.search(r'IMEST_VERSION_STRING "([0-9.]+)"', f.read()).group(1)
        self.assertEqual(imest.__version__, v)


class BadInput(unittest.TestCase):
    """Wrong inputs are a clear exception; nothing is cut to fit."""

    @classmethod
    def setUpClass(cls):
        import numpy as np
        import imest
        cls.imest, cls.np = imest, np
        n = 8000
        cls.t = np.arange(n) / 8000.0
        w = 2 * np.pi * 50 * cls.t
        cls.u = [300 * np.cos(w - k * 2 * np.pi / 3) for k in range(3)]
        cls.i = [10 * np.cos(w - 0.5 - k * 2 * np.pi / 3) for k in range(3)]
        cls.theta = (2 * np.pi * 24 * cls.t) % (2 * np.pi)
        cls.cfg = imest.Config(**MOTOR_CFG)

    def raises(self, exc, words, **kw):
        args = dict(t=self.t, u=self.u, i=self.i, theta=self.theta)
        args.update(kw)
        args = {k: v for k, v in args.items() if v is not None}
        with self.assertRaises(exc) as cm:
            self.imest.run(self.cfg, **args)
        for word in words:
            self.assertIn(word, str(cm.exception))

    def test_lengths(self):
        self.raises(ValueError, ["differ in length", "i_b 7999", "theta 8000", "nothing is cut"],
                    i=[self.i[0], self.i[1][:-1], self.i[2]])
        self.raises(ValueError, ["differ in length", "t 8001"], t=self.np.arange(8001) / 8000.0)
        self.raises(ValueError, ["differ in length", "theta 4000"], theta=self.theta[:4000])
        self.raises(ValueError, ["differ in length", "vdc 10"], u=None, duty=[x * 0 + 0.5 for x in self.u],
                    vdc=self.np.full(10, 560.0))

    def test_shapes(self):
        self.raises(ValueError, ["three phases", "got 2"], u=self.u[:2])
        self.raises(ValueError, ["shape (n, 3)"], i=self.np.zeros((8000, 4)))
        self.raises(ValueError, ["one-dimensional"], theta=self.np.zeros((8000, 2)))
        # an (n, 3) array is the same as three arrays
        a = self.imest.run(self.cfg, t=self.t, u=self.np.column_stack(self.u), i=self.i, theta=self.theta)
        b = self.imest.run(self.cfg, t=self.t, u=self.u, i=self.i, theta=self.theta)
        self.assertEqual(a.tobytes(), b.tobytes())

    def test_voltage_and_time(self):
        self.raises(ValueError, ["u=(u_a, u_b, u_c) or as duty="], duty=self.u)
        self.raises(ValueError, ["needs vdc="], u=None, duty=[x * 0 + 0.5 for x in self.u])
        self.raises(ValueError, ["give the sample times t"], t=None)
        self.raises(ValueError, ["does not increase"], t=self.t[::-1].copy())
        self.raises(ValueError, ["counts samples"], t=self.np.arange(8000.0))
        self.raises(ValueError, ["duty cycle of 50", "percent"], u=None, duty=[x * 0 + 50 for x in self.u], vdc=560.0)
        cfg = self.imest.Config(inverter_dead_time_s=1e-6, **MOTOR_CFG)
        with self.assertRaises(ValueError) as cm:
            self.imest.run(cfg, t=self.t, u=self.u, i=self.i, theta=self.theta)
        self.assertIn("inverter.dead_time_s describes the duty-cycle input", str(cm.exception))

    def test_config(self):
        with self.assertRaises(TypeError) as cm:
            self.imest.Config(pole_pair=2)
        self.assertIn("did you mean pole_pairs", str(cm.exception))
        with self.assertRaises(ValueError):
            self.imest.Config(pole_pairs=2.5)
        with self.assertRaises(ValueError):
            self.imest.Config(pwm_timing="middle")
        self.assertEqual(self.imest.Config(voltage_kind="smooth").voltage_kind, 1)
        self.assertEqual(self.imest.Config().voltage_kind, 0)
        with self.assertRaises(ValueError):
            self.imest.Config(voltage_kind="sine")
        with self.assertRaises(ValueError) as cm:
            self.imest.Config(voltage_kind=2, **MOTOR_CFG).check()
        self.assertIn("voltage_kind", str(cm.exception))
        cfg = self.imest.Config(filter_hz=5000, **MOTOR_CFG)
        with self.assertRaises(ValueError) as cm:
            self.imest.run(cfg, t=self.t, u=self.u, i=self.i, theta=self.theta)
        self.assertIn("filter_hz", str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            self.imest.Config().check()     # the motor constants are not set
        self.assertIn("pole_pairs", str(cm.exception))


def main():
    global ARGS
    p = argparse.ArgumentParser()
    for opt in ("--replay", "--sim", "--dump", "--lib", "--work"):
        p.add_argument(opt, required=True)
    ARGS, rest = p.parse_known_args()
    os.environ["IMEST_LIBRARY"] = ARGS.lib
    os.makedirs(ARGS.work, exist_ok=True)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)


if __name__ == "__main__":
    main()
