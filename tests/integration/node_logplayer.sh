#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.node_logplayer: Debian's lcm-logplayer plays an sfd-sim log over UDP multicast
# (ttl=0) into a running sfd-node while Debian's lcm-logger records the bus. Then:
#  - the node stops cleanly on SIGINT (exit 0), having received every IMU sample and frame played;
#  - the recording holds one SFD_VERDICT and one SFD_TIMING per FEATURES frame;
#  - a log recorded by lcm-logger replays in sfd-replay, and sfd's log reader reads it exactly as
#    liblcm's reader does;
#  - every verdict is identical to the one sfd-replay computes from the same log (the node and the
#    replay share one code path), read back through LCM's Python EventLog.
# Everything runs inside a private network namespace (unshare -n) whose only interface is
# loopback with a multicast route: no packet can leave the namespace.
#  - with a counting allocator preloaded (4th argument), the node's own per-frame path made 0 heap
#    calls after start-up; the LCM library's calls per message are reported.
# usage: node_logplayer.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES [HEAPCOUNT_PRELOAD_SO]
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"; preload="${4:-}"
if ! unshare -n true 2>/dev/null; then
  echo "node_logplayer: 'unshare -n' is not permitted here (needs root or user namespaces)" >&2
  exit 1
fi
# Debian's tools by absolute path (CMake checks they are liblcm-bin 1.3.x and passes them), never
# whichever lcm-logger is first on PATH
export SFD_LCM_LOGGER="${SFD_LCM_LOGGER:-/usr/bin/lcm-logger}"
export SFD_LCM_LOGPLAYER="${SFD_LCM_LOGPLAYER:-/usr/bin/lcm-logplayer}"
for tool in "$SFD_LCM_LOGGER" "$SFD_LCM_LOGPLAYER"; do
  [ -x "$tool" ] || {
    echo "node_logplayer: $tool: not an executable (tools/setup.sh installs liblcm-bin)" >&2; exit 1; }
done
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$build/apps/sfd-sim" mistracking -o "$tmp/in.lcmlog" --frames 60 --seed 3 >/dev/null
"$build/apps/sfd-replay" "$tmp/in.lcmlog" -o "$tmp/replay.lcmlog" >/dev/null

# What the node must receive: every IMU sample and frame of the log played.
read -r n_imu n_frames < <(PYTHONPATH="$pytypes" "$py" - "$tmp/in.lcmlog" <<'PYEOF'
import sys, lcm
n = {'IMU': 0, 'FEATURES': 0}
for ev in lcm.EventLog(sys.argv[1], 'r'):
    if ev.channel in n:
        n[ev.channel] += 1
print(n['IMU'], n['FEATURES'])
PYEOF
)
[ "$n_frames" -gt 0 ] && [ "$n_imu" -gt 0 ] || { echo "node_logplayer: no IMU or FEATURES in the log"; exit 1; }

export SFD_BUILD="$build" SFD_TMP="$tmp" SFD_PRELOAD="$preload" SFD_N_IMU="$n_imu" SFD_N_FRAMES="$n_frames"
unshare -n bash -euo pipefail <<'NS'
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.67:7667?ttl=0"
"$SFD_LCM_LOGGER" -q -f --lcm-url="$url" "$SFD_TMP/recorded.lcmlog" &
logger=$!
if [ -n "$SFD_PRELOAD" ]; then
  LD_PRELOAD="$SFD_PRELOAD" "$SFD_BUILD/apps/sfd-node" --lcm-url "$url" > "$SFD_TMP/node.txt" 2>&1 &
else
  "$SFD_BUILD/apps/sfd-node" --lcm-url "$url" > "$SFD_TMP/node.txt" 2>&1 &
fi
node=$!
# No process outlives an early exit (the logger holds ctest's output pipe open).
trap 'kill "$node" "$logger" 2>/dev/null || true' EXIT
# Play only once the node has subscribed (it prints its start line after lcm_subscribe), and stop
# it only once the logger has recorded a verdict for every frame: a fixed sleep lost the first
# messages, or the last frames still queued, whenever a sanitized build on a loaded machine was
# slow (up to 30 s each).
for _ in $(seq 300); do
  grep -q "^sfd-node .*: method" "$SFD_TMP/node.txt" 2>/dev/null && break
  kill -0 "$node" 2>/dev/null || break
  sleep 0.1
done
grep -q "^sfd-node .*: method" "$SFD_TMP/node.txt" || {
  cat "$SFD_TMP/node.txt"; echo "sfd-node did not start (it exited, or no start line in 30 s)"; exit 1; }
sleep 0.5  # the logger subscribes within this (it prints nothing with -q)
"$SFD_LCM_LOGPLAYER" --lcm-url="$url" -s 2.0 "$SFD_TMP/in.lcmlog" >/dev/null
verdicts=0
for _ in $(seq 300); do
  verdicts="$(grep -a -o SFD_VERDICT "$SFD_TMP/recorded.lcmlog" | wc -l)"
  [ "$verdicts" -ge "$SFD_N_FRAMES" ] && break
  sleep 0.1
done
[ "$verdicts" -ge "$SFD_N_FRAMES" ] || {
  cat "$SFD_TMP/node.txt"
  echo "lcm-logger recorded $verdicts verdicts of $SFD_N_FRAMES frames in 30 s"; exit 1; }
sleep 0.3  # SFD_STATE and SFD_TIMING of the last frame, and one logger flush (100 ms)
kill -INT "$node"
rc=0; wait "$node" || rc=$?
kill -INT "$logger"; wait "$logger" || true
cat "$SFD_TMP/node.txt"
[ "$rc" -eq 0 ] || { echo "sfd-node exited $rc on SIGINT"; exit 1; }
# Every message played reached the node; a loss on the bus or in liblcm's receive queues would
# make the verdicts differ from sfd-replay's for a reason that is not sfd's.
grep -q "stopped: $SFD_N_FRAMES frames in, .* $SFD_N_IMU IMU," "$SFD_TMP/node.txt" || {
  echo "sfd-node did not receive the $SFD_N_FRAMES frames and $SFD_N_IMU IMU samples played" \
       "(lost on the bus or in liblcm's receive queues)"
  exit 1
}
if [ -n "$SFD_PRELOAD" ]; then
  grep -q "heap calls after start-up: sfd per-frame path 0;" "$SFD_TMP/node.txt" || {
    echo "sfd-node's per-frame path allocated (see the heap line above)"; exit 1; }
fi
NS

PYTHONPATH="$pytypes" "$py" - "$tmp/recorded.lcmlog" "$tmp/replay.lcmlog" "$n_frames" <<'PYEOF'
import collections, sys
import lcm
from sfd import feature_verdict_t
def read(path):
    counts = collections.Counter()
    verdicts = {}
    for ev in lcm.EventLog(path, 'r'):
        counts[ev.channel] += 1
        if ev.channel == 'SFD_VERDICT':
            m = feature_verdict_t.decode(ev.data)
            n = m.num_features
            verdicts[m.utime] = (list(m.track_id[:n]), list(m.status[:n]), list(m.statistic[:n]))
    return counts, verdicts
rec_counts, rec = read(sys.argv[1])
rep_counts, rep = read(sys.argv[2])
print('recorded by lcm-logger:', dict(rec_counts))
frames = int(sys.argv[3])
assert rec_counts['FEATURES'] == rep_counts['FEATURES'] == frames, (rec_counts, rep_counts)
assert rec_counts['SFD_VERDICT'] == frames and rec_counts['SFD_TIMING'] == frames, rec_counts
assert rec.keys() == rep.keys()
spurious = 0
for utime in rep:
    assert rec[utime] == rep[utime], utime
    spurious += sum(1 for s in rep[utime][1] if s == 2)
print('node verdicts identical to sfd-replay for all %d frames (%d SPURIOUS)' % (frames, spurious))
PYEOF

# sfd's one log reader (apps/common/sfd_log_reader.h) reads the recording of Debian's lcm-logger
# exactly as liblcm's reader does: every event, field by field.
"$build/tests/test_log_reader" --compare "$tmp/recorded.lcmlog" | grep -v '^\['

# A log recorded by lcm-logger replays in sfd-replay (the recording also holds the node's own
# outputs and LCM_SELF_TEST: they are copied, not interpreted).
"$build/apps/sfd-replay" "$tmp/recorded.lcmlog" --summary "$tmp/rec.json" > "$tmp/rec.txt"
grep -q "\"processed\": $n_frames" "$tmp/rec.json" || {
  cat "$tmp/rec.txt"; echo "sfd-replay could not replay lcm-logger's recording"; exit 1; }
echo "sfd-replay replayed lcm-logger's recording: $(sed -n 2p "$tmp/rec.txt")"
