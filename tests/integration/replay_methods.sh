#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.replay_methods: every method of sfd-replay (none, parity, oprf, ransac1, ransacf,
# both) runs the node's filter path on one sfd-sim log with TRUTH (the filter started from TRUTH,
# filter.init_from_truth) and:
#  - each summary holds the scores (strict recall) and a position RMSE over every frame after the
#    start;
#  - oprf twice gives byte-identical OUT and summary (seeded hypotheses);
#  - OUT holds one SFD_STATE per judged frame, decodable with LCM's Python types;
#  - with 15% mistracked features and one depth prior per track, oprf, ransac1 and both keep the
#    position closer to TRUTH than no association (none), and find most of the jumps they test (strict jump recall above 0.4,
#    tested recall over all kinds above 0.4).
# usage: replay_methods.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$build/apps/sfd-sim" mistracking -o "$tmp/in.lcmlog" --frames 120 --features 120 --seed 5 \
  --outlier-ratio 0.15 --jump-px 12 >/dev/null
# One depth prior per track (filter.window_depth_priors: 1): sfd-sim's depths are exact, and with
# the first and the newest prior (the default, 2) the window filter's own gate refuses most
# jumped tracks here, so the comparison below would measure the gate rather than the association:
# on this log the default gives none 0.034 m, both 0.045 m, oprf 0.030 m (with 1: 0.107, 0.087,
# 0.052 m; docs/evaluation.md "Two depth priors per track"; measured since a flagged track's
# earlier observations pass the gate, 2026-11-27; before it 0.047 / 0.025 and 0.085 / 0.055 m).
printf '%%YAML:1.0\n---\nfilter:\n   init_from_truth: 1\n   window_depth_priors: 1\n' > "$tmp/cfg.yaml"
for m in none parity oprf ransac1 ransacf both; do
  "$build/apps/sfd-replay" "$tmp/in.lcmlog" --config "$tmp/cfg.yaml" --method "$m" \
    -o "$tmp/$m.lcmlog" --summary "$tmp/$m.json" >/dev/null
done
"$build/apps/sfd-replay" "$tmp/in.lcmlog" --config "$tmp/cfg.yaml" --method oprf \
  -o "$tmp/oprf2.lcmlog" --summary "$tmp/oprf2.json" >/dev/null
cmp "$tmp/oprf.lcmlog" "$tmp/oprf2.lcmlog"
cmp "$tmp/oprf.json" "$tmp/oprf2.json"
PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import json, sys, collections
import lcm
from sfd import nav_state_t
d = sys.argv[1]
summ = {m: json.load(open(f"{d}/{m}.json")) for m in
        ["none", "parity", "oprf", "ransac1", "ransacf", "both"]}
s = {}
for m, j in summ.items():
    assert j["method"] == m and j["filter_start"] == "truth", j
    v, tr = j["detection"], j["trajectory"]
    assert tr["frames"] >= 110, (m, tr)
    v["rmse"] = tr["rmse_raw_m"]  # the filter starts from TRUTH: the unaligned error
    s[m] = v
    print(f"{m:8s} precision {v['precision'] or 0:.3f} recall {v['recall']:.3f} f1 {v['f1']:.3f} "
          f"far {v['false_alarm_rate']:.4f} coverage {v['coverage']:.3f} rmse {v['rmse']:.3f} m")
for m in ["oprf", "ransac1", "both"]:
    assert s[m]["rmse"] < s["none"]["rmse"], (m, s[m], s["none"])
    # Since sfd-sim's tracker fault model (apps/sim/SIMULATION.md: a third each of jumps 5-30 px,
    # drifts 0.3-2 px/frame, one-frame mismatches 15-60 px) replaced the constant 12 px jumps, the
    # slow drifts are rarely found (tested recall ~0.15 for the frame-to-frame methods) and pull
    # the overall recall down: the check is on the jumps, which play the old fault's part. A jump
    # labels two frames (the two 3-frame windows that straddle it). A frame-to-frame method
    # (OPRF, RANSAC1) finds the first; a flagged track's landmark is then anchored again at the
    # jumped observation, so the second is tested against the point the track now follows and is
    # judged consistent (before, it was left UNTESTED): it finds about half of the tested jump
    # labels. Parity's windows (in both) find both frames.
    j = s[m]["by_kind"]["jump"]
    share = 0.8 if m == "both" else 0.45
    assert j["detected"] > share * (j["spurious"] - j["untested"]), (m, j)
    # Tested recall over all kinds: 0.38 for oprf since its noise is carried through the
    # distortion Jacobian (issue 17 item 4): its false alarms fell from 2.2 % to 0.5 % and with
    # them the slow drifts it "found" at the image edges (drift recall 0.051 -> 0.036; tested
    # recall 0.402 -> 0.395, jump recall unchanged at 0.49).
    floor = 0.38 if m == "oprf" else 0.4
    assert j["recall"] > 0.4 and s[m]["recall_tested"] > floor, (m, s[m])
c = collections.Counter()
for ev in lcm.EventLog(f"{d}/oprf.lcmlog", "r"):
    c[ev.channel] += 1
    if ev.channel == "SFD_STATE":
        st = nav_state_t.decode(ev.data)
        assert all(v == v for v in st.position), st.position
assert c["SFD_STATE"] >= 110 and c["SFD_STATE"] <= c["SFD_VERDICT"], c
print("replay methods: summaries, SFD_STATE and determinism checked")
PYEOF
