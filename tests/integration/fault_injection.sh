#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.fault_injection (issue 18 item 7): sfd-node over real LCM (UDP multicast, ttl=0)
# in a private network namespace, fed by sfd-hil with faults injected, and the node itself
# stopped for 1 s. Checks:
#  1. publisher faults (mistracking, 300 frames at 2x pace): frames 40-120 dropped, duplicated
#     and reordered with 10 % each, frame 140 stamped 1000 s ahead, a 1 s publisher stall
#     before frame 160, a publisher restart 100 s back from frame 220 on. Exit 0: every frame
#     the node received is judged or refused (frames_in = judged + frames_refused), no refused
#     frame is judged, every frame that is not a fault has its verdict (frames after the future
#     stamp and after the restart included), and the node's refusals are exactly the ones the
#     faults imply: order = duplicates + reordered, time_jump = 1 + 2 (N - 1), restart = 2;
#     the counters sfd-hil read from SFD_TIMING equal the node's stop report.
#  2. a stalled node (SIGSTOP for 1 s, 200 frames at the recorded pace): every frame received
#     is accounted for; the frames the kernel dropped while it was stopped (copies published -
#     frames_in) show in the node's frame_gap counter; the last 40 frames are judged.
# usage: fault_injection.sh BUILD_DIR
set -euo pipefail
build="$1"
if ! unshare -n true 2>/dev/null; then
  echo "fault_injection: 'unshare -n' is not permitted here (needs root or user namespaces)" >&2
  exit 1
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export SFD_BUILD="$build" SFD_TMP="$tmp"
unshare -n bash -euo pipefail <<'NS'
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.73:7673?ttl=0"
hil="$SFD_BUILD/apps/sfd-hil"
field() {  # the value column of a report row starting with "| $1"
  grep -m1 "^| $1" "$2" | awk -F'|' '{print $3}' | sed 's/^ *//; s/ *$//'
}
reason() {  # the node's stop-report count of a rejection reason
  grep -o " $1=[0-9]*" "$2" | head -1 | cut -d= -f2
}
fail() { echo "fault_injection: $*"; exit 1; }

# 1. publisher faults
"$SFD_BUILD/apps/sfd-node" --lcm-url "$url" > "$SFD_TMP/node1.txt" 2>&1 &
node=$!
sleep 0.3
rc=0
"$hil" --sim mistracking --frames 300 --rate 2 --timeout-ms 1000 --lcm-url "$url" \
  --fault-drop 0.1 --fault-dup 0.1 --fault-reorder 0.1 --fault-frames 40:120 --fault-seed 3 \
  --fault-future-frame 140 --fault-stall-frame 160 --fault-stall-ms 1000 \
  --fault-restart-frame 220 --csv "$SFD_TMP/faults.csv" > "$SFD_TMP/faults.txt" 2>&1 || rc=$?
kill -INT "$node"; wait "$node" || true
cat "$SFD_TMP/faults.txt"; tail -4 "$SFD_TMP/node1.txt"
[ "$rc" -eq 0 ] || fail "publisher faults: sfd-hil exit $rc, expected 0"
faults="$(field 'faults injected' "$SFD_TMP/faults.txt")"
dropped=$(echo "$faults" | sed -E 's/.*dropped ([0-9]+).*/\1/')
dup=$(echo "$faults" | sed -E 's/.*duplicated ([0-9]+).*/\1/')
reord=$(echo "$faults" | sed -E 's/.*reordered ([0-9]+).*/\1/')
[ "$dropped" -gt 0 ] && [ "$dup" -gt 0 ] && [ "$reord" -gt 0 ] || fail "faults not injected: $faults"
[ "$(field 'every frame received accounted for' "$SFD_TMP/faults.txt")" = "yes" ] || fail "not accounted"
[ "$(field 'refused frames the node judged anyway' "$SFD_TMP/faults.txt")" = "0" ] || fail "a refused frame was judged"
[ "$(field 'lost: frames without verdict' "$SFD_TMP/faults.txt" | awk '{print $1}')" = "0" ] || fail "frames lost"
[ "$(reason order "$SFD_TMP/node1.txt")" = "$((dup + reord))" ] || fail "order != duplicated + reordered"
[ "$(reason time_jump "$SFD_TMP/node1.txt")" = "9" ] || fail "time_jump != 1 + 2 x 4"
[ "$(reason restart "$SFD_TMP/node1.txt")" = "2" ] || fail "restart != 2"
# sfd-hil's view of the node's counters (from SFD_TIMING) equals the node's own stop report
compared=0
for kv in $(field 'node rejected\[\] during run' "$SFD_TMP/faults.txt"); do
  compared=$((compared + 1))
  name="${kv%%=*}"; total="$(echo "$kv" | sed -E 's/.*\(([0-9]+)\)/\1/')"
  [ "$(reason "$name" "$SFD_TMP/node1.txt")" = "$total" ] || fail "$name: sfd-hil saw $total, the node's stop report $(reason "$name" "$SFD_TMP/node1.txt")"
done
[ "$compared" -ge 3 ] || fail "sfd-hil's rejected[] row has $compared entries"
echo "ok: publisher faults: dropped $dropped, duplicated $dup, reordered $reord; every frame accounted for; sfd-hil and the node's stop report agree"

# 2. a stalled node
"$SFD_BUILD/apps/sfd-node" --lcm-url "$url" > "$SFD_TMP/node2.txt" 2>&1 &
node=$!
sleep 0.3
( sleep 4; kill -STOP "$node"; sleep 1; kill -CONT "$node" ) &
stopper=$!
rc=0
"$hil" --sim mistracking --frames 200 --rate 1 --timeout-ms 3000 --lcm-url "$url" \
  --csv "$SFD_TMP/stall.csv" > "$SFD_TMP/stall.txt" 2>&1 || rc=$?
wait "$stopper" || true
kill -INT "$node"; wait "$node" || true
cat "$SFD_TMP/stall.txt"; tail -4 "$SFD_TMP/node2.txt"
[ "$rc" -eq 0 ] || [ "$rc" -eq 3 ] || fail "stalled node: sfd-hil exit $rc, expected 0 or 3"
in=$(grep -o "stopped: [0-9]* frames in" "$SFD_TMP/node2.txt" | awk '{print $2}')
refused=$(grep -o "frames in, [0-9]* refused" "$SFD_TMP/node2.txt" | awk '{print $3}')
processed=$(grep -o "refused, [0-9]* processed" "$SFD_TMP/node2.txt" | awk '{print $2}')
[ "$in" -eq "$((refused + processed))" ] || fail "stalled node: $in frames in != $refused refused + $processed processed"
published=$(field 'frames published' "$SFD_TMP/stall.txt" | awk '{print $1}')
lost=$((published - in))
gap=$(reason frame_gap "$SFD_TMP/node2.txt")
[ "$gap" -ge "$lost" ] || fail "stalled node: $lost frames lost on the transport, frame_gap only $gap"
bad=$(tail -n 40 "$SFD_TMP/stall.csv" | awk -F, '$13 != 1' | wc -l)
[ "$bad" -eq 0 ] || fail "stalled node: $bad of the last 40 frames without verdict"
echo "ok: stalled node: $published published, $in received ($lost lost on the transport, frame_gap $gap), $processed judged, $refused refused"
NS
echo "fault_injection checks passed"
