#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The default configure on a machine with only the build tools: the source
# configured into a temporary folder with every test-only package made
# unfindable (GTest, Eigen3, nlohmann_json), as cmake -S . -B build would there.
#   1. no IMEST_BUILD_TESTS: succeeds, says "imest: tests off (missing: ...)" once, adds no test folder;
#   2. -DIMEST_BUILD_TESTS=ON: fails, naming the Debian packages to install;
#   3. imest added with add_subdirectory() by another project (packages findable): no tests, no message.
# usage: configure_default.sh SOURCE_DIR C_COMPILER CXX_COMPILER
set -eu
src=$1; cc=$2; cxx=$3
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
nopkg="-DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON"
compilers="-DCMAKE_C_COMPILER=$cc -DCMAKE_CXX_COMPILER=$cxx"
fail() { echo "configure_default: $*"; exit 1; }

# shellcheck disable=SC2086 # the option lists are words
cmake -S "$src" -B "$tmp/default" $compilers $nopkg >"$tmp/default.log" 2>&1 ||
  { cat "$tmp/default.log"; fail "1. the default configure failed without the test packages"; }
msg="-- imest: tests off (missing: GTest Eigen3 nlohmann_json); install them or -DIMEST_BUILD_TESTS=ON to insist"
[ "$(grep -c 'imest: tests' "$tmp/default.log")" = 1 ] && grep -qxF -- "$msg" "$tmp/default.log" ||
  { cat "$tmp/default.log"; fail "1. expected the one line '$msg'"; }
[ ! -e "$tmp/default/test" ] || fail "1. the test folder was configured without its packages"
echo "1. default without the test packages: configured, '$msg'"

# shellcheck disable=SC2086
if cmake -S "$src" -B "$tmp/on" $compilers $nopkg -DIMEST_BUILD_TESTS=ON >"$tmp/on.log" 2>&1; then
  cat "$tmp/on.log"; fail "2. -DIMEST_BUILD_TESTS=ON configured without the test packages"
fi
for deb in libgtest-dev libeigen3-dev nlohmann-json3-dev; do
  tr '\n' ' ' <"$tmp/on.log" | tr -s ' ' | grep -q -- "$deb" || { cat "$tmp/on.log"; fail "2. the error does not name $deb"; }
done
echo "2. -DIMEST_BUILD_TESTS=ON without the test packages: an error naming libgtest-dev libeigen3-dev nlohmann-json3-dev"

mkdir "$tmp/parent"
cat >"$tmp/parent/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.20)
project(parent C CXX)
add_subdirectory("$src" imest)
CMAKE
# shellcheck disable=SC2086
cmake -S "$tmp/parent" -B "$tmp/parent/b" $compilers >"$tmp/parent.log" 2>&1 ||
  { cat "$tmp/parent.log"; fail "3. a project adding imest with add_subdirectory() failed to configure"; }
[ -e "$tmp/parent/b/imest/src" ] || fail "3. imest was not configured in the parent project"
[ ! -e "$tmp/parent/b/imest/test" ] || fail "3. add_subdirectory(imest) configured imest's tests"
! grep -q 'imest: tests' "$tmp/parent.log" || { cat "$tmp/parent.log"; fail "3. unexpected message"; }
echo "3. add_subdirectory(imest) from another project: no tests"
