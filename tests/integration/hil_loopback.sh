#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.hil_loopback: sfd-hil against a running sfd-node over real LCM (UDP multicast,
# ttl=0, its own group and port), inside a private network namespace (unshare -n) whose only
# interface is loopback with a multicast route. Each run gets a fresh node (sfd-hil's restamped
# utimes run ahead of the wall clock at --rate 0 or > 1, so a node kept between runs would
# reject the next run's messages as out of order). --timeout-ms 200 (a frame's round trip takes
# a few ms) keeps a node that does not answer from stalling the closed loop. Checks:
#  1. --sim mistracking, 300 frames, --rate 0 (closed loop): exit 0, verdicts == timing ==
#     frames == 300, nothing lost, 300 CSV rows, the node's stop report counts 300 frames;
#  2. the same at --rate 4 (paced, 150 frames): exit 0, nothing lost, 150 CSV rows;
#  3. an impossible --budget-us 1: exit 3, every measured frame a deadline miss;
#  4. no node: every frame times out: exit 3, all frames lost;
#  5. usage and input errors: exit 2 (no source, unknown scenario, unreadable log, a file that
#     is not an LCM log);
#  7. --json: the report as JSON (json.load), equal to the printed table: 300 frames, nothing
#     lost, end-to-end p99 <= max; the impossible budget's 50 misses;
#  6. sfd-node's real-time set-up (--sched-fifo, --cpu, --lock-memory): the node and its LCM
#     receive thread run SCHED_FIFO at the priority asked, pinned to the CPU asked, with locked
#     memory (VmLck > 0), and a closed-loop run against it ends clean; bad values exit 2;
#     without CAP_SYS_NICE / CAP_IPC_LOCK (setpriv) the node stops with exit 1 and the reason.
# usage: hil_loopback.sh BUILD_DIR
set -euo pipefail
build="$1"
if ! unshare -n true 2>/dev/null; then
  echo "hil_loopback: 'unshare -n' is not permitted here (needs root or user namespaces)" >&2
  exit 1
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
hil="$build/apps/sfd-hil"

# 5. usage and input errors (no LCM needed).
expect_rc() {  # expected-rc description command...
  local want="$1" what="$2"; shift 2
  local rc=0
  "$@" > "$tmp/out.txt" 2>&1 || rc=$?
  if [ "$rc" -ne "$want" ]; then
    cat "$tmp/out.txt"; echo "hil_loopback: $what: exit $rc, expected $want"; exit 1
  fi
  echo "ok: $what -> exit $rc: $(grep -m1 'sfd-[a-z]*:' "$tmp/out.txt" || true)"
}
expect_rc 2 "no source" "$hil"
expect_rc 2 "unknown scenario" "$hil" --sim nowhere
expect_rc 2 "--log and --sim together" "$hil" --sim mistracking --log "$tmp/x.lcmlog"
expect_rc 2 "bad --rate" "$hil" --sim mistracking --rate fast
head -c 5000 /dev/urandom > "$tmp/garbage.lcmlog"
expect_rc 2 "unreadable log" "$hil" --log "$tmp/missing.lcmlog"
# sfd-node's real-time options: a bad value is refused before LCM starts (exit 2 and the reason;
# a value wrongly taken would start a node, which `timeout` ends with 124).
node_bin="$build/apps/sfd-node"
node_refuses() {  # description pattern args...
  local what="$1" pattern="$2"; shift 2
  expect_rc 2 "$what" timeout 10 "$node_bin" "$@"
  grep -q -- "$pattern" "$tmp/out.txt" || { cat "$tmp/out.txt"; echo "hil_loopback: $what: no '$pattern'"; exit 1; }
}
node_refuses "sfd-node --sched-fifo 0" "^sfd-node: --sched-fifo: 0 is not in 1..99$" --sched-fifo 0
node_refuses "sfd-node --sched-fifo 100" "^sfd-node: --sched-fifo: 100 is not in 1..99$" --sched-fifo=100
node_refuses "sfd-node --cpu -1" "^sfd-node: --cpu: -1 is not in 0\.\." --cpu -1
node_refuses "sfd-node --cpu x" "^sfd-node: --cpu: x is not an integer$" --cpu x
expect_rc 2 "sfd-hil --json without a value" "$hil" --sim mistracking --json
grep -q "^sfd-hil: --json needs a value$" "$tmp/out.txt" || { cat "$tmp/out.txt"; exit 1; }

export SFD_BUILD="$build" SFD_TMP="$tmp"
unshare -n bash -euo pipefail <<'NS'
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.71:7671?ttl=0"
hil="$SFD_BUILD/apps/sfd-hil"
start_node() {  # name [sfd-node options...]
  local name="$1"; shift
  "$SFD_BUILD/apps/sfd-node" --lcm-url "$url" "$@" > "$SFD_TMP/node_$name.txt" 2>&1 &
  node=$!
  sleep 0.5
}
stop_node() {
  kill -INT "$node"
  local rc=0; wait "$node" || rc=$?
  [ "$rc" -eq 0 ] || { cat "$SFD_TMP/node_$1.txt"; echo "sfd-node exited $rc on SIGINT"; exit 1; }
}
field() {  # the value column of a report row starting with "| $1"
  grep -m1 "^| $1" "$2" | awk -F'|' '{print $3}' | awk '{print $1}'
}
check_clean_run() {  # name frames
  local out="$SFD_TMP/$1.txt" n="$2"
  cat "$out"
  [ "$(field 'frames published' "$out")" = "$n" ] || { echo "$1: frames published != $n"; exit 1; }
  [ "$(field 'verdicts received' "$out")" = "$n" ] || { echo "$1: verdicts != $n"; exit 1; }
  [ "$(field 'timing received' "$out")" = "$n" ] || { echo "$1: timing != $n"; exit 1; }
  [ "$(field 'lost: frames without verdict' "$out")" = "0" ] || { echo "$1: frames lost"; exit 1; }
  [ "$(field 'lost: verdicts for unknown' "$out")" = "0" ] || { echo "$1: unknown verdicts"; exit 1; }
  [ "$(field 'lost: node-side drops' "$out")" = "0" ] || { echo "$1: node-side drops"; exit 1; }
  local rows; rows=$(($(wc -l < "$SFD_TMP/$1.csv") - 1))
  [ "$rows" -eq "$n" ] || { echo "$1: $rows CSV rows, expected $n"; exit 1; }
  # every row: a verdict, a timing, not lost
  awk -F, -v name="$1" 'NR > 1 && ($13 != 1 || $14 != 1 || $16 != 0) {
      print name ": CSV row " NR - 1 " not a clean frame: " $0; bad = 1 } END { exit bad }' \
      "$SFD_TMP/$1.csv"
}

# A run against a fresh node that must end clean (exit 0, every frame judged): NAME FRAMES RATE
run_clean() {  # NAME FRAMES RATE [sfd-node options...]
  start_node "$1" "${@:4}"
  local rc=0
  "$hil" --sim mistracking --frames "$2" --rate "$3" --timeout-ms 200 --lcm-url "$url" \
    --csv "$SFD_TMP/$1.csv" --json="$SFD_TMP/$1.json" > "$SFD_TMP/$1.txt" 2>&1 || rc=$?
  stop_node "$1"
  [ "$rc" -eq 0 ] || { cat "$SFD_TMP/$1.txt"; echo "rate $3: exit $rc, expected 0"; exit 1; }
  check_clean_run "$1" "$2"
}

# 1. closed loop
run_clean rate0 300 0
grep -q "stopped: 300 frames in, 0 refused, 300 processed" "$SFD_TMP/node_rate0.txt" || {
  cat "$SFD_TMP/node_rate0.txt"; echo "rate 0: the node did not process 300 frames"; exit 1; }
# 7. the report as JSON: parsed, and equal to the printed table
python3 - "$SFD_TMP/rate0.json" "$SFD_TMP/rate0.txt" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
text = open(sys.argv[2]).read()
assert j["frames_published"] == 300 and j["verdicts_received"] == 300, j
assert j["timing_received"] == 300 and j["lost"]["total"] == 0, j["lost"]
assert j["result"] == "ok" and j["deadline"] is None, j["result"]
e2e = j["latency_us"]["end_to_end"]
assert e2e["n"] == 290 and e2e["min"] <= e2e["median"] <= e2e["p99"] <= e2e["p999"] <= e2e["max"], e2e
row = "| end-to-end | %.0f | %.0f | %.0f | %.0f | %.0f |" % (
    e2e["min"], e2e["median"], e2e["p99"], e2e["p999"], e2e["max"])
assert row in text, (row, text)
assert j["node_rejected"]["decode"]["during_run"] == 0, j["node_rejected"]
print("ok: --json: 300 frames, nothing lost, end-to-end row as printed:", row)
PY

# 2. paced, 4x the recorded pace
run_clean rate4 150 4
grep -q "pacing: publish lateness" "$SFD_TMP/rate4.txt" || { echo "rate 4: no pacing row"; exit 1; }

# 3. an impossible budget: every measured frame misses it, exit 3
start_node budget
rc=0
"$hil" --sim mistracking --frames 60 --rate 0 --budget-us 1 --timeout-ms 200 --lcm-url "$url" \
  --json "$SFD_TMP/budget.json" > "$SFD_TMP/budget.txt" 2>&1 || rc=$?
stop_node budget
cat "$SFD_TMP/budget.txt"
[ "$rc" -eq 3 ] || { echo "budget 1 us: exit $rc, expected 3"; exit 1; }
grep -q "^| deadline misses (node total_us > 1 us) | 50 of 50 |" "$SFD_TMP/budget.txt" || {
  echo "budget 1 us: expected 50 of 50 measured frames (60 - 10 warm-up) to miss"; exit 1; }
python3 -c 'import json, sys; d = json.load(open(sys.argv[1]))["deadline"]
assert d == {"budget_us": 1, "of": "node total_us", "misses": 50, "frames": 50}, d' \
  "$SFD_TMP/budget.json" || { echo "budget 1 us: --json deadline"; exit 1; }

# 4. no node: every frame times out, exit 3
rc=0
"$hil" --sim mistracking --frames 20 --rate 0 --timeout-ms 50 --lcm-url "$url" \
  > "$SFD_TMP/nonode.txt" 2>&1 || rc=$?
cat "$SFD_TMP/nonode.txt"
[ "$rc" -eq 3 ] || { echo "no node: exit $rc, expected 3"; exit 1; }
[ "$(field 'verdicts received' "$SFD_TMP/nonode.txt")" = "0" ] || { echo "no node: verdicts?"; exit 1; }
[ "$(field 'lost: frames without verdict' "$SFD_TMP/nonode.txt")" = "20" ] || {
  echo "no node: expected 20 lost frames"; exit 1; }

# A file that is not an LCM log: exit 2 with the reason and the byte offset, no crash.
rc=0
"$hil" --log "$SFD_TMP/garbage.lcmlog" --rate 0 --timeout-ms 50 --lcm-url "$url" \
  > "$SFD_TMP/garbage.txt" 2>&1 || rc=$?
[ "$rc" -eq 2 ] && grep -q "garbage.lcmlog: no sync word at byte 0" "$SFD_TMP/garbage.txt" || {
  cat "$SFD_TMP/garbage.txt"; echo "garbage log: exit $rc, expected 2 with a reason"; exit 1; }
echo "ok: garbage log -> exit 2: $(grep -m1 'no sync word' "$SFD_TMP/garbage.txt")"

# 6. real-time set-up: every thread of the node (main and LCM's receive thread) SCHED_FIFO 7,
# pinned to CPU 0, memory locked; then a clean closed-loop run against it.
if chrt -f 1 true 2>/dev/null; then
  start_node rt --sched-fifo 7 --cpu 0 --lock-memory
  grep -q "real-time: scheduler SCHED_FIFO 7, CPU 0, memory locked" "$SFD_TMP/node_rt.txt" || {
    cat "$SFD_TMP/node_rt.txt"; echo "rt: no real-time line"; exit 1; }
  threads=0
  for task in /proc/"$node"/task/*; do
    tid="${task##*/}"
    threads=$((threads + 1))
    chrt -p "$tid" | grep -q "scheduling policy: SCHED_FIFO" || { chrt -p "$tid"; echo "rt: thread $tid not SCHED_FIFO"; exit 1; }
    chrt -p "$tid" | grep -q "scheduling priority: 7$" || { chrt -p "$tid"; echo "rt: thread $tid priority"; exit 1; }
    [ "$(taskset -pc "$tid" | awk '{print $NF}')" = "0" ] || { taskset -pc "$tid"; echo "rt: thread $tid affinity"; exit 1; }
  done
  [ "$threads" -ge 2 ] || { echo "rt: $threads thread(s): LCM's receive thread not there to check"; exit 1; }
  locked_kb="$(awk '/^VmLck:/ {print $2}' /proc/"$node"/status)"
  [ "${locked_kb:-0}" -gt 0 ] || { grep Vm /proc/"$node"/status; echo "rt: no locked memory"; exit 1; }
  stop_node rt
  echo "ok: rt node: $threads threads SCHED_FIFO 7 on CPU 0, VmLck $locked_kb kB"
  # Without the capabilities: exit 1 and the reason, before any message is handled.
  if command -v setpriv > /dev/null; then
    rc=0
    (ulimit -l 64; timeout 10 setpriv --inh-caps=-ipc_lock --bounding-set=-ipc_lock \
      "$SFD_BUILD/apps/sfd-node" --lcm-url "$url" --lock-memory) > "$SFD_TMP/nolock.txt" 2>&1 || rc=$?
    [ "$rc" -eq 1 ] && grep -q "^sfd-node: --lock-memory: mlockall: .*CAP_IPC_LOCK" "$SFD_TMP/nolock.txt" || {
      cat "$SFD_TMP/nolock.txt"; echo "rt: --lock-memory without CAP_IPC_LOCK: exit $rc, expected 1"; exit 1; }
    rc=0
    timeout 10 setpriv --inh-caps=-sys_nice --bounding-set=-sys_nice \
      "$SFD_BUILD/apps/sfd-node" --lcm-url "$url" --sched-fifo 7 > "$SFD_TMP/nonice.txt" 2>&1 || rc=$?
    [ "$rc" -eq 1 ] && grep -q "^sfd-node: --sched-fifo 7: sched_setscheduler: .*CAP_SYS_NICE" "$SFD_TMP/nonice.txt" || {
      cat "$SFD_TMP/nonice.txt"; echo "rt: --sched-fifo without CAP_SYS_NICE: exit $rc, expected 1"; exit 1; }
    echo "ok: without CAP_IPC_LOCK / CAP_SYS_NICE: exit 1: $(head -1 "$SFD_TMP/nolock.txt") / $(head -1 "$SFD_TMP/nonice.txt")"
  fi
  run_clean rt_run 100 0 --sched-fifo 7 --cpu 0 --lock-memory
else
  echo "hil_loopback: SCHED_FIFO not permitted here: real-time set-up not checked"
fi
NS
echo "hil_loopback: all checks passed"
