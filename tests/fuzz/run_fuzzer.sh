#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# CTest fuzz.<target>: fuzzes a fresh copy of the seed corpus for a bounded time with a fixed
# seed; fails on any crash, sanitizer report, violated invariant (abort), leak, timeout (a single
# input over 10 s: the flight code must run in bounded time) or RSS over 2 GiB.
# Usage: run_fuzzer.sh FUZZER SEEDS_DIR WORK_DIR SECONDS MAX_LEN [DICT] (libFuzzer -dict)
set -euo pipefail
fuzzer="$1"; seeds="$2"; work="$3"; seconds="$4"; max_len="$5"; dict="${6:-}"
dict_opt=()
if [ -n "$dict" ]; then
  if [ ! -s "$dict" ]; then echo "no dictionary at $dict (build the fuzz preset first)"; exit 1; fi
  dict_opt=(-dict="$dict")
fi
if [ ! -d "$seeds" ]; then echo "no seed corpus at $seeds (build the fuzz preset first)"; exit 1; fi
rm -rf "$work"
mkdir -p "$work/corpus" "$work/artifacts"
cp "$seeds"/* "$work/corpus/"
cd "$work"
set +e
"$fuzzer" -seed=1 -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len="$max_len" \
  "${dict_opt[@]}" \
  -print_final_stats=1 -artifact_prefix="$work/artifacts/" corpus > fuzz.log 2>&1
rc=$?
set -e
grep -E '^(#[0-9]+.*DONE|stat::number_of_executed_units|stat::average_exec_per_sec|stat::new_units_added|stat::peak_rss_mb|Done [0-9]+ runs)' fuzz.log || true
if [ "$rc" -ne 0 ]; then
  tail -60 fuzz.log
  echo "fuzzer $(basename "$fuzzer") failed (exit $rc); reproducer(s) in $work/artifacts:"
  ls -l "$work/artifacts"
  exit 1
fi
echo "fuzzer $(basename "$fuzzer"): no crash in ${seconds} s ($(ls corpus | wc -l) corpus inputs)"
