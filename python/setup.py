# SPDX-License-Identifier: Apache-2.0
"""Builds the package imest: the Python files, and libimest.so built by CMake from this
repository (the target imest_shared: the core's sources with the core's own flags, and the
module's entry point imest/_shim.c), copied into the package. The version is the library's
(include/imest/imest_version.h). Needs cmake and a C compiler (Debian: cmake gcc).

Environment: IMEST_BUILD_DIR, where the build goes (default python/build; the CMake build in its
cmake/ folder is kept, so a second install compiles only what changed); IMEST_CMAKE_ARGS, extra
arguments for the configure (e.g. -DCMAKE_C_COMPILER=clang); IMEST_BUILD_JOBS, parallel jobs
(default: the CPU count)."""
import os
import re
import shlex
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BUILD = os.path.abspath(os.environ.get("IMEST_BUILD_DIR") or os.path.join(HERE, "build"))


def version():
    path = os.path.join(ROOT, "include", "imest", "imest_version.h")
    if not os.path.exists(path):
        raise SystemExit("imest: %s is missing: build the package from the repository's python/ folder "
                         "(pip install --no-build-isolation ./python), not from a copy of it" % path)
    with open(path, encoding="utf-8") as f:
        return re.search(r'#define IMEST_VERSION_STRING "([0-9.]+)"', f.read()).group(1)


class BuildWithCore(build_py):
    """build_py, then the shared library into the built package."""

    def run(self):
        super().run()
        build_dir = os.path.join(BUILD, "cmake")
        jobs = os.environ.get("IMEST_BUILD_JOBS") or str(os.cpu_count() or 1)
        configure = ["cmake", "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                     "-DIMEST_BUILD_HOST=OFF", "-DIMEST_BUILD_TESTS=OFF"]
        configure += shlex.split(os.environ.get("IMEST_CMAKE_ARGS", ""))
        try:
            subprocess.check_call(configure)
            subprocess.check_call(["cmake", "--build", build_dir, "--target", "imest_shared", "-j", jobs])
        except FileNotFoundError:
            raise SystemExit("imest: cmake is needed to build the library (Debian: apt-get install cmake gcc)")
        lib = os.path.join(build_dir, "python", "imest", "libimest.so")
        dest = os.path.join(self.build_lib, "imest")
        os.makedirs(dest, exist_ok=True)
        shutil.copy2(lib, os.path.join(dest, "libimest.so"))


class BinaryDistribution(Distribution):
    """The wheel holds a compiled library: a platform wheel, not a pure one."""

    def has_ext_modules(self):
        return True


os.makedirs(BUILD, exist_ok=True)
setup(version=version(), cmdclass={"build_py": BuildWithCore}, distclass=BinaryDistribution, zip_safe=False,
      options={"build": {"build_base": BUILD}, "egg_info": {"egg_base": BUILD}})
