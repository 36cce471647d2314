#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.install_lcm_types (issue 19 item 1): `cmake --install` into a scratch prefix, then
# the LCM types are used from the install tree only, in every language:
#  - the .lcm files are installed, identical to lcm_types/;
#  - C: examples/lcm_consumer/verdict_roundtrip.c built with pkg-config (sfd-lcmtypes.pc)
#    encodes and decodes a verdict and writes it; the same example built through the CMake
#    package (find_package(sfd COMPONENTS lcmtypes)) also reads it back in C++;
#  - Python (PYTHONPATH=<prefix>/lib/python3/dist-packages): Debian's python3 (no numpy, no lcm
#    module) imports the types and decodes that verdict; sfd.log loads an sfd-replay output log
#    into numpy arrays whose lengths equal the counts of LCM's own reader (PyPI lcm's EventLog),
#    and python3 -m sfd.log2csv writes as many CSV rows; a cut-short log loads, a non-log is
#    refused with one line and exit 2;
#  - Java (skipped with a message only when there is no javac): the jar holds the sfd classes,
#    decodes the verdict, and sfd-spy finds its jar (--dry-run, --list-types), also after the
#    install tree is moved;
#  - every artifact carries VERSION (sfd.pc, sfd-lcmtypes.pc, CMake package, Python, jar, sfd-spy).
# usage: install_lcm_types.sh BUILD_DIR SOURCE_DIR PYTHON VERSION
set -euo pipefail
build="$1"; src="$2"; py="$3"; version="$4"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "install_lcm_types: $*" >&2; exit 1; }
cmake --install "$build" --prefix "$tmp/prefix" --component Unspecified >/dev/null
P="$tmp/prefix"
libdir="$(dirname "$(find "$P" -name libsfd_lcmtypes.a | head -1)")"
[ -f "$libdir/libsfd_lcmtypes.a" ] || fail "libsfd_lcmtypes.a not installed"
export PKG_CONFIG_PATH="$libdir/pkgconfig"

# The message definitions
for f in "$src"/lcm_types/*.lcm; do
  cmp "$f" "$P/share/sfd/lcm_types/$(basename "$f")" || fail "$(basename "$f") not installed as is"
done

# Versions: one, everywhere
for pc in sfd sfd-lcmtypes; do
  v="$(pkg-config --modversion "$pc")"
  [ "$v" = "$version" ] || fail "$pc.pc: version $v, not $version"
done
grep -q "^set(PACKAGE_VERSION \"$version\")" "$libdir/cmake/sfd/sfdConfigVersion.cmake" ||
  fail "sfdConfigVersion.cmake: not $version"
pyv="$(PYTHONPATH="$P/lib/python3/dist-packages" "$py" -c 'import sfd; print(sfd.__version__)')"
[ "$pyv" = "$version" ] || fail "Python sfd.__version__ $pyv, not $version"

# C, through pkg-config: encode + decode, the message written for the other languages
# shellcheck disable=SC2046
cc -std=c99 -Wall -Werror -o "$tmp/roundtrip_pc" "$src/examples/lcm_consumer/verdict_roundtrip.c" \
  $(pkg-config --cflags --libs sfd-lcmtypes)
"$tmp/roundtrip_pc" "$tmp/verdict.bin"
# C and C++, through the CMake package's component
cmake -S "$src/examples/lcm_consumer" -B "$tmp/lc" -DCMAKE_PREFIX_PATH="$P" >/dev/null
cmake --build "$tmp/lc" >/dev/null
"$tmp/lc/verdict_roundtrip" "$tmp/verdict_cmake.bin"
cmp "$tmp/verdict.bin" "$tmp/verdict_cmake.bin" || fail "the two C builds encode differently"
"$tmp/lc/verdict_read" "$tmp/verdict.bin"

# Python: Debian's python3 (no numpy, no lcm module) imports the installed types
PYTHONPATH="$P/lib/python3/dist-packages" /usr/bin/python3 - "$tmp/verdict.bin" "$P" <<'PYEOF'
import sys
import sfd
assert sfd.__file__.startswith(sys.argv[2]), sfd.__file__
m = sfd.feature_verdict_t.decode(open(sys.argv[1], 'rb').read())
assert (m.utime, m.camera_id, m.num_features) == (1234567, 1, 3), m.utime
assert list(m.track_id[:3]) == [11, 12, 13] and m.status[1] == sfd.feature_verdict_t.SPURIOUS
assert m.statistic[1] == 3.25
print('Debian python3: installed sfd %s decodes the C verdict' % sfd.__version__)
PYEOF

# sfd.log on an sfd-replay output log, against LCM's own reader
"$build/apps/sfd-sim" mistracking -o "$tmp/in.lcmlog" --frames 25 --seed 5 >/dev/null
"$build/apps/sfd-replay" "$tmp/in.lcmlog" -o "$tmp/out.lcmlog" >/dev/null
PYTHONPATH="$P/lib/python3/dist-packages" "$py" -m sfd.log2csv "$tmp/out.lcmlog" "$tmp/csv" \
  > "$tmp/log2csv.txt"
PYTHONPATH="$P/lib/python3/dist-packages" "$py" - "$tmp/out.lcmlog" "$tmp/csv" "$P" <<'PYEOF'
import collections, csv, os, sys
import lcm                      # PyPI's (Debian has no python3 binding): the reference reader
import numpy as np
import sfd
from sfd.log import load_log
assert sfd.__file__.startswith(sys.argv[3]), sfd.__file__
path, csvdir = sys.argv[1], sys.argv[2]
count = collections.Counter()
nfeat = collections.Counter()
for ev in lcm.EventLog(path, 'r'):
    count[ev.channel] += 1
    if ev.channel in ('FEATURES', 'SFD_VERDICT', 'TRUTH'):
        nfeat[ev.channel] += {'FEATURES': sfd.feature_frame_t, 'SFD_VERDICT': sfd.feature_verdict_t,
                              'TRUTH': sfd.truth_t}[ev.channel].decode(ev.data).num_features
log = load_log(path)
assert not log.skipped and not log.malformed and log.truncated_at is None, log
assert set(log.channels) == set(count), (sorted(log.channels), count)
assert count['FEATURES'] == count['SFD_VERDICT'] == count['SFD_TIMING'] == count['TRUTH'] == 25
for name, ch in log.channels.items():
    assert len(ch) == count[name], (name, len(ch), count[name])
    for field, arr in ch.fields.items():
        assert isinstance(arr, np.ndarray) and arr.shape[0] == count[name], (name, field)
    rows = sum(1 for _ in open(os.path.join(csvdir, name + '.csv'))) - 1
    assert rows == count[name], (name, rows)
    if ch.features is not None:
        for field, arr in ch.features.items():
            assert arr.shape == (nfeat[name],), (name, field, arr.shape, nfeat[name])
        rows = sum(1 for _ in open(os.path.join(csvdir, name + '.features.csv'))) - 1
        assert rows == nfeat[name], (name, rows)
v, f = log['SFD_VERDICT'], log['FEATURES']
assert v['num_features'].sum() == f['num_features'].sum() == nfeat['FEATURES'] > 0
assert (v.features['track_id'] == f.features['track_id']).all()  # same features, same order
assert log['SFD_TIMING']['rejected'].shape == (25, 21)
assert log['SFD_STATE']['position'].shape == (count['SFD_STATE'], 3)
spurious = int((v.features['status'] == sfd.feature_verdict_t.SPURIOUS).sum())
with open(os.path.join(csvdir, 'SFD_VERDICT.features.csv')) as fh:
    rows = list(csv.DictReader(fh))
assert sum(r['status'] == '2' for r in rows) == spurious
assert [int(r['track_id']) for r in rows] == v.features['track_id'].tolist()
print('sfd.log: %s; %d verdict rows (%d SPURIOUS), CSV rows equal' % (
    ', '.join('%s %d' % kv for kv in sorted(count.items())), len(rows), spurious))
PYEOF
# a log cut short mid-event loads up to the last whole event; a file that is not a log: exit 2
size="$(stat -c %s "$tmp/out.lcmlog")"
head -c "$((size - 100))" "$tmp/out.lcmlog" > "$tmp/cut.lcmlog"
PYTHONPATH="$P/lib/python3/dist-packages" "$py" -m sfd.log2csv "$tmp/cut.lcmlog" "$tmp/csv_cut" \
  > "$tmp/cut.txt"
grep -q "cut.lcmlog: last event cut short at byte [0-9]* (ignored)" "$tmp/cut.txt" ||
  { cat "$tmp/cut.txt"; fail "log2csv: cut-short log not reported"; }
echo "not a log" > "$tmp/bad.lcmlog"
rc=0
PYTHONPATH="$P/lib/python3/dist-packages" "$py" -m sfd.log2csv "$tmp/bad.lcmlog" "$tmp/csv_bad" \
  > "$tmp/bad.out" 2> "$tmp/bad.err" || rc=$?
[ "$rc" -eq 2 ] && [ "$(wc -l < "$tmp/bad.err")" -eq 1 ] &&
  grep -q "^log2csv: $tmp/bad.lcmlog: no LCM sync word at byte 0" "$tmp/bad.err" ||
  { cat "$tmp/bad.err"; fail "log2csv on a non-log: exit $rc"; }

# Java
if ! command -v javac >/dev/null; then
  echo "install_lcm_types: Java part skipped: no javac (tools/setup.sh installs default-jdk-headless)"
else
  jar="$P/share/java/sfd-lcmtypes.jar"
  [ -f "$jar" ] || fail "javac is present but $jar was not installed"
  for t in "$src"/lcm_types/*.lcm; do
    c="sfd/$(basename "$t" .lcm).class"
    jar tf "$jar" | grep -qx "$c" || fail "$jar lacks $c"
  done
  unzip -p "$jar" META-INF/MANIFEST.MF | tr -d '\r' | grep -qx "Implementation-Version: $version" ||
    fail "$jar: manifest version is not $version"
  mkdir "$tmp/jc"
  javac -d "$tmp/jc" -cp "$jar:/usr/share/java/lcm.jar" "$src/examples/lcm_consumer/VerdictRead.java"
  java -cp "$tmp/jc:$jar:/usr/share/java/lcm.jar" VerdictRead "$tmp/verdict.bin"
  [ "$("$P/bin/sfd-spy" --version)" = "sfd-spy $version" ] || fail "sfd-spy --version"
  # --help loads lcm.spy.Spy itself from that class path (headless: it prints lcm-spy's usage)
  "$P/bin/sfd-spy" --help > "$tmp/spy_help.txt" 2>&1 || { cat "$tmp/spy_help.txt"; fail "sfd-spy --help"; }
  grep -q "^usage: lcm-spy" "$tmp/spy_help.txt" || { cat "$tmp/spy_help.txt"; fail "sfd-spy --help: no lcm-spy usage"; }
  # the tree moved: sfd-spy still finds its jar (relative to itself) and lcm-spy's type
  # discovery sees every sfd type
  mv "$P" "$tmp/moved"
  "$tmp/moved/bin/sfd-spy" --dry-run | grep -q -- "-cp $tmp/moved/bin/../share/java/sfd-lcmtypes.jar:" ||
    fail "sfd-spy --dry-run does not use the moved tree's jar"
  "$tmp/moved/bin/sfd-spy" --list-types > "$tmp/types.txt"
  for t in "$src"/lcm_types/*.lcm; do
    grep -qx "sfd.$(basename "$t" .lcm)" "$tmp/types.txt" ||
      { cat "$tmp/types.txt"; fail "sfd-spy --list-types lacks sfd.$(basename "$t" .lcm)"; }
  done
  rc=0
  SFD_SPY_JAR="$tmp/none.jar" "$tmp/moved/bin/sfd-spy" --dry-run 2> "$tmp/spy.err" || rc=$?
  [ "$rc" -eq 2 ] && grep -q "^sfd-spy: $tmp/none.jar: no such file" "$tmp/spy.err" ||
    fail "sfd-spy with a missing jar: exit $rc, $(cat "$tmp/spy.err")"
  echo "install_lcm_types: jar holds the $(wc -l < "$tmp/types.txt") sfd types; sfd-spy finds it"
fi
echo "install_lcm_types: .lcm, C, C++, Python and Java types used from the install tree (version $version)"
