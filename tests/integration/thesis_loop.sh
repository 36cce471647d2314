#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.thesis_loop: `sfd-sim thesis-loop --quick` (Kilic 2014 Chapter IV, EKF loop) twice;
# the RMSE CSVs must be byte-identical (timing lives in a separate CSV); with 0% mismatches OPRF's
# position RMSE must be within 20% of no association's (OPRF must not throw away good data), and
# with 30% mismatches OPRF's RMSE must be below no association's.
# usage: thesis_loop.sh BUILD_DIR
set -euo pipefail
build="$1"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/a" "$tmp/b"
"$build/apps/sfd-sim" thesis-loop --quick --csv-dir "$tmp/a" >"$tmp/a.txt"
"$build/apps/sfd-sim" thesis-loop --quick --csv-dir "$tmp/b" >/dev/null
cmp "$tmp/a/thesis_rmse.csv" "$tmp/b/thesis_rmse.csv"
echo "thesis_rmse.csv byte-identical over two runs ($(grep -vc '^#' "$tmp/a/thesis_rmse.csv") lines)"
for f in thesis_rmse.csv thesis_time.csv; do
  [ "$(grep -vc '^#' "$tmp/a/$f")" -eq 25 ] || { echo "FAIL: $f: expected 24 rows + header"; exit 1; }
done
grep -q '^| 30 |' "$tmp/a.txt" || { echo "FAIL: no 30% row in the printed table"; exit 1; }
# rmse_m of the mismatch sweep at LEVEL for METHOD
rmse() {
  awk -F, -v lvl="$1" -v m="$2" '!/^#/ && $1 == "mismatch" && $2 == lvl && $9 == m { print $12 }' \
    "$tmp/a/thesis_rmse.csv"
}
o0="$(rmse 0 OPRF)"; n0="$(rmse 0 NONE)"; o30="$(rmse 30 OPRF)"; n30="$(rmse 30 NONE)"
for v in "$o0" "$n0" "$o30" "$n30"; do
  [ -n "$v" ] || { echo "FAIL: a mismatch-sweep RMSE is missing from thesis_rmse.csv"; exit 1; }
done
echo "mismatch 0%: OPRF ${o0} m, NONE ${n0} m; mismatch 30%: OPRF ${o30} m, NONE ${n30} m"
awk -v o="$o0" -v n="$n0" 'BEGIN { r = o / n; if (!(r >= 0.8 && r <= 1.2)) {
  printf "FAIL: 0%% mismatches: OPRF/NONE RMSE ratio %.4f outside [0.8, 1.2]\n", r; exit 1 } }'
awk -v o="$o30" -v n="$n30" 'BEGIN { if (!(o < n)) {
  printf "FAIL: 30%% mismatches: OPRF RMSE %g not below NONE %g\n", o, n; exit 1 } }'
echo "thesis-loop checks passed"
