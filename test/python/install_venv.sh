#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The install python/README.md gives, as written: a venv over Debian's packages
# (numpy from python3-numpy), then pip install --no-build-isolation ./python
# from the top of the repository. The package index is switched off
# (PIP_NO_INDEX), so the install must need no network; the build goes to the
# test's folder (IMEST_BUILD_DIR) instead of python/build. Then the installed
# module, with no IMEST_LIBRARY, loads its own libimest.so, has the library's
# version and runs a log.
# usage: install_venv.sh SOURCE_DIR WORK_DIR VERSION
set -eu
src=$1; work=$2; version=$3
fail() { echo "install_venv: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
unset IMEST_LIBRARY PYTHONPATH || true
/usr/bin/python3 -m venv --system-site-packages "$work/venv" >"$work/venv.log" 2>&1 ||
  { cat "$work/venv.log"; fail "python3 -m venv failed (Debian: python3-venv)"; }
# shellcheck disable=SC2164 # set -e
cd "$src"
PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1 IMEST_BUILD_DIR="$work/build" \
  "$work/venv/bin/pip" install --no-build-isolation ./python >"$work/pip.log" 2>&1 ||
  { cat "$work/pip.log"; fail "pip install --no-build-isolation ./python failed"; }
for d in "$src/python/build" "$src/python/imest.egg-info"; do
  if [ -e "$d" ] && [ -n "$(find "$d" -newer "$work/venv.log" -print -quit)" ]; then
    fail "the build wrote into $d despite IMEST_BUILD_DIR"
  fi
done
cd "$work"
"$work/venv/bin/python" - "$version" "$work/venv" <<'PY'
import os, sys
import numpy as np
import imest
version, venv = sys.argv[1], sys.argv[2]
assert imest.__version__ == version, (imest.__version__, version)
lib = os.path.realpath(imest._lib.path)
assert lib.startswith(os.path.realpath(venv) + os.sep), "loaded %s, not the venv's library" % lib
assert np.__file__.startswith("/usr/lib/python3/"), "numpy is not Debian's: %s" % np.__file__
t = np.arange(8000) / 4000.0
w = 2 * np.pi * 30 * t
u = [200 * np.cos(w - k * 2 * np.pi / 3) for k in range(3)]
i = [5 * np.cos(w - 0.6 - k * 2 * np.pi / 3) for k in range(3)]
out = imest.run(imest.Config(pole_pairs=2, ls_h=0.2908, sigma=0.096), t=t, u=u, i=i, theta=(2 * np.pi * 14 * t))
assert len(out) == 2 and list(out["seq"]) == [0, 1], out
print("installed imest %s from %s: %d windows" % (imest.__version__, lib, len(out)))
PY
