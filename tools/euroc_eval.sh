#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Real-sequence evaluation (docs/euroc.md): converts the 10 in-flight EuRoC V1_01 frames with the
# tracker's forward-backward check on (fb) and off (nofb), replays each log through every method
# (filter started from TRUTH, gyro bias = the ground truth's at the first frame; the fb log also
# with a 3 m depth prior), and writes overlays, the fraction judged spurious per method and frame
# and the ground-truth epipolar check of every track with tools/euroc_overlay.py (out/euroc/overlay).
# usage: tools/euroc_eval.sh [BUILD_DIR (build/host)] [OUT_DIR (out/euroc)] [DATA_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build/host}"; out="${2:-$root/out/euroc}"
data="${3:-$root/../shared/data}/euroc_v1_01_flight10"
if [ ! -d "$data/frontend/cam0" ]; then
  echo "euroc_eval: $data not present (real data lives in ../shared/data next to the repo)" >&2
  exit 2
fi
py="$root/.venv/bin/python"; [ -x "$py" ] || py=python3
mkdir -p "$out"
common=(--images "$data/frontend/cam0" --frames "$data/derived/frames.csv"
        --imu "$data/derived/imu0/data.csv" --calib "$data/derived/calib/cam0_sensor.yaml"
        --gt "$data/derived/groundtruth/V1_01_easy.csv")
"$build/apps/sfd-euroc" "${common[@]}" -o "$out/fb.lcmlog" | tee "$out/convert_fb.txt"
"$build/apps/sfd-euroc" "${common[@]}" --no-fb-check -o "$out/nofb.lcmlog" | tee "$out/convert_nofb.txt"
# The filter cannot start at rest (0.45 s, in flight): it starts from TRUTH; the gyro bias is the
# one sfd-euroc printed from the ground truth (the node does not estimate it before its start).
bias="$(sed -n 's/.*gyro bias at the first frame: \(\[.*\]\) rad\/s/\1/p' "$out/convert_fb.txt")"
printf '%%YAML:1.0\n---\ngyro_bias_rad_s: %s\nfilter:\n   init_from_truth: 1\n' "$bias" > "$out/cfg.yaml"
# fb, nofb: the node's defaults (depth prior 10 m for features without one); fb-d3: the depth
# prior set to 3 m, a guess at the scale of the indoor room (not measured).
runs=()
for run in fb nofb fb-d3; do
  log="${run%-d3}"; extra=()
  [ "$run" = fb-d3 ] && extra=(--default-depth-m 3)
  for m in parity oprf ransac1 ransacf both; do
    "$build/apps/sfd-replay" "$out/$log.lcmlog" --config "$out/cfg.yaml" --method "$m" \
      "${extra[@]}" -o "$out/${run}_$m.out.lcmlog" --summary "$out/${run}_$m.json" | head -2
    runs+=("$run/$m=$out/${run}_$m.out.lcmlog")
  done
done
PYTHONPATH="$build/lcm_types/python" "$py" "$root/tools/euroc_overlay.py" \
  --images "$data/frontend/cam0" --out-dir "$out/overlay" --every-frame \
  --gt "$data/derived/groundtruth/V1_01_easy.csv" --calib "$data/derived/calib/cam0_sensor.yaml" \
  --crops 99,178,165,34,57,61,65,110,124 --crops-run fb/oprf "${runs[@]}"
