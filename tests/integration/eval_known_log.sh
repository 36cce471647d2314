#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.eval_known_log: a hand-built log whose scores are known, scored by sfd-replay
# --score-only (no node: the SFD_VERDICT and SFD_STATE in the log are what is judged):
#  - 4 frames of TRUTH with kinds (jump, drift, moving, mismatch, clean) and verdicts chosen so
#    that the strict recall (UNTESTED spurious = miss, a frame without verdict = untested) and the
#    lenient one differ: every count, score and per-kind recall equals the hand count;
#  - SFD_STATE poses are the truth seen from another frame (yaw 0.9 rad, a translation): the ATE
#    after the position+yaw alignment is 0 while the raw RMSE is the offset;
#  - an input file name with quotes and a backslash stays valid JSON.
# usage: eval_known_log.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
log="$tmp/known \"quoted\" \\ log.lcmlog"
PYTHONPATH="$pytypes" "$py" - "$log" <<'PYEOF'
import math, sys
import lcm
from sfd import truth_t, feature_verdict_t, nav_state_t
CLEAN, JUMP, DRIFT, MOVING, MISMATCH = 0, 1, 2, 3, 4
UNTESTED, CONSISTENT, SPURIOUS = 0, 1, 2
log = lcm.EventLog(sys.argv[1], "w", overwrite=True)
# frame: (truth [(id, kind)], verdict [(id, status)] or None for a frame without a verdict)
frames = [
    ([(1, JUMP), (2, CLEAN), (3, CLEAN), (4, MOVING)],
     [(1, SPURIOUS), (2, CONSISTENT), (3, SPURIOUS), (4, UNTESTED)]),
    ([(1, JUMP), (2, CLEAN), (3, CLEAN), (4, MOVING), (5, DRIFT)],
     [(1, UNTESTED), (2, CONSISTENT), (3, CONSISTENT), (4, SPURIOUS), (5, CONSISTENT),
      (77, SPURIOUS)]),                        # 77: not labelled, not scored
    ([(2, CLEAN), (5, DRIFT), (6, MISMATCH)], None),   # no verdict: all untested
    ([(2, CLEAN), (3, CLEAN), (5, DRIFT), (6, MISMATCH)],
     [(2, SPURIOUS), (3, CONSISTENT), (6, SPURIOUS)]),  # 5 missing from the verdict: untested
]
psi, off = 0.9, (3.0, -2.0, 0.5)
c, s = math.cos(psi), math.sin(psi)
for i, (tr_list, ver) in enumerate(frames):
    t = 1_000_000 + i * 50_000
    x, y, z = 2.0 * i, 1.0 * i * i, 0.1 * i          # truth position (horizontal spread)
    yaw = 0.2 * i
    tr = truth_t()
    tr.utime = t
    tr.position = [x, y, z]
    tr.orientation = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    tr.num_features = len(tr_list)
    tr.track_id = [k for k, _ in tr_list] + [0] * (512 - len(tr_list))
    tr.spurious = [int(kd != CLEAN) for _, kd in tr_list] + [0] * (512 - len(tr_list))
    tr.kind = [kd for _, kd in tr_list] + [0] * (512 - len(tr_list))
    log.write_event(t, "TRUTH", tr.encode())
    if ver is not None:
        v = feature_verdict_t()
        v.utime = t
        v.num_features = len(ver)
        pad = [0] * (512 - len(ver))
        v.track_id = [k for k, _ in ver] + pad
        v.status = [st for _, st in ver] + pad
        log.write_event(t, "SFD_VERDICT", v.encode())
    st = nav_state_t()
    st.utime = t
    d = (x - off[0], y - off[1], z - off[2])          # x_e = R_z(-psi)(x_g - off)
    st.position = [c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]]
    st.velocity = [0.0, 0.0, 0.0]
    ye = yaw - psi
    st.orientation = [math.cos(ye / 2), 0.0, 0.0, math.sin(ye / 2)]
    st.position_var = [0.01, 0.01, 0.01]
    log.write_event(t, "SFD_STATE", st.encode())
log.close()
PYEOF
"$build/apps/sfd-replay" "$log" --score-only --summary "$tmp/s.json"
"$py" - "$tmp/s.json" "$log" <<'PYEOF'
import json, math, sys
s = json.load(open(sys.argv[1]))
assert s["input"] == sys.argv[2], s["input"]
d = s["detection"]
# Hand count (frame: track). Spurious (9): f0 1 TP, 4 untested; f1 1 untested, 4 TP, 5 FN; f2 5
# and 6 untested (no verdict); f3 5 untested (missing from the verdict), 6 TP. Clean (7): f0 2 TN,
# 3 FP; f1 2 TN, 3 TN; f2 2 untested; f3 2 FP, 3 TN.
want = {"labelled": 16, "spurious": 9, "clean": 7, "tp": 3, "fp": 2, "tn": 4, "fn": 1,
        "untested_spurious": 5, "untested_clean": 1}
for k, v in want.items():
    assert d[k] == v, (k, d[k], v)
close = lambda a, b: abs(a - b) < 1e-12
assert close(d["recall"], 3 / 9) and close(d["recall_tested"], 3 / 4), d   # strict vs lenient
assert close(d["precision"], 3 / 5) and close(d["f1"], 6 / (6 + 2 + 1 + 5)), d
assert close(d["false_alarm_rate"], 2 / 7) and close(d["false_alarm_rate_tested"], 2 / 6), d
assert close(d["coverage"], 10 / 16), d
k = d["by_kind"]
# Fault events (one per track here): jump 1 caught in its first frame (f0), moving 4 in its
# second (f1), drift 5 never, mismatch 6 in its second (f3).
caught = lambda c1, c3: {"events": 1, "caught_1": c1, "caught_3": c3, "caught_5": c3,
                         "caught_10": c3}
assert k["jump"] == {"spurious": 2, "detected": 1, "untested": 1, "recall": 0.5,
                     **caught(1.0, 1.0)}, k["jump"]
assert k["moving"] == {"spurious": 2, "detected": 1, "untested": 1, "recall": 0.5,
                       **caught(0.0, 1.0)}, k["moving"]
assert k["drift"] == {"spurious": 3, "detected": 0, "untested": 2, "recall": 0.0,
                      **caught(0.0, 0.0)}, k["drift"]
assert k["mismatch"] == {"spurious": 2, "detected": 1, "untested": 1, "recall": 0.5,
                         **caught(0.0, 1.0)}, k
assert k["unspecified"]["spurious"] == 0 and k["unspecified"]["recall"] is None, k
assert k["unspecified"]["events"] == 0 and k["unspecified"]["caught_10"] is None, k
t = s["trajectory"]
assert t["frames"] == 4 and t["ate_m"] < 1e-9, t
assert abs(t["align_yaw_rad"] - 0.9) < 1e-9, t
assert t["rmse_raw_m"] > 1.0 and t["final_error_m"] < 1e-9, t
print("eval known log: counts, strict/lenient recall, kinds, ATE and JSON quoting as hand-counted")
PYEOF
