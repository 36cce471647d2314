#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.oracle_poses: sfd-replay --oracle-poses (parity's filter-path test with TRUTH's
# poses in place of the window filter; apps/common/sfd_pose_oracle.hpp):
#  - on a clean flight (sfd-sim mistracking --outlier-ratio 0, 400 frames) the oracle flags a
#    clean feature with probability at most alpha (the 99 % binomial interval over a third of the
#    tests, as integration.clean_false_alarms): a wrong pose convention (a transposed rotation,
#    the IMU's pose used as the camera's) flags most features;
#  - on a flight with spurious tracks (200 frames) it judges every frame, never through the
#    unknown-translation fallback (its window is accepted as the filter's), and scores at least
#    the product's parity (F1 within 0.02 of it or above: it has the poses exactly);
#  - bad usage is exit 2: with -o, with --score-only, with a method other than parity;
#  - tools/strip_spurious.py (the input a perfect detector leaves the filter) removes exactly the
#    labelled features: replayed, none of them gets a verdict and every clean one is judged;
#    with --frame-stride 2 it keeps the 1st, 3rd, ... frame and their TRUTH (100 of 200 frames,
#    each judged, their clean features all there), and refuses a stride of 0 (exit 2).
# usage: oracle_poses.sh BUILD_DIR SOURCE_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; src="$2"; py="$3"; pytypes="$4"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cfg="$src/apps/config/sfd.yaml"
replay="$build/apps/sfd-replay"

"$build/apps/sfd-sim" mistracking -o "$tmp/clean.lcmlog" --frames 400 --seed 3 \
  --outlier-ratio 0 >/dev/null
"$replay" "$tmp/clean.lcmlog" --config "$cfg" --oracle-poses --summary "$tmp/clean.json" >/dev/null
"$build/apps/sfd-sim" mistracking -o "$tmp/faults.lcmlog" --frames 200 --seed 1 >/dev/null
"$replay" "$tmp/faults.lcmlog" --config "$cfg" --oracle-poses --summary "$tmp/oracle.json" \
  >/dev/null
"$replay" "$tmp/faults.lcmlog" --config "$cfg" --method parity --summary "$tmp/parity.json" \
  >/dev/null

python3 - "$tmp" <<'PYEOF'
import json, math, sys
tmp = sys.argv[1]
clean = json.load(open(tmp + "/clean.json"))
d = clean["detection"]
alpha = 0.01
tested = d["fp"] + d["tn"]
rate = d["fp"] / tested
half = 2.576 * math.sqrt(alpha * (1 - alpha) / (tested / 3))
print(f"clean flight: oracle flags {d['fp']} of {tested} clean tests, rate {rate:.4f} "
      f"(at most {alpha + half:.4f})")
assert clean["method"] == "parity-oracle" and clean["filter_start"] == "oracle", clean
assert d["spurious"] == 0 and tested > 20000, d
assert rate <= alpha + half, rate
o = json.load(open(tmp + "/oracle.json"))
p = json.load(open(tmp + "/parity.json"))
print(f"faults: oracle F1 {o['detection']['f1']:.4f} (recall {o['detection']['recall']:.4f}), "
      f"product parity F1 {p['detection']['f1']:.4f}; oracle {o['oracle']}")
assert o["oracle"]["judged"] == 200 and o["oracle"]["fallbacks"] == 0, o["oracle"]
assert o["oracle"]["without_truth"] == 0 and o["oracle"]["refused"] == 0, o["oracle"]
assert o["oracle"]["failed"] == 0, o["oracle"]
assert o["frames"]["processed"] == 200 and o["trajectory"] is None, o
assert o["detection"]["f1"] >= p["detection"]["f1"] - 0.02, (o["detection"], p["detection"])
PYEOF

expect_2() { # DESCRIPTION ARGS...
  local what="$1"; shift
  local rc=0
  "$replay" "$tmp/faults.lcmlog" --config "$cfg" "$@" >"$tmp/out.txt" 2>"$tmp/err.txt" || rc=$?
  [ "$rc" -eq 2 ] || { echo "$what: exit $rc, want 2" >&2; cat "$tmp/err.txt" >&2; exit 1; }
  [ "$(wc -l <"$tmp/err.txt")" -eq 1 ] || { echo "$what: not one line" >&2; exit 1; }
  echo "$what: exit 2: $(cat "$tmp/err.txt")"
}
expect_2 "with -o" --oracle-poses -o "$tmp/o.lcmlog"
expect_2 "with --score-only" --oracle-poses --score-only
expect_2 "with method both" --oracle-poses --method both
expect_2 "with translation_known 0" --oracle-poses --translation-known 0
[ ! -e "$tmp/o.lcmlog" ] || { echo "-o written" >&2; exit 1; }

PYTHONPATH="$pytypes" "$py" "$src/tools/strip_spurious.py" "$tmp/faults.lcmlog" \
  "$tmp/stripped.lcmlog"
"$replay" "$tmp/stripped.lcmlog" --config "$cfg" --method none --summary "$tmp/stripped.json" \
  >/dev/null
python3 - "$tmp" <<'PYEOF'
import json, sys
tmp = sys.argv[1]
a = json.load(open(tmp + "/parity.json"))["detection"]
s = json.load(open(tmp + "/stripped.json"))["detection"]
print(f"stripped: {s['spurious']} labelled spurious, {s['untested_spurious']} without a verdict; "
      f"clean {s['clean']}, judged {s['tn'] + s['fp']}")
assert s["spurious"] == a["spurious"] > 0 and s["untested_spurious"] == s["spurious"], s
# method none judges every feature it gets CONSISTENT: every clean one is still there
assert s["clean"] == a["clean"] and s["tn"] == s["clean"] and s["untested_clean"] == 0, (s, a)
PYEOF

PYTHONPATH="$pytypes" "$py" "$src/tools/strip_spurious.py" "$tmp/faults.lcmlog" \
  "$tmp/stride2.lcmlog" --frame-stride 2 | tee "$tmp/stride2.txt"
grep -q ", 100 of 200 frames left out$" "$tmp/stride2.txt" || { echo "stride 2: count" >&2; exit 1; }
"$replay" "$tmp/stride2.lcmlog" --config "$cfg" --method none --summary "$tmp/stride2.json" \
  >/dev/null
PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import json, sys
import lcm
from sfd import feature_frame_t, truth_t
tmp = sys.argv[1]
def times(path, channel, t):
    return [t.decode(e.data).utime for e in lcm.EventLog(path, "r") if e.channel == channel]
full = times(tmp + "/faults.lcmlog", "FEATURES", feature_frame_t)
kept = times(tmp + "/stride2.lcmlog", "FEATURES", feature_frame_t)
assert kept == full[::2] and len(kept) == 100, (len(full), len(kept))
assert times(tmp + "/stride2.lcmlog", "TRUTH", truth_t) == kept
def count(path, channel):
    return sum(1 for e in lcm.EventLog(path, "r") if e.channel == channel)
for ch in ("IMU", "CAMERA_INFO"):
    assert count(tmp + "/stride2.lcmlog", ch) == count(tmp + "/faults.lcmlog", ch) > 0, ch
j = json.load(open(tmp + "/stride2.json"))
s = j["detection"]
assert j["frames"]["processed"] == 100 and j["truth"]["frames"] == 100, j
assert s["untested_spurious"] == s["spurious"] > 0 and s["tn"] == s["clean"] > 0, s
assert s["untested_clean"] == 0, s
print(f"stride 2: {len(kept)} of {len(full)} frames, {s['clean']} clean features judged")
PYEOF
rc=0
PYTHONPATH="$pytypes" "$py" "$src/tools/strip_spurious.py" "$tmp/faults.lcmlog" \
  "$tmp/stride0.lcmlog" --frame-stride 0 2>"$tmp/stride0.err" || rc=$?
[ "$rc" -eq 2 ] && [ ! -e "$tmp/stride0.lcmlog" ] && [ "$(wc -l <"$tmp/stride0.err")" -eq 1 ] || {
  echo "stride 0: exit $rc, want 2 with one line and no output" >&2; cat "$tmp/stride0.err" >&2
  exit 1
}
echo "oracle_poses: ok"
