#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.remembered_point: tools/remembered_point.py on a short mistracking flight replayed
# with method both. With true poses the test of a clean observation against its remembered point
# is calibrated: mean NIS within [1.6, 2.5] (2 for chi-square with 2 dof; 4 241 samples, 2.07 on
# 2026-11-29); the replay's line reproduces sfd-replay's own score; the
# added flags never remove a true positive; unreadable logs exit 2.
# usage: remembered_point.sh SOURCE_DIR BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
src="$1"; build="$2"; py="$3"; pytypes="$4"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
apps="$build/apps"
"$apps/sfd-sim" mistracking --seed 3 --frames 120 --features 60 -o "$tmp/in.lcmlog" > /dev/null
"$apps/sfd-replay" "$tmp/in.lcmlog" --config "$src/apps/config/sfd.yaml" --method both \
  -o "$tmp/out.lcmlog" --summary "$tmp/sum.json" > /dev/null
out="$(PYTHONPATH="$pytypes" "$py" "$src/tools/remembered_point.py" "$tmp/in.lcmlog" \
  "$tmp/out.lcmlog" --sigma-px 1 --alpha 0.01)"
echo "$out"
PYTHONPATH="$pytypes" "$py" - "$tmp/sum.json" <<PYEOF || fail "inconsistent with the replay: $out"
import json, re, sys
out = """$out"""
s = json.load(open(sys.argv[1]))
n, mean = map(float, re.search(r"point: (\d+) of \d+, mean NIS ([0-9.]+)", out).groups())
assert n >= 500, n
assert 1.6 <= mean <= 2.5, mean
tp, fp, f1 = re.search(r"replay: TP (\d+), FP (\d+), spurious \d+, F1 ([0-9.]+)", out).groups()
tp2, fp2 = re.search(r"\+ remembered point .*: TP (\d+), FP (\d+)", out).groups()
d = s["detection"]
assert (int(tp), int(fp)) == (d["tp"], d["fp"]), (tp, fp, d["tp"], d["fp"])
assert abs(float(f1) - d["f1"]) < 1e-4, (f1, d["f1"])
assert int(tp2) >= int(tp) and int(fp2) >= int(fp)
PYEOF
echo "ok: calibrated on clean observations, the replay's score reproduced"
set +e
PYTHONPATH="$pytypes" "$py" "$src/tools/remembered_point.py" /nonexistent "$tmp/out.lcmlog" \
  --sigma-px 1 > /dev/null 2> "$tmp/err"; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "cannot read the logs" "$tmp/err" || fail "missing log: exit $rc"
echo "ok: a missing log exits 2"
