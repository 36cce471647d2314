#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# tools.evaluate_quick: tools/evaluate.py's quick preset on a Dask LocalCluster (2 workers), then
# serially, and checks: the deterministic columns (all but time_*) of every row
# are equal, the expected rows are there, summary.md and the three PNGs are written, the CSV holds
# sfd-replay's own numbers (one JSON re-read), bad usage exits 2 and a failing run exits 1; a
# sweep whose grid has no alpha (here the alarm hold's) writes its rows and plots too (it
# crashed in the precision-recall plot before).
# Usage: evaluate_quick.sh BUILD_DIR PYTHON
set -euo pipefail
build="$(cd "$1" && pwd)"
py="$2"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
ev=("$py" "$root/tools/evaluate.py" --build "$build")

"$py" -c 'import distributed, matplotlib' || {
  echo "evaluate_quick: $py lacks dask.distributed or matplotlib" \
    "(tools/setup.sh installs tools/requirements.txt)" >&2
  exit 1
}

t0=$(date +%s)
"${ev[@]}" --preset quick --workers 2 --out "$tmp/dask" >"$tmp/dask.txt"
t1=$(date +%s)
"${ev[@]}" --preset quick --serial --out "$tmp/serial" >"$tmp/serial.txt"
t2=$(date +%s)
echo "quick preset: Dask (2 workers) $((t1 - t0)) s, serial $((t2 - t1)) s"
grep -q '^| both |' "$tmp/dask.txt" || { echo "no summary table on stdout" >&2; exit 1; }

rc=0
"${ev[@]}" --serial --methods bogus --out "$tmp/bad" >/dev/null 2>&1 || rc=$?
[ "$rc" -eq 2 ] || { echo "bad usage: exit $rc, want 2" >&2; exit 1; }
rc=0
"${ev[@]}" --serial --scenarios mistracking --seeds 1 --methods parity --frames 40 --alpha 0.9 \
  --out "$tmp/fail" >/dev/null 2>"$tmp/fail.err" || rc=$?
[ "$rc" -eq 1 ] || { echo "failing run: exit $rc, want 1" >&2; exit 1; }
grep -q 'FAILED.*sfd-replay.*--false-alarm-rate 0.9' "$tmp/fail.err" || {
  echo "failure not reported" >&2
  cat "$tmp/fail.err" >&2
  exit 1
}

"${ev[@]}" --serial --scenarios mistracking --seeds 1 --methods parity --frames 40 \
  --grid hold=1,0.3 --out "$tmp/hold" >/dev/null
for f in results.csv summary.md pr_curves.png ate.png kind_recall.png; do
  [ -s "$tmp/hold/$f" ] || { echo "sweep without alpha: no $f" >&2; exit 1; }
done
[ "$(wc -l <"$tmp/hold/results.csv")" -eq 3 ] || { echo "sweep without alpha: rows" >&2; exit 1; }

"$py" - "$tmp" <<'PY'
import csv, json, math, os, sys
tmp = sys.argv[1]
def load(d):
    with open(os.path.join(tmp, d, "results.csv")) as f:
        rows = list(csv.DictReader(f))
    return rows, {(r["scenario"], r["seed"], r["method"], r["alpha"]): r for r in rows}
dask_rows, dask = load("dask")
serial_rows, serial = load("serial")
methods = ["none", "parity", "oprf", "ransac1", "ransacf", "both", "parity-oracle"]
want = {(s, str(seed), m, a) for s in ("mistracking", "moving-object") for seed in (1, 2)
        for m in methods for a in ("0.01", "0.1")}
assert set(dask) == want and len(dask_rows) == len(want), sorted(set(dask) ^ want)
assert set(serial) == want and len(serial_rows) == len(want)
cols = [c for c in dask_rows[0] if not c.startswith("time_")]
assert "f1" in cols and "ate_m" in cols and "time_frame_median_us" in dask_rows[0]
diff = [(k, c) for k in serial for c in cols if serial[k][c] != dask[k][c]]
assert not diff, "Dask and serial differ: %s" % diff[:5]
# The rows come sorted by (scenario, seed, method, alpha): the same order, line for line.
assert [[r[c] for c in cols] for r in dask_rows] == [[r[c] for c in cols] for r in serial_rows]
for r in dask_rows:
    assert r["filter_start"] == ("oracle" if r["method"] == "parity-oracle" else "rest"), r
    assert int(r["frames_processed"]) == 200 and int(r["labelled"]) > 0, r
    assert r["method"] == "none" or float(r["f1"]) > 0, r
for f in ("summary.md", "pr_curves.png", "ate.png", "kind_recall.png", "commands.log"):
    p = os.path.join(tmp, "dask", f)
    assert os.path.isfile(p) and os.path.getsize(p) > 0, p
md = open(os.path.join(tmp, "dask", "summary.md")).read()
assert "## mistracking" in md and "## moving-object" in md and "| both |" in md
# The CSV holds sfd-replay's numbers: re-read one JSON.
r = dask[("moving-object", "2", "both", "0.01")]
s = json.load(open(os.path.join(tmp, "dask", r["json"])))
d, t = s["detection"], s["trajectory"]
assert s["method"] == "both"
for c, v in (("tp", d["tp"]), ("fp", d["fp"]), ("untested_spurious", d["untested_spurious"]),
             ("f1", d["f1"]), ("recall", d["recall"]), ("precision", d["precision"]),
             ("moving_recall", d["by_kind"]["moving"]["recall"]), ("ate_m", t["ate_m"]),
             ("drift_percent", t["drift_percent"]), ("rpe_10m_mean_m", t["rpe_10m"]["mean_m"])):
    assert float(r[c]) == v, (c, r[c], v)
tm = json.load(open(os.path.join(tmp, "dask", r["json"]) + ".timing.json"))
assert float(r["time_frame_median_us"]) == tm["frame_us"]["median"]
print("evaluate_quick: %d Dask rows, %d serial rows equal on %d deterministic columns" %
      (len(dask_rows), len(serial_rows), len(cols)))
PY
echo "tools.evaluate_quick: ok ($(( $(date +%s) - t0 )) s)"
