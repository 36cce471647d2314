#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.install_consumer: `cmake --install` of the build into a scratch prefix (core
# package, node, configuration, systemd unit), then
# examples/consumer is configured and built against the installed tree twice, through
# find_package(sfd) (CMake package, sfd::core) and through pkg-config (sfd.pc), and both run
# the parity detector on the scene they build: the one feature whose track jumps is SPURIOUS,
# the 19 others CONSISTENT, in both tested frames. A consumer compiled with other capacities
# than the installed library's does not compile.
# usage: install_consumer.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"; src="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" --component Unspecified >/dev/null
test -f "$tmp/prefix/include/sfd/sfd.h"
test -f "$tmp/prefix/lib/libsfd_core.a" || test -f "$tmp/prefix/lib64/libsfd_core.a"
# deployment files: the node, its configuration, the systemd unit pointing at both, the doc
test -x "$tmp/prefix/bin/sfd-node"
test -f "$tmp/prefix/etc/sfd/sfd.yaml"
grep -q "^ExecStart=$tmp/prefix/bin/sfd-node --config $tmp/prefix/etc/sfd/sfd.yaml --sched-fifo 50 --lock-memory$" \
  "$tmp/prefix/share/sfd/sfd-node.service"
test -f "$tmp/prefix/share/sfd/deploy.md"
grep -q "^MIT License" "$tmp/prefix/share/doc/sfd/LICENSE"
"$tmp/prefix/bin/sfd-node" --help >/dev/null
# the timing tool, its histogram script and its documentation
test -x "$tmp/prefix/bin/sfd-hil"
test -f "$tmp/prefix/share/sfd/plot_hil.py"
test -f "$tmp/prefix/share/sfd/hil.md"
"$tmp/prefix/bin/sfd-hil" --help >/dev/null
# the installed configuration is one the node accepts (it fails on any unknown/invalid key)
"$tmp/prefix/bin/sfd-replay" "$src/tests/replay/golden.lcmlog" \
  --config "$tmp/prefix/etc/sfd/sfd.yaml" >/dev/null
cmake -S "$src/examples/consumer" -B "$tmp/b" -DCMAKE_PREFIX_PATH="$tmp/prefix" >/dev/null
cmake --build "$tmp/b" >/dev/null
"$tmp/b/sfd_consumer" > "$tmp/consumer.txt" || { cat "$tmp/consumer.txt"; exit 1; }
grep -q "2 tested frames: jumped track 107 SPURIOUS (statistic [0-9.]*), 0 wrong verdicts: ok$" \
  "$tmp/consumer.txt" || { cat "$tmp/consumer.txt"; echo "install_consumer: detector verdicts"; exit 1; }
tail -1 "$tmp/consumer.txt"
# sfd.pc is relocatable (prefix=${pcfiledir}/...): the tree moved elsewhere still resolves,
# without pkg-config's --define-prefix
mv "$tmp/prefix" "$tmp/moved"
pcdir="$(dirname "$(find "$tmp/moved" -name sfd.pc | head -1)")"
grep -q '^prefix=${pcfiledir}/' "$pcdir/sfd.pc" || { cat "$pcdir/sfd.pc"; echo "sfd.pc: prefix not relative"; exit 1; }
flags="$(PKG_CONFIG_PATH="$pcdir" pkg-config --dont-define-prefix --cflags --libs --static sfd)"
case "$flags" in
  *"$tmp/moved/"*) ;;
  *) echo "install_consumer: pkg-config flags do not point into the moved tree: $flags"; exit 1 ;;
esac
# shellcheck disable=SC2086
cc -o "$tmp/consumer_pc" "$src/examples/consumer/main.c" $flags
"$tmp/consumer_pc" > "$tmp/consumer_pc.txt" || { cat "$tmp/consumer_pc.txt"; exit 1; }
cmp "$tmp/consumer.txt" "$tmp/consumer_pc.txt" || {
  echo "install_consumer: the pkg-config build's verdicts differ from the CMake build's"; exit 1; }
# a consumer compiled with other capacities than the installed library's is a compile error
# naming the capacity (it used to build, then crash in sfd_parity_init)
for def in SFD_MAX_FEATURES=512 SFD_MAX_WINDOW=4 SFD_IMU_RING_CAPACITY=1024; do
  # shellcheck disable=SC2086
  if cc -D"$def" -o "$tmp/consumer_bad" "$src/examples/consumer/main.c" $flags 2> "$tmp/bad.txt"; then
    echo "install_consumer: -D$def compiled against the installed headers"; exit 1
  fi
  grep -q "sfd: ${def%%=*} differs from the installed library's" "$tmp/bad.txt" || {
    cat "$tmp/bad.txt"; echo "install_consumer: -D$def: no capacity message"; exit 1; }
done
# the library's own values are accepted when given explicitly
# shellcheck disable=SC2086
cc -DSFD_MAX_FEATURES=256 -DSFD_MAX_LANDMARKS=256 -o "$tmp/consumer_same" \
  "$src/examples/consumer/main.c" $flags
echo "install_consumer: find_package(sfd) and a relocated pkg-config (sfd.pc) consumer built and ran the detector"
