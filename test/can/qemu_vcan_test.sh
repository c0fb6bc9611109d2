#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Real SocketCAN end-to-end test (CTest label "socketcan").
#
# This machine's kernel has no CAN support, so the test boots a small Linux
# guest under qemu-system-x86_64 (software emulation, TCG): Debian's stock
# kernel (package linux-image-<version>-amd64, fetched with apt-get download
# into CACHE_DIR on first use and unpacked with dpkg-deb -x, never installed)
# with an initramfs of busybox-static, the modules can-dev, vcan, can,
# can-raw, and two statically linked programs of this project:
#   imest-can-selftest  an imest instance with the SocketCAN port attached,
#                       publishing N synthetic windows via imest_can_publish
#   imest-monitor       reading vcan0 live (--can-iface vcan0 --csv)
# The guest prints the monitor's CSV and messages on its serial console; the
# host compares the CSV with the same windows decoded from a candump log
# written by the same selftest on the host (every column but t_s), and checks
# the port's error messages with a real CAN stack (no such interface, not a
# CAN interface, interface down).
#
# usage: qemu_vcan_test.sh CACHE_DIR MONITOR_STATIC SELFTEST_STATIC MONITOR SELFTEST [N]
# Needs: qemu-system-x86, busybox-static, cpio, gzip, and apt-get access to
# the Debian archive on first run. Exit 77 (CTest skip) only if qemu cannot
# run at all.
set -eu

CACHE=$1
MON_STATIC=$2
PUB_STATIC=$3
MON=$4
PUB=$5
N=${6:-25}
T0=$(date +%s)

say() { echo "qemu_vcan_test: $*"; }
die() { echo "qemu_vcan_test: FAIL: $*" >&2; exit 1; }

QEMU=${IMEST_QEMU:-$(command -v qemu-system-x86_64 || true)}
if [ -z "$QEMU" ] || [ ! -x "$QEMU" ]; then
  echo "qemu_vcan_test: SKIP: qemu-system-x86_64 not found${QEMU:+ at $QEMU} (apt-get install qemu-system-x86)"
  exit 77
fi
if ! "$QEMU" -version >/dev/null 2>&1; then
  echo "qemu_vcan_test: SKIP: qemu-system-x86_64 does not run: $("$QEMU" -version 2>&1 | head -1)"
  exit 77
fi
BUSYBOX=$(command -v busybox || true)
[ -n "$BUSYBOX" ] || die "busybox not found (apt-get install busybox-static)"
file -L "$BUSYBOX" 2>/dev/null | grep -q "statically linked" ||
  ldd "$BUSYBOX" 2>&1 | grep -q "not a dynamic" ||
  die "$BUSYBOX is not statically linked (apt-get install busybox-static)"
command -v cpio >/dev/null || die "cpio not found (apt-get install cpio)"
for f in "$MON_STATIC" "$PUB_STATIC" "$MON" "$PUB"; do [ -x "$f" ] || die "missing program $f"; done

# --- kernel and modules (cached) -------------------------------------------
mkdir -p "$CACHE"
CACHE=$(cd "$CACHE" && pwd)
KDIR=$CACHE/kernel
if [ ! -f "$KDIR/.complete" ]; then
  PKG=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
  [ -n "$PKG" ] || die "cannot resolve linux-image-amd64 to a kernel package (apt-cache depends)"
  DEB=$(ls "$CACHE"/"$PKG"_*.deb 2>/dev/null | head -1 || true)
  if [ -z "$DEB" ]; then
    say "downloading $PKG (apt-get download, about 70 MB, cached in $CACHE)"
    (cd "$CACHE" && apt-get download "$PKG" >/dev/null 2>"$CACHE/apt.err") ||
      die "apt-get download $PKG failed: $(tail -3 "$CACHE/apt.err")"
    DEB=$(ls "$CACHE"/"$PKG"_*.deb | head -1)
  fi
  rm -rf "$KDIR"
  mkdir -p "$KDIR/x"
  dpkg-deb -x "$DEB" "$KDIR/x"
  cp "$KDIR"/x/boot/vmlinuz-* "$KDIR/vmlinuz"
  for m in can-dev vcan can can-raw; do
    p=$(find "$KDIR/x/lib/modules" -name "$m.ko*" | head -1)
    [ -n "$p" ] || die "module $m not in $DEB"
    case $p in
      *.xz) xz -dc "$p" >"$KDIR/$m.ko" ;;
      *.zst) zstd -dqc "$p" >"$KDIR/$m.ko" ;;
      *) cp "$p" "$KDIR/$m.ko" ;;
    esac
  done
  basename "$DEB" >"$KDIR/package"
  rm -rf "$KDIR/x"
  touch "$KDIR/.complete"
fi
say "kernel: $(cat "$KDIR/package")"

# --- initramfs -----------------------------------------------------------------
WORK=$CACHE/run.$$
rm -rf "$WORK"
mkdir -p "$WORK/root/bin" "$WORK/root/lib" "$WORK/root/proc" "$WORK/root/sys" "$WORK/root/dev" \
  "$WORK/root/tmp"
trap 'rm -rf "$WORK"' EXIT
cp "$BUSYBOX" "$WORK/root/bin/busybox"
for a in sh mount insmod ip sleep cat grep poweroff echo; do ln -s busybox "$WORK/root/bin/$a"; done
cp "$KDIR"/*.ko "$WORK/root/lib/"
cp "$MON_STATIC" "$WORK/root/bin/imest-monitor"
cp "$PUB_STATIC" "$WORK/root/bin/imest-can-selftest"
cat >"$WORK/root/init" <<GUEST
#!/bin/sh
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev 2>/dev/null
echo IMEST-GUEST-START
for m in can-dev vcan can can-raw; do insmod /lib/\$m.ko || echo "IMEST-FAIL insmod \$m"; done
ip link add dev vcan0 type vcan && ip link set up vcan0 || echo "IMEST-FAIL vcan0"
ip link add dev vcan1 type vcan || echo "IMEST-FAIL vcan1"
ip link set up lo
for i in nosuch0 lo vcan1; do
  imest-can-selftest --iface \$i --count 1 2>/tmp/e; echo "IMEST-ERRPATH \$i rc=\$?: \$(cat /tmp/e)"
done
imest-monitor --can-iface vcan0 --csv --count $N --timeout 30 >/tmp/mon.csv 2>/tmp/mon.err &
MON=\$!
i=0
while ! grep -q listening /tmp/mon.err; do
  i=\$((i+1)); [ \$i -gt 400 ] && break; sleep 0.05
done
imest-can-selftest --iface vcan0 --count $N --period-ms 2 2>/tmp/pub.err
echo "IMEST-PUB rc=\$?"
wait \$MON
echo "IMEST-MON rc=\$?"
echo IMEST-CSV-BEGIN; cat /tmp/mon.csv; echo IMEST-CSV-END
echo IMEST-ERR-BEGIN; cat /tmp/mon.err /tmp/pub.err; echo IMEST-ERR-END
echo IMEST-GUEST-DONE
poweroff -f
GUEST
chmod +x "$WORK/root/init"
(cd "$WORK/root" && find . | cpio -o -H newc --quiet | gzip -1) >"$WORK/initrd.gz"

# --- expected: the same selftest through the candump port, decoded on the host
"$PUB" --log "$WORK/expect.log" --count "$N" 2>/dev/null
"$MON" --log "$WORK/expect.log" --csv >"$WORK/expect.csv" 2>/dev/null

# --- boot --------------------------------------------------------------------
ACCEL=${IMEST_QEMU_ACCEL:-tcg}
say "booting the guest (qemu-system-x86_64 -accel $ACCEL)"
T1=$(date +%s)
set +e
timeout 240 "$QEMU" -accel "$ACCEL" -m 256M -smp 1 -no-reboot -nographic -nodefaults \
  -serial stdio -kernel "$KDIR/vmlinuz" -initrd "$WORK/initrd.gz" \
  -append "console=ttyS0 panic=-1 quiet loglevel=3" </dev/null >"$WORK/console.log" 2>&1
QRC=$?
set -e
T2=$(date +%s)
tr -d '\r' <"$WORK/console.log" >"$WORK/console.txt"
if ! grep -q IMEST-GUEST-START "$WORK/console.txt"; then
  tail -30 "$WORK/console.txt"
  die "the guest did not start (qemu exit $QRC)"
fi
grep -q IMEST-GUEST-DONE "$WORK/console.txt" || { tail -40 "$WORK/console.txt"; die "guest did not finish (qemu exit $QRC)"; }
sed -n '/^IMEST-ERRPATH/p;/^IMEST-PUB/p;/^IMEST-MON/p;/^IMEST-FAIL/p' "$WORK/console.txt"
sed -n '/^IMEST-ERR-BEGIN/,/^IMEST-ERR-END/p' "$WORK/console.txt" | sed '1d;$d'
sed -n '/^IMEST-CSV-BEGIN/,/^IMEST-CSV-END/p' "$WORK/console.txt" | sed '1d;$d' >"$WORK/guest.csv"

FAILS=0
bad() { echo "qemu_vcan_test: FAIL: $*" >&2; FAILS=$((FAILS + 1)); }
grep -q '^IMEST-FAIL' "$WORK/console.txt" && bad "guest setup failed (see IMEST-FAIL above)"
grep -q '^IMEST-PUB rc=0$' "$WORK/console.txt" || bad "publisher failed in the guest"
grep -q '^IMEST-MON rc=0$' "$WORK/console.txt" || bad "monitor failed in the guest"
grep -q "^IMEST-ERRPATH nosuch0 rc=3: .*no such network interface 'nosuch0'" "$WORK/console.txt" ||
  bad "no clear 'no such interface' message"
grep -q "^IMEST-ERRPATH lo rc=3: .*'lo' is not a CAN interface" "$WORK/console.txt" ||
  bad "no clear 'not a CAN interface' message"
grep -q "^IMEST-ERRPATH vcan1 rc=3: .*'vcan1' is down" "$WORK/console.txt" ||
  bad "no clear 'interface is down' message"
grep -q "published $N window(s), 0 failed send(s)" "$WORK/console.txt" || bad "publisher reported failed sends"
grep -q "lost 0, repeated 0, corrupted 0, estimator gaps 2," "$WORK/console.txt" ||
  bad "monitor summary (expected no bus errors and the 2 windows the selftest skips)"
ROWS=$(($(wc -l <"$WORK/guest.csv") - 1))
[ "$ROWS" -eq "$N" ] || bad "monitor printed $ROWS windows, expected $N"
cut -d, -f2- "$WORK/guest.csv" >"$WORK/guest.cols"
cut -d, -f2- "$WORK/expect.csv" >"$WORK/expect.cols"
if ! cmp -s "$WORK/guest.cols" "$WORK/expect.cols"; then
  diff "$WORK/expect.cols" "$WORK/guest.cols" | head -20
  bad "windows decoded live over vcan0 differ from the same windows via candump"
fi
head -3 "$WORK/guest.csv"
say "guest boot + test $((T2 - T1)) s, total $(($(date +%s) - T0)) s"
[ "$FAILS" -eq 0 ] || exit 1
say "PASS: $N windows over SocketCAN vcan0 in a $(cat "$KDIR/package" | sed 's/_.*//') guest"
