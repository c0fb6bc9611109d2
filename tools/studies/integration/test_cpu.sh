#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The integration study's CPU table (run --parts cpu): every core at both sample rates, the
# DSP's row marked as not measured, and the figures the arithmetic of cpu.py gives for the
# committed counts (Cortex-M4F at 10 kHz: 652 instructions x 1.1..1.6 x 10 kHz / 168 MHz).
# Usage: test_cpu.sh OUT_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: test_cpu.sh OUT_DIR}
rm -rf "$out"
/usr/bin/python3 "$here/run" --parts cpu --out "$out" --quiet >/dev/null
md=$out/results.md
fail() { echo "integration_study.cpu: $*" >&2; exit 1; }
[ -s "$md" ] || fail "no results.md"
for core in "Cortex-M4F 168 MHz" "Cortex-M7 480 MHz" "200 MHz DSP"; do
  for fs in "10 kHz" "20 kHz"; do
    grep -q "^| $core.* | $fs |" "$md" || fail "no row for $core at $fs"
  done
done
grep -q "^| 200 MHz DSP.*(estimate, not measured) |" "$md" || fail "the DSP row does not say it is an estimate"
grep -q "NOT MEASURED" "$md" || fail "the CPI notes do not say the DSP is not measured"
grep -q "^| Cortex-M4F 168 MHz (STM32F4, ART accelerator) | 10 kHz | 652 / 713 | 4.3-6.2 % |" "$md" ||
  fail "Cortex-M4F 10 kHz ISR row is not 652 / 713 | 4.3-6.2 %"
grep -q "^| Cortex-M4F 168 MHz (STM32F4, ART accelerator) | 20 kHz | 652 / 713 | 8.5-12.4 % |" "$md" ||
  fail "the ISR share does not double at 20 kHz"
# a bad option: named on stderr, exit 2
set +e
/usr/bin/python3 "$here/run" --no-such-option >/dev/null 2>"$out/err.txt"
rc=$?
set -e
[ "$rc" = 2 ] || fail "unknown option: exit $rc, not 2"
grep -q "unknown option '--no-such-option'" "$out/err.txt" || fail "unknown option not named on stderr"
echo "integration_study.cpu: ok"
