# SPDX-License-Identifier: Apache-2.0
"""imest for notebooks: a drive log through the firmware's own estimator code.

    import imest
    cfg = imest.Config(pole_pairs=2, ls_h=0.178039, sigma=0.0645168)
    w = imest.run(cfg, t=t, u=(ua, ub, uc), i=(ia, ib, ic), theta=theta)          # phase voltages
    w = imest.run(cfg, t=t, duty=(da, db, dc), vdc=vdc, i=(ia, ib, ic), theta=theta)
    df = imest.run_frame(log_df, cfg)            # a DataFrame with imest-replay's column names
    w["T_R_s"][w["tr_valid"] == 1]

`run` calls the library's float32 ISR per sample and its background task per window, the loop
imest-replay runs (the library is the core built as a shared library: python/README.md), and
returns one record per window with imest-replay's CSV columns, then a few more. The same log with
the same settings gives the same numbers as imest-replay: the sample rate, start time, ADC limits,
speed limit, at-rest start and inverter uncertainty follow replay's rules unless the Config sets
them (python/README.md lists the rules and which of replay's checks the module makes).
"""
import difflib
import math
import warnings

import numpy as np

from . import _lib
from ._lib import KIND_FLOAT, KIND_INT, KIND_PWM_TIMING, KIND_REASON, KIND_UINT

__all__ = ["Config", "run", "run_frame", "to_frame", "reason_name", "columns", "ImestWarning",
           "__version__", "version"]

#: the library's version (include/imest/imest_version.h)
version = _lib.lib.imest_py_version().decode()
__version__ = version

_FIELDS = _lib.config_fields()                  # [(C name, kind)]
_KIND = dict(_FIELDS)
_DEFAULTS_ARRAY = (_lib.ctypes.c_double * len(_FIELDS))()
_lib.lib.imest_py_config_default(_DEFAULTS_ARRAY)
_DEFAULTS = {name: (float(v) if kind == KIND_FLOAT else int(v))
             for (name, kind), v in zip(_FIELDS, _DEFAULTS_ARRAY)}
# Python spelling: a nested field's dot as an underscore (inverter.dead_time_s -> inverter_dead_time_s)
# a nested field's dot and an array element's brackets as underscores: inverter_dead_time_s,
# ls_curve_h_1 for ls_curve_h[1]
_PY_NAME = {name.replace(".", "_").replace("[", "_").replace("]", ""): name for name, _ in _FIELDS}

_COLUMNS = _lib.columns()                       # [(name, kind)]
_REASON_NAMES = {k: _lib.reason_name(k) for k in range(64)}
_REASON_WIDTH = max(len(s) for s in _REASON_NAMES.values())

# imest-replay's rules (tools/replay/replay.c configure(), replay_options.c, replay_scan.c): the
# values it takes for what its options do not set. Kept equal to replay's by the test
# test/python/test_imest.py, which compares the two on the same logs.
_INVERTER_MODEL = ("inverter.dead_time_s", "inverter.v_switch_v", "inverter.r_switch_ohm",
                   "inverter.v_diode_v", "inverter.r_diode_ohm", "inverter.i_band_a",
                   "inverter.edge_band_a")
_INVERTER_UNCERTAINTY_GIVEN = 0.2   # a model given without its uncertainty: a data sheet's
_ENCODER_COUNT_STILL_RAD = 2.0 * math.pi / 4096.0 * 1.0001  # one count of a 4096-count encoder
_FS_IMPLAUSIBLE_HZ = 100.0
_DUTY_SLACK = 1e-6


class ImestWarning(UserWarning):
    """A note about the data, as imest-replay prints on stderr (a clipped channel, an angle that
    wraps at 360, a negative mean power)."""


def reason_name(code):
    """The short name of an imest_reason_t value ("ok", "warmup", "zero_slip", ...)."""
    return _REASON_NAMES.get(int(code)) or _lib.reason_name(code)


def columns():
    """The names of the result columns: imest-replay's CSV columns in its order, then more of
    imest_result_t (samples, overruns, E, E_I_noise, noise_i_a, noise_u_v, pe_k1, pe_k2,
    ls_noload_h, ls_window_h)."""
    return [name for name, _ in _COLUMNS]


def _c_name(name):
    if name in _KIND:
        return name
    if name in _PY_NAME:
        return _PY_NAME[name]
    close = difflib.get_close_matches(name, list(_PY_NAME), n=3)
    raise AttributeError("imest.Config has no field %r%s (fields: include/imest/imest.h imest_config_t)"
                         % (name, "; did you mean " + " or ".join(close) + "?" if close else ""))


class Config:
    """An estimator config: every imest_config_t field, with imest_config_default()'s values
    (read from the library, so they cannot drift). Set fields as keywords or attributes; a nested
    field takes an underscore for its dot (inverter_dead_time_s) or its C name as a key
    (cfg["inverter.dead_time_s"]); an array's element likewise (ls_curve_h_1, cfg["ls_curve_h[1]"]). pwm_timing takes "next", "centred" or "last"; voltage_kind
    "staircase" or "smooth" (or IMEST_VOLTAGE_STAIRCASE's 0, IMEST_VOLTAGE_SMOOTH's 1).

    Fields you set are "given": run() keeps them as they are. For the others it applies
    imest-replay's rules (the sample rate, the ADC limits, the speed limit, the at-rest start, the
    inverter uncertainty), so that the same log gives the same windows as imest-replay with the
    same options.
    """

    def __init__(self, **fields):
        object.__setattr__(self, "_values", dict(_DEFAULTS))
        object.__setattr__(self, "_given", set())
        for k, v in fields.items():
            self[k] = v

    def __setitem__(self, name, value):
        try:
            c = _c_name(name)
        except AttributeError as e:
            raise TypeError(str(e)) from None
        self._values[c] = _coerce(c, value)
        self._given.add(c)

    def __getitem__(self, name):
        try:
            return self._values[_c_name(name)]
        except AttributeError as e:
            raise KeyError(str(e)) from None

    def __setattr__(self, name, value):
        self[name] = value

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return self._values[_c_name(name)]

    def __dir__(self):
        return sorted(set(object.__dir__(self)) | set(_PY_NAME))

    def __eq__(self, other):
        return isinstance(other, Config) and self._values == other._values and self._given == other._given

    def __repr__(self):
        given = ", ".join("%s=%r" % (k.replace(".", "_"), self._values[k]) for k, _ in _FIELDS if k in self._given)
        return "imest.Config(%s)" % given

    def given(self):
        """The C names of the fields set explicitly."""
        return set(self._given)

    def to_dict(self):
        """{C name: value} of every field."""
        return dict(self._values)

    @staticmethod
    def defaults():
        """{C name: value} of imest_config_default(), as the library gives it."""
        return dict(_DEFAULTS)

    def copy(self):
        c = Config()
        c._values.update(self._values)
        c._given.update(self._given)
        return c

    def check(self):
        """imest_config_check() on this config as it stands; ValueError naming the field."""
        _check(self._values)


# imest_voltage_kind_t by imest-replay's --voltage-kind words
_VOLTAGE_KINDS = {"staircase": 0, "smooth": 1}


def _coerce(c, value):
    kind = _KIND[c]
    if kind == KIND_PWM_TIMING and isinstance(value, str):
        code = _lib.lib.imest_py_pwm_timing(value.encode())
        if code < 0:
            raise ValueError("imest.Config: pwm_timing takes 'next', 'centred' or 'last', not %r" % value)
        return code
    if c == "voltage_kind" and isinstance(value, str):
        if value not in _VOLTAGE_KINDS:
            raise ValueError("imest.Config: voltage_kind takes 'staircase' or 'smooth', not %r" % value)
        return _VOLTAGE_KINDS[value]
    if isinstance(value, (bool, np.bool_)) and kind != KIND_INT:
        raise TypeError("imest.Config: %s takes a number, not %r" % (c, value))
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TypeError("imest.Config: %s takes a number, not %r" % (c, value)) from None
    if kind == KIND_FLOAT:
        return x
    if not math.isfinite(x) or x != math.floor(x) or (kind == KIND_UINT and x < 0):
        raise ValueError("imest.Config: %s takes %s integer, not %r"
                         % (c, "a non-negative" if kind == KIND_UINT else "an", value))
    return int(x)


def _flat(values):
    arr = (_lib.ctypes.c_double * len(_FIELDS))()
    for k, (name, _) in enumerate(_FIELDS):
        arr[k] = float(values[name])
    return arr


def _check(values, fs=None):
    field = _lib.ctypes.c_char_p()
    rc = _lib.lib.imest_py_config_check(_flat(values), _lib.ctypes.byref(field))
    if rc == 0:
        return
    name = field.value.decode() if field.value else None
    if name in values:
        what = "%s = %r is out of range" % (name, values[name])
    else:
        what = "the config is refused (%s)" % (name or _lib.err_name(rc))
    at = " at fs_hz = %.6g" % fs if fs is not None else ""
    raise ValueError("imest: %s%s (imest_config_check; include/imest/imest.h documents each field's "
                     "range)" % (what, at))


# --------------------------------------------------------------------------------------------
# inputs


def _vector(name, x, n=None):
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError("imest.run: %s must be one-dimensional (one value per sample), it has shape %s"
                         % (name, a.shape))
    return a


def _three(name, x):
    """(a, b, c) of a three-phase input: a sequence of three 1-D arrays or an (n, 3) array."""
    if isinstance(x, np.ndarray) and x.ndim == 2:
        if x.shape[1] != 3:
            raise ValueError("imest.run: %s as an array must have shape (n, 3), it has %s" % (name, x.shape))
        return [_vector("%s[:, %d]" % (name, k), x[:, k]) for k in range(3)]
    if hasattr(x, "columns") and len(x.columns) == 3:       # a DataFrame of the three phases
        return [_vector("%s[%r]" % (name, c), x[c]) for c in x.columns]
    try:
        parts = list(x)
    except TypeError:
        raise TypeError("imest.run: %s takes three arrays (a, b, c) or an (n, 3) array" % name) from None
    if len(parts) != 3:
        raise ValueError("imest.run: %s takes the three phases (a, b, c), got %d arrays" % (name, len(parts)))
    return [_vector("%s_%s" % (name, "abc"[k]), p) for k, p in enumerate(parts)]


def _same_length(named):
    lengths = {name: len(a) for name, a in named}
    if len(set(lengths.values())) > 1:
        raise ValueError("imest.run: the inputs differ in length (%s): every input needs one value per "
                         "sample; nothing is cut to fit" % ", ".join("%s %d" % kv for kv in lengths.items()))
    return next(iter(lengths.values()))


def _wrap_pi(x):
    return x - 2.0 * math.pi * np.floor((x + math.pi) / (2.0 * math.pi))


def _adc_limit(channels, sym, unit, field):
    """imest-replay's auto limit: a channel whose extreme value sits on plateaus of >= 5 equal
    samples is clipped there (replay_scan.c clip_feed); the last such channel's extreme is the
    limit, 0 (off) if none."""
    limit = 0.0
    for k, x in enumerate(channels):
        a = np.abs(x)
        if np.all(np.isnan(a)):
            continue
        top = np.nanmax(a)
        if not top > 0:
            continue
        # runs of identical consecutive samples at |x| == top; a run of length L >= 5 counts L
        at = a == top
        change = np.ones(len(x), dtype=bool)
        change[1:] = x[1:] != x[:-1]
        start = np.flatnonzero(change)
        length = np.diff(np.append(start, len(x)))
        plateau = int(np.sum(length[(length >= 5) & at[start]]))
        if plateau >= 5:
            limit = float(top)
            warnings.warn("%s_%s looks clipped at %.6g %s (%d samples on plateaus); windows with such "
                          "samples are marked adc_saturation (Config(%s=...) overrides)"
                          % (sym, "abc"[k], top, unit, plateau, field), ImestWarning, stacklevel=4)
    return limit


def _time_base(t, fs, n):
    """(fs, t0_s) as imest-replay's scan finds them (replay_scan.c time_base_from_t and
    time_base_given)."""
    if t is not None and not np.all(np.isfinite(t)):
        k = int(np.argmax(~np.isfinite(t)))
        raise ValueError("imest.run: t[%d] = %r: t must be finite" % (k, t[k]))
    if fs is not None:
        fs = float(fs)
        if not (fs > 0.0) or fs > 1e6:
            raise ValueError("imest.run: fs must be a sample rate above 0 and at most 1e6 Hz, not %r" % fs)
        if t is None:
            return fs, 0.0
        dt = np.diff(t)
        if np.any(dt < 0):
            warnings.warn("t decreases (at sample %d); with fs it is not used, t_end_s counts from the "
                          "first sample" % (int(np.argmax(dt < 0)) + 1), ImestWarning, stacklevel=3)
            return fs, 0.0
        step = (t[-1] - t[0]) / float(n - 1)
        unit = 1.0 / (fs * step) if step > 0 else 0.0
        for u in (1.0, 1e-3, 1e-6):
            if abs(unit / u - 1.0) < 0.05:
                if u == 1.0 and abs(unit - 1.0) > 0.01:
                    warnings.warn("t says %.6g Hz, fs says %.6g Hz: using fs" % (1.0 / step, fs), ImestWarning,
                                  stacklevel=3)
                unit = u
                break
        return fs, float(t[0]) * unit
    if t is None:
        raise ValueError("imest.run: give the sample times t (in s) or the sample rate fs")
    dt = np.diff(t)
    if np.any(dt < 0):
        k = int(np.argmax(dt < 0)) + 1
        raise ValueError("imest.run: t[%d] = %.9g does not increase (previous %.9g): samples out of order, "
                         "or a timer that wrapped (then give fs)" % (k, t[k], t[k - 1]))
    step = (t[-1] - t[0]) / float(n - 1)
    if np.any(dt == 0):
        k = int(np.argmax(dt == 0)) + 1
        raise ValueError("imest.run: t[%d] = %.9g repeats the previous t: a duplicated sample, or t too "
                         "coarse for its mean step of %.6g s; give fs if the drive sampled at a fixed rate"
                         % (k, t[k], step))
    if np.all(dt == 1.0):
        raise ValueError("imest.run: t counts samples (every step is exactly 1), it is not a time in "
                         "seconds: give the drive's sample rate fs, or t in seconds")
    if 1.0 / step < _FS_IMPLAUSIBLE_HZ or 1.0 / step > 1e6:
        raise ValueError("imest.run: t steps by %.6g on average, %.6g Hz if t is in seconds: not a motor "
                         "log's rate. Give t in seconds, or the sample rate fs" % (step, 1.0 / step))
    hi, lo = dt.max(), dt.min()
    if hi > 1.05 * step or lo < 0.95 * step:
        gap = hi - 1.05 * step > 0.95 * step - lo
        k = int(np.argmax(dt)) if gap else int(np.argmin(dt))
        raise ValueError("imest.run: irregular sampling: a step of %.6g s after t[%d] where the mean step is "
                         "%.6g s (%.6g Hz)%s. The estimator needs a fixed sample rate; if the drive had one "
                         "and only t is inaccurate (rounded), give fs"
                         % (dt[k], k, step, 1.0 / step,
                            ": samples are missing there" if gap and dt[k] > 1.5 * step else ""))
    return 1.0 / step, float(t[0])


def _check_duty(d, vdc):
    lo = min(float(np.nanmin(x)) for x in d)
    hi = max(float(np.nanmax(x)) for x in d)
    if lo < -_DUTY_SLACK:
        raise ValueError("imest.run: a duty cycle of %.6g: duties must be the upper switch's on-time share in "
                         "[0, 1].%s" % (lo, " A signed modulation index m in [-1, 1] converts as d = (m + 1) / 2."
                                        if lo >= -1.0 - _DUTY_SLACK and hi <= 1.0 + _DUTY_SLACK
                                        else " Convert the log's duty scale to [0, 1]."))
    if hi > 1.0 + _DUTY_SLACK:
        raise ValueError("imest.run: a duty cycle of %.6g: duties must be the upper switch's on-time share in "
                         "[0, 1].%s" % (hi, " In percent? Divide by 100." if hi <= 100.0 + _DUTY_SLACK
                                        else " Timer compare counts? Divide by the timer's period."))
    if np.nanmin(vdc) < 0.0:
        raise ValueError("imest.run: v_dc = %.6g V: the DC-bus voltage must be positive, in V" % np.nanmin(vdc))


def _check_conventions(u, i, theta):
    """replay_scan.c check_conventions: theta against the current field is an error, a negative
    mean power and an angle wrapping beyond 2 pi are notes."""
    ia = (2.0 * i[0] - i[1] - i[2]) / 3.0
    ib = (i[1] - i[2]) / math.sqrt(3.0)
    p = np.nansum(u[0] * i[0] + u[1] * i[1] + u[2] * i[2])
    s = np.nansum(np.sqrt((u[0] ** 2 + u[1] ** 2 + u[2] ** 2) * (i[0] ** 2 + i[1] ** 2 + i[2] ** 2)))
    if s > 0 and p < -0.2 * s:
        warnings.warn("the mean power u.i is negative (%.3g of the apparent power): unless the motor was "
                      "braking, the current sign is inverted (currents must be positive into the motor) or a "
                      "voltage and a current column are of different phases" % (p / s), ImestWarning,
                      stacklevel=3)
    field = np.nansum(np.arctan2(ia[:-1] * ib[1:] - ib[:-1] * ia[1:], ia[:-1] * ia[1:] + ib[:-1] * ib[1:]))
    dth = np.diff(theta)
    mech = np.nansum(_wrap_pi(dth))
    if abs(field) > 4.0 * math.pi and abs(mech) > math.pi and (field > 0) != (mech > 0):
        raise ValueError("imest.run: theta turns %s (%.3g turns) while the a-b-c current field turns %s (%.3g "
                         "turns): theta must increase with the a-b-c field, else T_R comes out far too small "
                         "and can look valid. Negate theta, or swap two phases of u and i alike."
                         % ("forward" if mech > 0 else "backward", abs(mech) / (2 * math.pi),
                            "forward" if field > 0 else "backward", abs(field) / (2 * math.pi)))
    if np.any(np.abs(dth) > math.pi) and np.nanmax(theta) - np.nanmin(theta) > 2.0 * math.pi * 1.05:
        warnings.warn("theta wraps around at about %.6g; an angle in rad wraps at 2 pi = 6.283. theta must be "
                      "the mechanical angle in rad, not degrees (360) or encoder counts"
                      % (np.nanmax(theta) - np.nanmin(theta)), ImestWarning, stacklevel=3)


def _replay_config(cfg, fs, duty, u, i, theta):
    """The values imest-replay would run with: cfg's given fields, replay's rules for the rest."""
    values = cfg.to_dict()
    given = cfg.given()
    if not duty:
        bad = [f for f in ("pwm_timing",) + _INVERTER_MODEL + ("inverter.uncertainty",) if f in given]
        if bad:
            raise ValueError("imest.run: %s describes the duty-cycle input: pass duty= and vdc= (measured "
                             "phase voltages already contain the inverter's error)" % bad[0])
    elif "u_limit_v" in given:
        raise ValueError("imest.run: u_limit_v applies to measured phase voltages; with duty= the voltage "
                         "comes from the duty cycles and has no ADC to clip")
    elif values["voltage_kind"] == _VOLTAGE_KINDS["smooth"]:
        raise ValueError("imest.run: voltage_kind smooth applies to measured phase voltages; the voltage "
                         "formed from the duty cycles is a PWM staircase by construction")
    values["fs_hz"] = fs
    if "speed_limit_rad_s" not in given:
        values["speed_limit_rad_s"] = float(min(np.float32(values["speed_limit_rad_s"]), np.float32(2.0 * fs)))
    if "i_limit_a" not in given:
        values["i_limit_a"] = _adc_limit(i, "i", "A", "i_limit_a")
    if "u_limit_v" not in given:
        values["u_limit_v"] = 0.0 if duty else _adc_limit(u, "u", "V", "u_limit_v")
    if "start_at_rest" not in given:
        # fmax() in replay: a NaN loses against a number
        first = np.abs([x[0] for x in i])
        every = np.abs(np.concatenate(i))
        i_first = float(np.nanmax(first)) if not np.all(np.isnan(first)) else math.nan
        i_max = float(np.nanmax(every)) if not np.all(np.isnan(every)) else 0.0
        step1 = abs(float(_wrap_pi(theta[1] - theta[0])))
        still = step1 * fs < 2.0 or step1 <= _ENCODER_COUNT_STILL_RAD
        values["start_at_rest"] = int(i_first <= 0.01 * i_max and still)
    if duty and "inverter.uncertainty" not in given and any(f in given for f in _INVERTER_MODEL):
        values["inverter.uncertainty"] = _INVERTER_UNCERTAINTY_GIVEN
    return values


def _ptr(a):
    return a.ctypes.data_as(_lib.ctypes.POINTER(_lib.ctypes.c_double))


def _records(rows):
    dtype = []
    for name, kind in _COLUMNS:
        if kind == KIND_FLOAT:
            dtype.append((name, np.float64))
        elif kind == KIND_REASON:
            dtype.append((name, "U%d" % _REASON_WIDTH))
        else:
            dtype.append((name, np.int64))
    out = np.zeros(len(rows), dtype=dtype)
    for k, (name, kind) in enumerate(_COLUMNS):
        col = rows[:, k]
        if kind == KIND_REASON:
            out[name] = [reason_name(int(c)) for c in col]
        elif kind == KIND_FLOAT:
            out[name] = col
        else:
            out[name] = col.astype(np.int64)
    return out


def run(cfg, t=None, fs=None, u=None, duty=None, vdc=None, i=None, theta=None, check=True):
    """Runs a log through the estimator; returns the windows as a numpy structured array.

    cfg     imest.Config (pole_pairs, ls_h and sigma set)
    t       sample times [s], increasing at a fixed rate (rounding within 5 % of the mean step);
            or any increasing count if fs is given (its unit, s, ms or us, then follows from fs)
    fs      sample rate [Hz]; default: from t (as imest-replay without --fs)
    u       phase-to-neutral voltages [V]: (u_a, u_b, u_c) or an (n, 3) array
    duty    instead of u: the upper switches' duties in [0, 1], (d_a, d_b, d_c) or (n, 3), row k's
            applied as cfg.pwm_timing says; with vdc, the DC bus [V] (an array, or one number)
    i       phase currents [A], positive into the motor: (i_a, i_b, i_c) or (n, 3)
    theta   mechanical angle [rad], wrapped or not, increasing with the a-b-c field
    check   False skips replay's checks of the conventions and the duty range (not the lengths)

    Every input needs one value per sample: different lengths are a ValueError, nothing is cut.
    One record per window, the columns of imest-replay's CSV in its order (t_end_s counts from
    t[0]; status, tr_reason, rs_reason are the reason names), then samples, overruns, E,
    E_I_noise, noise_i_a, noise_u_v, pe_k1, pe_k2, ls_noload_h, ls_window_h. A last partial window of at least
    half the length (or a log shorter than one window) is estimated too, as replay does.
    """
    if not isinstance(cfg, Config):
        raise TypeError("imest.run: the first argument is an imest.Config, not %s" % type(cfg).__name__)
    if (u is None) == (duty is None):
        raise ValueError("imest.run: give the voltage as u=(u_a, u_b, u_c) or as duty=(d_a, d_b, d_c) with vdc=")
    if i is None or theta is None:
        raise ValueError("imest.run: i=(i_a, i_b, i_c) and theta= are needed")
    is_duty = duty is not None
    v = _three("duty" if is_duty else "u", duty if is_duty else u)
    cur = _three("i", i)
    th = _vector("theta", theta)
    named = [("%s_%s" % ("d" if is_duty else "u", "abc"[k]), v[k]) for k in range(3)]
    named += [("i_%s" % "abc"[k], cur[k]) for k in range(3)] + [("theta", th)]
    if t is not None:
        t = _vector("t", t)
        named.append(("t", t))
    if is_duty:
        if vdc is None:
            raise ValueError("imest.run: duty= needs vdc= (the DC bus [V], an array or one number)")
        vb = np.asarray(vdc, dtype=np.float64)
        if vb.ndim == 0:
            vb = np.full(len(th), float(vb))
        vb = _vector("vdc", vb)
        named.append(("vdc", vb))
    elif vdc is not None:
        raise ValueError("imest.run: vdc= goes with duty=; measured phase voltages u= need no bus voltage")
    n = _same_length(named)
    if n < 2:
        raise ValueError("imest.run: %d samples: at least two are needed" % n)
    if fs is None and t is None and "fs_hz" in cfg.given():
        fs = cfg.fs_hz
    rate, t0_s = _time_base(t, fs, n)
    if is_duty:
        # the voltage the drive commands, without the zero sequence (for the checks only; the
        # library forms its own)
        mean = (v[0] + v[1] + v[2]) / 3.0
        u_chk = [vb * (x - mean) for x in v]
        if check:
            _check_duty(v, vb)
    else:
        u_chk = v
    if check:
        _check_conventions(u_chk, cur, th)
    values = _replay_config(cfg, rate, is_duty, v, cur, th)
    _check(values, rate)

    v3 = np.ascontiguousarray(np.column_stack(v))
    i3 = np.ascontiguousarray(np.column_stack(cur))
    thc = np.ascontiguousarray(th)
    vbc = np.ascontiguousarray(vb) if is_duty else None
    flat = _flat(values)
    ncol = len(_COLUMNS)
    win_n = max(1, int(values["window_s"] * rate))
    room = n // win_n + 2
    while True:
        out = np.zeros((room, ncol), dtype=np.float64)
        err = _lib.ctypes.c_int(0)
        got = _lib.lib.imest_py_run(flat, int(is_duty), n, _ptr(v3), _ptr(vbc) if is_duty else None, _ptr(i3),
                                    _ptr(thc), rate, t0_s, _ptr(out), room, _lib.ctypes.byref(err))
        if got < 0:
            raise ValueError("imest.run: the library refused the config: %s" % _lib.err_name(got))
        if got <= room:
            break
        room = got
    if err.value:
        raise RuntimeError("imest.run: imest_background failed after %d windows: %s"
                           % (got, _lib.err_name(err.value)))
    return _records(out[:got])


def to_frame(windows):
    """The windows run() returns as a pandas DataFrame (pandas must be installed)."""
    import pandas as pd  # only here: the module itself needs numpy only
    return pd.DataFrame.from_records(windows)


_PHASE_COLS = ("u_a", "u_b", "u_c")
_DUTY_COLS = ("d_a", "d_b", "d_c", "v_dc")


def run_frame(df, cfg, voltage=None, fs=None, check=True):
    """run() on a DataFrame with imest-replay's column names (other columns ignored):
    t,u_a,u_b,u_c,i_a,i_b,i_c,theta, or with voltage="duty" t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta.
    voltage: "phase" or "duty"; default phase if the u_ columns are there, else duty. t may be left
    out if fs is given. Returns a DataFrame of the windows."""
    cols = set(df.columns)
    if voltage is None:
        voltage = "phase" if set(_PHASE_COLS) <= cols else "duty" if set(_DUTY_COLS) <= cols else "phase"
    if voltage not in ("phase", "duty"):
        raise ValueError("imest.run_frame: voltage is 'phase' or 'duty', not %r" % voltage)
    need = (_PHASE_COLS if voltage == "phase" else _DUTY_COLS) + ("i_a", "i_b", "i_c", "theta")
    if fs is None:
        need = ("t",) + need
    missing = [c for c in need if c not in cols]
    if missing:
        raise ValueError("imest.run_frame: the frame has no column %s (voltage=%r needs %s)"
                         % (", ".join(missing), voltage, ",".join(need)))
    kw = dict(t=df["t"].to_numpy() if "t" in cols else None, fs=fs, i=[df[c].to_numpy() for c in ("i_a", "i_b", "i_c")],
              theta=df["theta"].to_numpy(), check=check)
    if voltage == "phase":
        kw["u"] = [df[c].to_numpy() for c in _PHASE_COLS]
    else:
        kw["duty"] = [df[c].to_numpy() for c in _DUTY_COLS[:3]]
        kw["vdc"] = df["v_dc"].to_numpy()
    return to_frame(run(cfg, **kw))
