# SPDX-License-Identifier: Apache-2.0
"""The shared library (libimest.so: the core and the entry point python/imest/_shim.c) through ctypes.

Only plain doubles, ints and strings cross: no C struct is mirrored here. The library is the one
installed next to this file (pip install, python/README.md), or the one IMEST_LIBRARY names (a
build tree's `cmake --build BUILD --target imest_shared` gives BUILD/python/imest/libimest.so).
"""
import ctypes
import os

ABI = 1  # imest_py_abi() of the library this module is written for (_shim.c IMEST_PY_ABI)

# the kinds of a config field and of a result column (_shim.c KIND_*)
KIND_FLOAT, KIND_INT, KIND_UINT, KIND_PWM_TIMING, KIND_REASON = range(5)


def _path():
    env = os.environ.get("IMEST_LIBRARY")
    if env:
        return env
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "libimest.so")


def _load():
    path = _path()
    if not os.path.exists(path):
        raise ImportError(
            "imest: the shared library %s is missing. Install the package from the repository "
            "(python/README.md: pip install --no-build-isolation ./python in a venv), or point "
            "IMEST_LIBRARY at a libimest.so built with 'cmake --build BUILD --target imest_shared'"
            % path)
    lib = ctypes.CDLL(path)
    if not hasattr(lib, "imest_py_abi"):
        raise ImportError("imest: %s has no imest_py_abi(): not the library the module loads "
                          "(the target imest_shared builds it)" % path)
    lib.imest_py_abi.restype = ctypes.c_int
    got = lib.imest_py_abi()
    if got != ABI:
        raise ImportError("imest: %s has interface %d, this module needs %d: rebuild it "
                          "(pip install again, or the imest_shared target)" % (path, got, ABI))
    dp = ctypes.POINTER(ctypes.c_double)
    sigs = {
        "imest_py_version": (ctypes.c_char_p, []),
        "imest_py_config_fields": (ctypes.c_int, []),
        "imest_py_config_name": (ctypes.c_char_p, [ctypes.c_int]),
        "imest_py_config_kind": (ctypes.c_int, [ctypes.c_int]),
        "imest_py_config_default": (None, [dp]),
        "imest_py_config_check": (ctypes.c_int, [dp, ctypes.POINTER(ctypes.c_char_p)]),
        "imest_py_pwm_timing": (ctypes.c_int, [ctypes.c_char_p]),
        "imest_py_columns": (ctypes.c_int, []),
        "imest_py_column_name": (ctypes.c_char_p, [ctypes.c_int]),
        "imest_py_column_kind": (ctypes.c_int, [ctypes.c_int]),
        "imest_py_run": (ctypes.c_long, [dp, ctypes.c_int, ctypes.c_long, dp, dp, dp, dp, ctypes.c_double,
                                         ctypes.c_double, dp, ctypes.c_long, ctypes.POINTER(ctypes.c_int)]),
        "imest_reason_name": (ctypes.c_char_p, [ctypes.c_int]),
        "imest_err_name": (ctypes.c_char_p, [ctypes.c_int]),
    }
    for name, (res, args) in sigs.items():
        f = getattr(lib, name)
        f.restype = res
        f.argtypes = args
    return lib, path


lib, path = _load()


def config_fields():
    """[(name, kind)] of every imest_config_t field, in the library's order."""
    return [(lib.imest_py_config_name(k).decode(), lib.imest_py_config_kind(k))
            for k in range(lib.imest_py_config_fields())]


def columns():
    """[(name, kind)] of the result columns, in the library's order."""
    return [(lib.imest_py_column_name(k).decode(), lib.imest_py_column_kind(k))
            for k in range(lib.imest_py_columns())]


def reason_name(code):
    return lib.imest_reason_name(int(code)).decode()


def err_name(code):
    return lib.imest_err_name(int(code)).decode()
