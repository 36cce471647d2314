#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.replay_bad_inputs: sfd-replay on logs that are truncated, corrupt or not LCM logs at
# all, and with outputs that are inputs or cannot be written (docs/deploy.md, "Reading logs and
# writing outputs"). Each case checks the exit code, that the message is one line naming the file
# (and the byte offset of the bad event), and that a failed run leaves no output and no temporary
# file behind and changes no input:
#  - truncated log, junk between events, data length 0x7fffffff, negative length, random bytes,
#    /etc/passwd, a directory, an empty file, a missing file -> exit 2;
#  - --salvage -> exit 0 on the corrupt logs with "log": {bad_events, bytes_skipped} in the
#    summary accounting for every byte, exit 2 on a file without any good event;
#  - -o / --summary naming an input (same path, ./path, hard link, symbolic link, --config) or
#    another output -> exit 2, the input unchanged;
#  - --summary /dev/full, -o /dev/full, a missing directory -> exit 1 naming the path; an older
#    output survives a failed run unchanged; -o /dev/null works.
# sfd-hil --log and sfd-fuzz-seeds read logs through the same reader: sfd-hil is checked here on a
# corrupt log (it must refuse it before it publishes anything).
# usage: replay_bad_inputs.sh BUILD_DIR PYTHON
set -euo pipefail
build="$1"; py="$2"
replay="$build/apps/sfd-replay"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

"$build/apps/sfd-sim" mistracking -o good.lcmlog --frames 8 --features 20 --seed 5 >/dev/null
cp good.lcmlog pristine.lcmlog
# Event offsets of the good log, and the corrupt logs, written by plain Python from the format.
"$py" - <<'PYEOF'
import random, struct
data = open('good.lcmlog', 'rb').read()
offs, p = [], 0
while p < len(data):
    sync, num, ts, cl, dl = struct.unpack('>IqqII', data[p:p + 28])
    assert sync == 0xEDA1DA01
    offs.append(p)
    p += 28 + cl + dl
assert p == len(data)
offs.append(len(data))
n = len(offs) - 1
last, mid = offs[n - 1], offs[n // 2]
def w(name, b): open(name, 'wb').write(b)
w('trunc.lcmlog', data[:last + 40])                                  # cut inside the last event
w('junk.lcmlog', data[:mid] + b'JUNK!' + data[mid:])                 # 5 bytes between events
huge = bytearray(data); huge[mid + 24:mid + 28] = struct.pack('>I', 0x7fffffff)
w('huge.lcmlog', bytes(huge))
neg = bytearray(data); neg[mid + 24:mid + 28] = struct.pack('>i', -5)
w('neg.lcmlog', bytes(neg))
random.seed(1); w('random.lcmlog', bytes(random.getrandbits(8) for _ in range(5000)))
w('empty.lcmlog', b'')
with open('offsets.sh', 'w') as f:
    f.write('n=%d last=%d mid=%d mid_size=%d size=%d\n' % (n, last, mid, offs[n // 2 + 1] - mid, len(data)))
PYEOF
# shellcheck disable=SC1091
source offsets.sh

# expect CODE PATTERN ARGS...: sfd-replay exits CODE with exactly one stderr line matching
# PATTERN (grep -E); no OUT/summary/temporary file is left behind when CODE != 0.
expect() {
  local code="$1" pattern="$2"; shift 2
  rm -f out.lcmlog s.json s.json.timing.json
  local rc=0
  "$replay" "$@" > stdout.txt 2> stderr.txt || rc=$?
  if [ "$rc" -ne "$code" ]; then fail "sfd-replay $* exited $rc, expected $code: $(cat stderr.txt)"; return; fi
  if [ "$code" -ne 0 ]; then
    if [ "$(wc -l < stderr.txt)" -ne 1 ]; then fail "sfd-replay $*: not one line: $(cat stderr.txt)"; fi
    if ! grep -Eq -- "$pattern" stderr.txt; then fail "sfd-replay $*: '$(cat stderr.txt)' !~ '$pattern'"; fi
    if [ -e out.lcmlog ] || [ -e s.json ] || [ -e s.json.timing.json ]; then fail "sfd-replay $*: left an output"; fi
  fi
  if ls -A | grep -q '^\.'; then fail "sfd-replay $*: left a temporary file: $(ls -A | grep '^\.')"; fi
  echo "exit $rc: sfd-replay $* $(head -c 200 stderr.txt)"
}
# log_field FILE KEY: the integer "KEY" inside the summary's "log" object
log_field() { "$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['log'][sys.argv[2]])" "$1" "$2"; }
events_of() { "$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['events'])" "$1"; }

# --- corrupt, truncated and non-LCM inputs: exit 2 naming the file and the byte offset
expect 0 '' good.lcmlog -o out.lcmlog --summary s.json
[ "$(log_field s.json bad_events)" = 0 ] && [ "$(log_field s.json bytes_skipped)" = 0 ] ||
  fail "good log: bad_events/bytes_skipped not 0"
[ "$(events_of s.json)" = "$n" ] || fail "good log: $(events_of s.json) events, expected $n"
expect 2 "^sfd-replay: trunc\.lcmlog: truncated event at byte $last " trunc.lcmlog -o out.lcmlog --summary s.json
expect 2 "^sfd-replay: junk\.lcmlog: no sync word at byte $mid " junk.lcmlog -o out.lcmlog
expect 2 "^sfd-replay: huge\.lcmlog: truncated event at byte $mid \(.*data 2147483647 bytes" huge.lcmlog -o out.lcmlog
expect 2 "^sfd-replay: neg\.lcmlog: bad length in event at byte $mid \(channel [0-9]+, data -5\)" neg.lcmlog --summary s.json
expect 2 "^sfd-replay: random\.lcmlog: no sync word at byte 0 " random.lcmlog -o out.lcmlog
expect 2 "^sfd-replay: /etc/passwd: no sync word at byte 0 " /etc/passwd -o out.lcmlog
expect 2 "^sfd-replay: $tmp: is a directory" "$tmp" -o out.lcmlog
expect 2 "^sfd-replay: empty\.lcmlog: empty file" empty.lcmlog -o out.lcmlog
expect 2 "^sfd-replay: missing\.lcmlog: cannot open" missing.lcmlog -o out.lcmlog
expect 2 "^sfd-replay: random\.lcmlog: no LCM event in 5000 bytes" random.lcmlog --salvage --summary s.json
expect 2 "^sfd-replay: empty\.lcmlog: empty file" empty.lcmlog --salvage

# --- --salvage: skipped events counted in the summary; events + skipped bytes = the whole file
salvage() {  # salvage FILE EVENTS BAD SKIPPED
  expect 0 '' "$1" --salvage -o out.lcmlog --summary s.json
  local got="$(events_of s.json) $(log_field s.json bad_events) $(log_field s.json bytes_skipped)"
  [ "$got" = "$2 $3 $4" ] || fail "--salvage $1: events/bad/skipped $got, expected $2 $3 $4"
  grep -q "skipped $3 bad events ($4 bytes)" stderr.txt || fail "--salvage $1: no warning on stderr"
}
salvage trunc.lcmlog $((n - 1)) 1 40
salvage junk.lcmlog "$n" 1 5
salvage huge.lcmlog $((n - 1)) 1 "$mid_size"
salvage neg.lcmlog $((n - 1)) 1 "$mid_size"
# the salvaged OUT holds the good events: a strict replay of it reads them all
expect 0 '' junk.lcmlog --salvage -o out.lcmlog
cp out.lcmlog salvaged.lcmlog
expect 0 '' salvaged.lcmlog --summary s.json

# --- no output may be an input (or another output): exit 2, nothing written, inputs unchanged
ln good.lcmlog hard.lcmlog
ln -s good.lcmlog soft.lcmlog
cp "$here/../../apps/config/sfd.yaml" cfg.yaml
cp cfg.yaml cfg.pristine
expect 2 "^sfd-replay: -o good\.lcmlog is the input log good\.lcmlog \(same file\)" good.lcmlog -o good.lcmlog
expect 2 "^sfd-replay: -o \./good\.lcmlog is the input log good\.lcmlog" good.lcmlog -o ./good.lcmlog
expect 2 "^sfd-replay: -o $tmp/good\.lcmlog is the input log good\.lcmlog" good.lcmlog -o "$tmp/good.lcmlog"
expect 2 "^sfd-replay: -o hard\.lcmlog is the input log good\.lcmlog" good.lcmlog -o hard.lcmlog
expect 2 "^sfd-replay: -o soft\.lcmlog is the input log good\.lcmlog" good.lcmlog -o soft.lcmlog
expect 2 "^sfd-replay: -o good\.lcmlog is the input log soft\.lcmlog" soft.lcmlog -o good.lcmlog
expect 2 "^sfd-replay: --summary good\.lcmlog is the input log" good.lcmlog --summary good.lcmlog
expect 2 "^sfd-replay: --summary cfg\.yaml is the input --config cfg\.yaml" good.lcmlog --config cfg.yaml --summary cfg.yaml
expect 2 "^sfd-replay: -o \./cfg\.yaml is the input --config cfg\.yaml" good.lcmlog --config cfg.yaml -o ./cfg.yaml
cp good.lcmlog t.timing.json
expect 2 "^sfd-replay: --summary timing t\.timing\.json is the input log t\.timing\.json" t.timing.json --summary t
expect 2 "^sfd-replay: -o s\.json and --summary s\.json are the same file" good.lcmlog -o s.json --summary s.json
expect 2 "is the input log good\.lcmlog" good.lcmlog --score-only --summary hard.lcmlog
cmp good.lcmlog pristine.lcmlog || fail "an input log was changed"
cmp cfg.yaml cfg.pristine || fail "the input config was changed"

# --- write failures: exit 1 naming the path; a failed run leaves an older output as it was
expect 1 "^sfd-replay: --summary /dev/full: write failed" good.lcmlog --summary /dev/full
expect 1 "^sfd-replay: -o /dev/full: write failed" good.lcmlog -o /dev/full
expect 1 "^sfd-replay: -o nodir/out\.lcmlog: cannot create a file in nodir" good.lcmlog -o nodir/out.lcmlog
expect 1 "^sfd-replay: --summary nodir/s\.json: cannot create" good.lcmlog --summary nodir/s.json
expect 1 "^sfd-replay: -o $tmp: is a directory" good.lcmlog -o "$tmp"
echo "an older output" > old.lcmlog
rc=0; "$replay" trunc.lcmlog -o old.lcmlog >/dev/null 2>&1 || rc=$?
[ "$rc" -eq 2 ] && [ "$(cat old.lcmlog)" = "an older output" ] || fail "a failed run changed an older output"
rc=0; "$replay" good.lcmlog -o old.lcmlog --summary /dev/full >/dev/null 2>&1 || rc=$?
[ "$rc" -eq 1 ] && [ "$(cat old.lcmlog)" = "an older output" ] || fail "a failed --summary changed -o"
expect 0 '' good.lcmlog -o /dev/null --summary /dev/null
# outputs get the usual mode (0666 less the umask), and a symbolic link to an output is written
# through (the link stays a link)
(umask 022; "$replay" good.lcmlog -o mode.lcmlog >/dev/null)
[ "$(stat -c %a mode.lcmlog)" = 644 ] || fail "output mode $(stat -c %a mode.lcmlog), expected 644"
ln -s mode.lcmlog link.lcmlog
"$replay" good.lcmlog -o link.lcmlog >/dev/null
[ -L link.lcmlog ] && cmp -s link.lcmlog mode.lcmlog || fail "-o through a symbolic link"
if ls -A | grep -q '^\.'; then fail "temporary files left: $(ls -A | grep '^\.')"; fi

# --- sfd-hil reads --log through the same reader: a corrupt log is refused before publishing
rc=0; "$build/apps/sfd-hil" --log huge.lcmlog --lcm-url memq:// > hil.txt 2> hil.err || rc=$?
[ "$rc" -eq 2 ] && grep -Eq "huge\.lcmlog: truncated event at byte $mid " hil.err &&
  ! grep -q "^sfd-hil: log" hil.txt || fail "sfd-hil --log huge.lcmlog: exit $rc, $(cat hil.err)"
rc=0; "$build/apps/sfd-hil" --log good.lcmlog --csv ./good.lcmlog --lcm-url memq:// > hil.txt 2> hil.err || rc=$?
[ "$rc" -eq 2 ] && grep -q "is the input" hil.err || fail "sfd-hil --csv = --log: exit $rc, $(cat hil.err)"
cmp good.lcmlog pristine.lcmlog || fail "sfd-hil changed its input log"

if [ "$fails" -ne 0 ]; then echo "replay_bad_inputs: $fails failures"; exit 1; fi
echo "replay_bad_inputs: all cases as documented"
