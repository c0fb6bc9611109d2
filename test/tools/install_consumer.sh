#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Installs the build into a temporary prefix and builds a program outside the
# project against it (test/tools/consumer: the core and the installed firmware
# CAN port), one way per run:
#   cmake       find_package(imest): the exported CMake package works
#   pkg-config  cc $(pkg-config --cflags --libs imest), PKG_CONFIG_PATH at the
#               prefix: lib/pkgconfig/imest.pc works
# usage: install_consumer.sh cmake|pkg-config BUILD_DIR CONSUMER_SRC C_COMPILER VERSION
set -eu
how=$1; build=$2; src=$3; cc=$4; version=$5
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
for f in bin/imest-replay bin/imest-sim bin/imest-monitor lib/libimest.a include/imest/imest.h \
         lib/cmake/imest/imestConfig.cmake lib/pkgconfig/imest.pc share/imest/imest.dbc \
         share/imest/port/callback/imest_can_callback.c share/imest/port/callback/imest_can_callback.h; do
  [ -e "$tmp/prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
case "$how" in
  cmake)
    cmake -S "$src" -B "$tmp/b" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_C_COMPILER="$cc" >/dev/null
    cmake --build "$tmp/b" >/dev/null
    "$tmp/b/app"
    ;;
  pkg-config)
    command -v pkg-config >/dev/null || { echo "pkg-config not installed (Debian: pkg-config)"; exit 1; }
    # only the prefix: a system-wide imest.pc must not stand in for this one
    PKG_CONFIG_PATH="$tmp/prefix/lib/pkgconfig"; PKG_CONFIG_LIBDIR="$tmp/prefix/lib/pkgconfig"
    export PKG_CONFIG_PATH PKG_CONFIG_LIBDIR
    v=$(pkg-config --modversion imest)
    [ "$v" = "$version" ] || { echo "imest.pc: version $v, the project's is $version"; exit 1; }
    port=$(pkg-config --variable=can_callback_dir imest)
    [ -f "$port/imest_can_callback.c" ] || { echo "imest.pc: can_callback_dir=$port has no imest_can_callback.c"; exit 1; }
    [ -f "$(pkg-config --variable=dbc imest)" ] || { echo "imest.pc: dbc=$(pkg-config --variable=dbc imest) missing"; exit 1; }
    echo "pkg-config --cflags --libs imest: $(pkg-config --cflags --libs imest)"
    # shellcheck disable=SC2046 # the flags are words
    "$cc" -std=c11 $(pkg-config --cflags imest) -I"$port" -o "$tmp/app" "$src/main.c" "$port/imest_can_callback.c" \
          $(pkg-config --libs imest)
    "$tmp/app"
    ;;
  *) echo "usage: $0 cmake|pkg-config BUILD_DIR CONSUMER_SRC C_COMPILER VERSION"; exit 2 ;;
esac
