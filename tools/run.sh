#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# README command (1): set up, build, and run the main job on its built-in default, a simulated
# flight: the paper's UAV scenario through the parity-space detector (sfd-sim paper-uav), the
# isolation comparison on a simulated flight with mistracks (sfd-sim isolation), and their plots;
# then the thesis's EKF loop (sfd-sim thesis-loop --quick) and its Figures 4-9.
# Results: the tables printed here, CSV and PNG files in out/ (or $SFD_OUT).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash tools/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc 2>/dev/null || echo 2)" --target sfd-sim sfd-replay
out="${SFD_OUT:-$root/out}"
mkdir -p "$out"
./build/host/apps/sfd-sim paper-uav --csv-dir "$out" "$@"
echo
./build/host/apps/sfd-sim isolation --csv-dir "$out"
echo
echo
# A simulated flight as a log, replayed through the node's code path, per method. The log does
# not begin at rest, so the filter starts from its TRUTH (filter.init_from_truth, evaluation only).
./build/host/apps/sfd-sim mistracking -o "$out/flight.lcmlog" --frames 400
printf '%%YAML:1.0\n---\nfilter:\n   init_from_truth: 1\n' > "$out/flight.yaml"
printf '\n%-8s %-10s %-8s %-8s %-12s %-16s %-12s\n' method precision recall F1 false-alarm \
  "time/frame (us)" "RMSE (m)"
for m in none parity oprf ransac1 ransacf both; do
  ./build/host/apps/sfd-replay "$out/flight.lcmlog" --config "$out/flight.yaml" --method "$m" \
    -o "$out/flight_$m.out.lcmlog" --summary "$out/flight_$m.json" >/dev/null
  .venv/bin/python - "$out/flight_$m.json" "$m" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = json.load(open(sys.argv[1] + '.timing.json'))
m = s['methods'][sys.argv[2]]
print('%-8s %-10.4f %-8.4f %-8.4f %-12.5f %-16.1f %-12.3f' % (sys.argv[2], m['precision'],
      m['recall'], m['f1'], m['false_alarm_rate'], t['frame_us']['median'],
      m.get('position_rmse_m', float('nan'))))
PY
done
echo
.venv/bin/python tools/plot_paper.py "$out"
echo
# Kilic 2014 Chapter IV: the association methods in an EKF localization loop, small sweep (~5 s).
# The full sweep (README): sfd-sim thesis-loop --csv-dir DIR (about 2 minutes).
mkdir -p "$out/thesis"
./build/host/apps/sfd-sim thesis-loop --quick --csv-dir "$out/thesis"
.venv/bin/python tools/plot_thesis.py "$out/thesis"
