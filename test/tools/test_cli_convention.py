#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""The command-line convention of every program users run (README, "Tools"):

  -h, --help   the help on stdout ("usage: NAME ...", with an "Exit status:" section), exit 0
  --version    "NAME VERSION" as the first line on stdout, exit 0
  --bogus      "NAME: unknown option '--bogus'" and "Try 'NAME --help'." on stderr, exit 2

usage: test_cli_convention.py VERSION NAME=COMMAND [NAME=COMMAND ...]
  VERSION   the version CMake read from include/imest/imest_version.h
  COMMAND   the program (a path; several words for a script run by an interpreter)
Exit status: 0 every program keeps the convention; 1 one does not (each failure listed);
2 usage error.
"""
import shlex
import subprocess
import sys


def run(cmd, arg):
    p = subprocess.run(cmd + [arg], stdin=subprocess.DEVNULL, capture_output=True, text=True,
                       timeout=60)
    return p.returncode, p.stdout, p.stderr


def check_tool(name, cmd, version):
    fails = []

    def expect(cond, what, rc, out, err):
        if not cond:
            fails.append("%s %s: exit %d\n  stdout: %r\n  stderr: %r" % (name, what, rc, out[:300], err[:300]))

    for opt in ("-h", "--help"):
        rc, out, err = run(cmd, opt)
        expect(rc == 0 and out.startswith("usage: " + name) and err == "",
               opt + ": help on stdout, exit 0", rc, out, err)
        expect("Exit status:" in out, opt + ": an 'Exit status:' section", rc, out, err)
    rc, out, err = run(cmd, "--version")
    first = out.splitlines()[0] if out else ""
    expect(rc == 0 and first == "%s %s" % (name, version) and err == "",
           "--version: '%s %s' on stdout, exit 0" % (name, version), rc, out, err)
    rc, out, err = run(cmd, "--bogus")
    expect(rc == 2 and out == "" and ("%s: unknown option '--bogus'" % name) in err
           and ("Try '%s --help'." % name) in err,
           "--bogus: named on stderr with a Try line, exit 2", rc, out, err)
    return fails


def main():
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        print(__doc__, file=sys.stderr)
        return 2
    version = sys.argv[1]
    fails = []
    for spec in sys.argv[2:]:
        name, command = spec.split("=", 1)
        fails += check_tool(name, shlex.split(command), version)
    for f in fails:
        print("FAIL " + f)
    print("%d programs, %d failures" % (len(sys.argv) - 2, len(fails)))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
