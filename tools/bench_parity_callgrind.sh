#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Instructions per frame of sfd_parity_push_frame (callgrind, inclusive, only that function
# collected), for the sfd-bench parity grid. Instruction counts are repeatable on a noisy machine,
# unlike wall time. Usage: tools/bench_parity_callgrind.sh [BUILD_DIR] [FRAMES]
set -euo pipefail
build="${1:-build/host}"
frames="${2:-50}"
bench="$build/apps/sfd-bench"
[ -x "$bench" ] || { echo "bench_parity_callgrind.sh: $bench not built" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "bench_parity_callgrind.sh: valgrind missing (tools/setup.sh)" >&2; exit 2; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
echo "| N | L | n | translation | instructions per frame |"
echo "|---|---|---|---|---|"
for N in 50 100 200 500; do
  for L in 2 3 5; do
    for n in 3 4; do
      for known in 0 1; do
        out="$tmp/cg.$N.$L.$n.$known"
        valgrind --tool=callgrind --callgrind-out-file="$out" --toggle-collect=sfd_parity_push_frame \
          "$bench" parity --single --features "$N" --window-frames "$L" --group-size "$n" --translation-known "$known" --frames "$frames" >/dev/null 2>&1
        total="$(grep -E '^summary:' "$out" | awk '{print $2}')"
        calls=$((frames + L))
        tr=$([ "$known" = 1 ] && echo known || echo unknown)
        echo "| $N | $L | $n | $tr | $((total / calls)) |"
      done
    done
  done
done
