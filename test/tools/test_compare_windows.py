#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/studies/compare/compare-windows on two small tables: a relative difference, a one-sided
NaN and a verdict flip are each reported, identical tables pass.

usage: test_compare_windows.py TOOL
Exit status: 0 every check passed; 1 a check failed (each listed); 2 usage error.
"""
import os
import subprocess
import sys
import tempfile

A = "t_end_s,T_R_s,E_I,valid,tr_reason\n1,0.1,0.5,1,ok\n2,0.2,nan,0,zero_slip\n3,0.3,0.7,1,ok\n"
B = "t_end_s,T_R_s,E_I,valid,tr_reason\n1,0.1,0.5,1,ok\n2,0.2002,nan,0,zero_slip\n3,0.3,nan,0,tr_uncertain\n"


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    tool = sys.argv[1]
    fails = []
    with tempfile.TemporaryDirectory() as d:
        a, b = os.path.join(d, "a.csv"), os.path.join(d, "b.csv")
        with open(a, "w", encoding="utf-8") as f:
            f.write(A)
        with open(b, "w", encoding="utf-8") as f:
            f.write(B)
        p = subprocess.run([sys.executable, tool, a, a], capture_output=True, text=True)
        if p.returncode != 0 or "verdict_flips 0" not in p.stdout or "largest_rel" in p.stdout:
            fails.append("identical tables: exit %d\n%s" % (p.returncode, p.stdout))
        p = subprocess.run([sys.executable, tool, a, b], capture_output=True, text=True)
        out = p.stdout
        for want in ("largest_rel T_R_s 0.000999", "mismatch E_I 1", "verdict valid 1", "verdict tr_reason 1",
                     "row 3: ok -> tr_uncertain", "verdict_flips 2"):
            if want not in out:
                fails.append("a flip and a difference: %r not in the report\n%s" % (want, out))
        if p.returncode != 1:
            fails.append("a flip: exit %d, not 1" % p.returncode)
    for f in fails:
        print("FAIL " + f)
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
