#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One sfd-hil measurement against a fresh sfd-node (docs/hil.md): starts the node, runs sfd-hil,
# stops the node and keeps everything in OUTDIR.
#
# usage: tools/hil_bench.sh OUTDIR MODE [sfd-hil ARGS...]
#   MODE          the node's --method: none | parity | oprf | ransac1 | ransacf | both
#   ARGS          passed to sfd-hil (--sim/--log, --rate, --budget-us, ...; not --lcm-url,
#                 --csv, --png: set here)
# Environment:
#   SFD_NODE_PREFIX  command prefix of the node, e.g. "chrt -f 50" or "taskset -c 1 chrt -f 50"
#   SFD_HIL_PREFIX   the same for sfd-hil, e.g. "taskset -c 0"
#   SFD_NODE_ARGS    extra sfd-node options, e.g. "--sched-fifo 50 --cpu 1 --lock-memory"
#   SFD_NODE_YAML    the node's configuration (default: apps/config/sfd.yaml with
#                    filter.init_from_truth: 1, written to OUTDIR/node.yaml: sfd-hil --sim
#                    publishes TRUTH, and its flights do not start at rest)
#   SFD_LCM_URL      LCM URL of both (default udpm://239.255.76.67:7667?ttl=0)
#   SFD_BIN          directory of sfd-node and sfd-hil (default build/host/apps)
#   SFD_HIL_NETNS=1  run inside a private network namespace (unshare -n, root) with loopback
#                    and a multicast route only: for hosts without a multicast route
# Writes OUTDIR/report.txt (sfd-hil's table), hil.csv, hil.png, node.txt (the node's start and
# stop report: frames, rejections, heap), node.yaml (if generated), cmd.txt. Exit: sfd-hil's
# (0 ok, 2 usage, 3 budget missed or messages lost), 1 if the node failed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ "$#" -lt 2 ]; then
  sed -n '3,23p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
out="$1"; mode="$2"; shift 2
if [ "${SFD_HIL_NETNS:-0}" = "1" ] && [ -z "${SFD_HIL_IN_NETNS:-}" ]; then
  exec unshare -n env SFD_HIL_IN_NETNS=1 bash -c '
    ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo &&
    exec bash "$0" "$@"' "${BASH_SOURCE[0]}" "$out" "$mode" "$@"
fi
bin="${SFD_BIN:-$root/build/host/apps}"
url="${SFD_LCM_URL:-udpm://239.255.76.67:7667?ttl=0}"
mkdir -p "$out"
yaml="${SFD_NODE_YAML:-}"
if [ -z "$yaml" ]; then
  yaml="$out/node.yaml"
  sed 's/^\( *init_from_truth:\) 0$/\1 1/' "$root/apps/config/sfd.yaml" > "$yaml"
  grep -q '^ *init_from_truth: 1$' "$yaml" || { echo "hil_bench: could not set init_from_truth" >&2; exit 1; }
fi
# shellcheck disable=SC2086
${SFD_NODE_PREFIX:-} "$bin/sfd-node" --config "$yaml" --method "$mode" --lcm-url "$url" \
  ${SFD_NODE_ARGS:-} > "$out/node.txt" 2>&1 &
node=$!
sleep 1
if ! kill -0 "$node" 2>/dev/null; then
  cat "$out/node.txt" >&2; echo "hil_bench: sfd-node did not start" >&2; exit 1
fi
{
  echo "node: ${SFD_NODE_PREFIX:-} $bin/sfd-node --config $yaml --method $mode --lcm-url $url ${SFD_NODE_ARGS:-}"
  echo "hil:  ${SFD_HIL_PREFIX:-} $bin/sfd-hil $* --lcm-url $url --csv $out/hil.csv --png $out/hil.png"
  echo "host: $(uname -srm), $(nproc) CPUs, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
} > "$out/cmd.txt"
rc=0
# shellcheck disable=SC2086
${SFD_HIL_PREFIX:-} "$bin/sfd-hil" "$@" --lcm-url "$url" --csv "$out/hil.csv" --png "$out/hil.png" \
  > "$out/report.txt" 2>&1 || rc=$?
node_rc=0
kill -INT "$node" 2>/dev/null || true
wait "$node" || node_rc=$?
cat "$out/report.txt"
echo
grep '^sfd-node: \(stopped\|publish\|rejected\|heap\)' "$out/node.txt" || true
if [ "$node_rc" -ne 0 ]; then echo "hil_bench: sfd-node exited $node_rc" >&2; exit 1; fi
exit "$rc"
