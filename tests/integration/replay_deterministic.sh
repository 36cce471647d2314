#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.replay_deterministic: sfd-sim writes a log; sfd-replay plays it twice; OUT and the
# summary must be byte-identical, OUT must hold every input event plus one SFD_VERDICT and one
# SFD_TIMING per frame, and LCM's own Python EventLog reader must read OUT and decode the
# verdicts with the generated Python types (interoperability with LCM's implementation).
# usage: replay_deterministic.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$build/apps/sfd-sim" moving-object -o "$tmp/in.lcmlog" --frames 120 --seed 7 >/dev/null
"$build/apps/sfd-replay" "$tmp/in.lcmlog" -o "$tmp/out1.lcmlog" --summary "$tmp/s1.json" >/dev/null
"$build/apps/sfd-replay" "$tmp/in.lcmlog" -o "$tmp/out2.lcmlog" --summary "$tmp/s2.json" >/dev/null
cmp "$tmp/out1.lcmlog" "$tmp/out2.lcmlog"
cmp "$tmp/s1.json" "$tmp/s2.json"
echo "OUT and summary byte-identical ($(stat -c %s "$tmp/out1.lcmlog") bytes)"
PYTHONPATH="$pytypes" "$py" - "$tmp/in.lcmlog" "$tmp/out1.lcmlog" <<'PYEOF'
import collections, sys
import lcm
from sfd import feature_verdict_t, feature_frame_t
def channels(path):
    c = collections.Counter()
    frames = {}
    verdicts = {}
    for ev in lcm.EventLog(path, 'r'):
        c[ev.channel] += 1
        if ev.channel == 'FEATURES':
            m = feature_frame_t.decode(ev.data)
            frames[m.utime] = list(m.track_id[:m.num_features])
        if ev.channel == 'SFD_VERDICT':
            m = feature_verdict_t.decode(ev.data)
            verdicts[m.utime] = list(m.track_id[:m.num_features])
    return c, frames, verdicts
cin, frames, _ = channels(sys.argv[1])
cout, _, verdicts = channels(sys.argv[2])
for ch, n in cin.items():
    assert cout[ch] == n, (ch, n, cout[ch])
assert cout['SFD_VERDICT'] == cin['FEATURES'], cout
assert cout['SFD_TIMING'] == cin['FEATURES'], cout
for utime, ids in frames.items():
    assert verdicts[utime] == ids, utime   # every feature of its frame, in the frame's order
print('python lcm.EventLog read OUT:', dict(cout))
PYEOF
