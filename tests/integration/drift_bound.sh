#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.drift_bound: tools/drift_bound.py's ceilings on cases whose answer is known.
#  - no slide (--rate-px 0 0): every detector flags a label with probability alpha exactly;
#  - a slide far above the noise: every detector flags every label;
#  - the sim's slides: oracle >= known-start >= window-5 >= single > remembered (each knows
#    less);
#  - the F1 substitution on a hand-made results.csv: measured F1 reproduced, and with drift
#    recall 1 (a large slide) the F1 of the hand count;
#  - a sim source without the constants, or a results file without the columns: exit 2.
# usage: drift_bound.sh SOURCE_DIR PYTHON
set -euo pipefail
src="$1"; py="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
tool="$src/tools/drift_bound.py"
fail() { echo "FAIL: $*" >&2; exit 1; }
ceiling() {  # ceiling NAME OUTPUT: the detector's recall from the tool's table
  awk -F'|' -v n="$1" '$2 ~ "^ " n " $" {gsub(/ /, "", $3); print $3}' <<< "$2"
}

out="$("$py" "$tool" --rate-px 0 0 --events 500)"
for d in oracle known-start window-5 single remembered; do
  [ "$(ceiling "$d" "$out")" = "0.010" ] || fail "no slide: $d $(ceiling "$d" "$out"), want 0.010"
done
out="$("$py" "$tool" --rate-px 40 40 --events 500 --alpha 0.001)"
for d in oracle known-start window-5 single remembered; do
  [ "$(ceiling "$d" "$out")" = "1.000" ] || fail "large slide: $d $(ceiling "$d" "$out")"
done
echo "ok: alpha with no slide, 1 with a large one"

out="$("$py" "$tool" --events 4000)"
"$py" - "$(ceiling oracle "$out")" "$(ceiling known-start "$out")" \
  "$(ceiling window-5 "$out")" "$(ceiling single "$out")" "$(ceiling remembered "$out")" \
  <<'PYEOF' || fail "order: $out"
import sys
o, k, w, s, r = map(float, sys.argv[1:])
assert 0.5 < r < s <= w <= k <= o < 1.0, (o, k, w, s, r)
PYEOF
echo "ok: the sim's slides, $(ceiling oracle "$out") >= ... >= $(ceiling remembered "$out")"

# One run: 100 spurious of which 40 drift (10 caught), 60 others (50 caught), 20 false alarms.
# Measured F1 = 2*60/(2*60+20+40) = 0.667; with every drift caught 2*90/(2*90+20+10) = 0.857.
cat > "$tmp/results.csv" <<'CSV'
scenario,seed,method,alpha,tp,fp,spurious,f1,drift_spurious,drift_detected
mistracking,1,both,0.01,60,20,100,0.6666666666666666,40,10
mistracking,1,parity,0.01,0,0,100,0,40,0
CSV
out="$("$py" "$tool" --rate-px 40 40 --events 200 --alpha 0.01 --results "$tmp/results.csv")"
grep -q "^| mistracking | 1 | 0.250 | 0.667 | 0.857 | 0.857 | 0.857 | 0.857 | 0.857 |$" <<< "$out" ||
  fail "F1 substitution: $out"
echo "ok: F1 substitution"

sed 's/0.6666666666666666/0.7/' "$tmp/results.csv" > "$tmp/bad.csv"
set +e
"$py" "$tool" --results "$tmp/bad.csv" > /dev/null 2> "$tmp/err"; rc=$?
[ "$rc" = 2 ] && grep -q "is not 2TP/(2TP+FP+FN)" "$tmp/err" || fail "inconsistent F1: exit $rc"
echo "a,b" > "$tmp/cols.csv"
"$py" "$tool" --results "$tmp/cols.csv" > /dev/null 2> "$tmp/err"; rc=$?
[ "$rc" = 2 ] && grep -q "not a tools/evaluate.py results.csv" "$tmp/err" || fail "columns: exit $rc"
"$py" "$tool" --sim-source "$tmp" 2> "$tmp/err"; rc=$?
[ "$rc" = 2 ] && grep -q "flight_log.cpp" "$tmp/err" || fail "no sim source: exit $rc"
set -e
echo "ok: bad inputs exit 2"
