#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Runs a ThreadSanitizer test program (test/concurrency): any report fails it
# (halt_on_error=1). The caller's TSAN_OPTIONS come after these defaults and
# override them, e.g. TSAN_OPTIONS=halt_on_error=0 to see every report.
#
# The TSan runtimes of gcc 12 and clang 14 stop at start with "FATAL:
# ThreadSanitizer: unexpected memory mapping" on kernels that randomise mmap
# with more bits than they know (vm.mmap_rnd_bits 30..32): the program then
# runs again with address-space randomisation off (setarch -R).
# Usage: run_tsan.sh program [arguments]
set -u
TSAN_OPTIONS="halt_on_error=1 history_size=7 second_deadlock_stack=1 ${TSAN_OPTIONS:-}"
export TSAN_OPTIONS
out=$(mktemp) || exit 1
trap 'rm -f "$out"' EXIT
"$@" >"$out" 2>&1
rc=$?
if [ "$rc" -ne 0 ] && grep -q "unexpected memory mapping" "$out"; then
  echo "run_tsan.sh: TSan cannot place its shadow memory with this kernel's ASLR; again with setarch -R" >&2
  setarch "$(uname -m)" -R "$@"
  exit $?
fi
cat "$out"
exit "$rc"
