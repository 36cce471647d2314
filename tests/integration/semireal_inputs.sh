#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.semireal_inputs: `sfd-sim euroc-semireal` on small EuRoC-layout folders written
# here (no shared data needed):
#  - a well-formed folder (2 s of 200 Hz IMU, 40 Hz ground truth starting 0.1 s later, cam0
#    sensor.yaml of EuRoC) gives a log whose IMU count is the CSV rows inside the overlap, whose
#    frame count is floor(overlap x rate) + 1, with one TRUTH per frame;
#  - malformed inputs exit with 2 and a one-line reason naming the file and line (or field):
#    a non-numeric field, a wrong field count, a timestamp going backwards, a non-unit
#    quaternion, a ground-truth gap over 0.2 s, a missing sensor.yaml key, a missing folder;
#    bad options exit with 2; sfd-replay refuses a malformed filter.init_accel_bias_m_s2;
#  - -o or --config-out naming an input file is exit 2 and leaves it unchanged.
# usage: semireal_inputs.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"
sim="$build/apps/sfd-sim"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

make_folder() {  # make_folder DIR: a well-formed EuRoC-layout folder
  "$py" - "$1" <<'PYEOF'
import math, os, sys
d = sys.argv[1]
for sub in ["imu0", "state_groundtruth_estimate0", "cam0"]:
    os.makedirs(f"{d}/mav0/{sub}", exist_ok=True)
t0 = 1403715523912140000
with open(f"{d}/mav0/imu0/data.csv", "w") as f:
    f.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
    for i in range(401):  # 2.000 s at 200 Hz
        f.write(f"{t0 + i * 5000000},0.001,-0.002,0.01,9.81,0.01,-0.02\n")
with open(f"{d}/mav0/state_groundtruth_estimate0/data.csv", "w") as f:
    f.write("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
            "q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], "
            "b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], "
            "b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n")
    # IMU x up (as EuRoC's at rest): q = rotation of -90 deg about y; slow drift along x
    q = (math.cos(-math.pi / 4), 0.0, math.sin(-math.pi / 4), 0.0)
    for i in range(100):  # from t0 + 0.1 s at 40 Hz, 2.475 s: ends after the IMU
        t = t0 + 100000000 + i * 25000000
        f.write(f"{t},{0.1 * i * 0.025:.6f},1.0,1.5,{q[0]:.6f},{q[1]:.6f},{q[2]:.6f},{q[3]:.6f},"
                "0.1,0,0,0.001,-0.002,0.01,0.02,-0.03,0.04\n")
with open(f"{d}/mav0/cam0/sensor.yaml", "w") as f:
    f.write("""%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
""")
PYEOF
}

# --- a well-formed folder: counts -------------------------------------------------------------
make_folder "$tmp/good"
"$sim" euroc-semireal --euroc "$tmp/good" -o "$tmp/good.lcmlog" --features 50 \
  --config-out "$tmp/good.yaml" > "$tmp/good.txt"
cat "$tmp/good.txt"
PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import collections, sys
import lcm
from sfd import feature_frame_t, truth_t
d = sys.argv[1]
c = collections.Counter(ev.channel for ev in lcm.EventLog(f"{d}/good.lcmlog", "r"))
# overlap: IMU 0..2.000 s, ground truth 0.100..2.575 s -> 0.100..2.000 s
imu_rows = sum(1 for i in range(401) if 100000000 <= i * 5000000 <= 2000000000)
frames = int((2000000000 - 100000000) // 50000000) + 1
assert c["IMU"] == imu_rows == 381, (c, imu_rows)
assert c["FEATURES"] == frames == 39 and c["TRUTH"] == frames, (c, frames)
assert c["CAMERA_INFO"] == 2, c
for ev in lcm.EventLog(f"{d}/good.lcmlog", "r"):
    if ev.channel == "FEATURES":
        ff = feature_frame_t.decode(ev.data)
        assert ff.num_features == 50, ff.num_features
        assert all(0 <= ff.u[i] < 752 and 0 <= ff.v[i] < 480 for i in range(50))
print(f"well-formed folder: {c['IMU']} IMU (CSV rows in the overlap), {c['FEATURES']} frames, "
      f"{c['TRUTH']} TRUTH, {c['CAMERA_INFO']} CAMERA_INFO")
PYEOF
grep -q "init_accel_bias_m_s2: \[ 0.02, -0.029999999999999999, 0.040000000000000001 \]" \
  "$tmp/good.yaml" || { echo "FAIL: --config-out lacks the ground truth's b_a"; cat "$tmp/good.yaml"; exit 1; }
"$build/apps/sfd-replay" "$tmp/good.lcmlog" --config "$tmp/good.yaml" --method none >/dev/null
# the node key it writes is validated: two numbers are refused with the key named
sed 's/init_accel_bias_m_s2: \[.*\]/init_accel_bias_m_s2: [ 0.1, 0.2 ]/' "$tmp/good.yaml" > "$tmp/bad2.yaml"
set +e
"$build/apps/sfd-replay" "$tmp/good.lcmlog" --config "$tmp/bad2.yaml" >/dev/null 2>"$tmp/err.txt"
rc=$?
set -e
if [ "$rc" -ne 2 ] || ! grep -q "filter.init_accel_bias_m_s2: \[0.1, 0.2\] is not a list of 3 numbers" "$tmp/err.txt"; then
  echo "FAIL: a 2-element init_accel_bias_m_s2 was not refused (exit $rc)"; cat "$tmp/err.txt"; exit 1
fi
echo "sfd-replay config: $(cat "$tmp/err.txt")"

# --- malformed inputs: exit 2 and the reason --------------------------------------------------
expect_fail() {  # expect_fail NAME PATTERN ARGS...: exit code 2, stderr matching PATTERN
  local name="$1" pattern="$2"; shift 2
  set +e
  "$sim" "$@" >/dev/null 2>"$tmp/err.txt"
  local rc=$?
  set -e
  if [ "$rc" -ne 2 ] || ! grep -qE -- "$pattern" "$tmp/err.txt"; then
    echo "FAIL: $name: exit $rc, stderr:"; cat "$tmp/err.txt"; exit 1
  fi
  echo "$name: exit 2: $(head -1 "$tmp/err.txt")"
}
bad() {  # bad NAME: a fresh copy of the good folder in $tmp/NAME
  rm -rf "${tmp:?}/$1"; cp -r "$tmp/good" "$tmp/$1"
}
imu_csv=mav0/imu0/data.csv
gt_csv=mav0/state_groundtruth_estimate0/data.csv

bad field; sed -i '4s/,9.81,/,9.8x1,/' "$tmp/field/$imu_csv"
expect_fail "non-numeric field" "imu0/data.csv:4: field 5: not a finite number: '9.8x1'" \
  euroc-semireal --euroc "$tmp/field" -o "$tmp/x.lcmlog"
bad count; sed -i '7s/,0.01,-0.02$//' "$tmp/count/$imu_csv"
expect_fail "field count" "imu0/data.csv:7: expected 7 comma-separated fields, got 5" \
  euroc-semireal --euroc "$tmp/count" -o "$tmp/x.lcmlog"
bad order
sed -i '10s/^[0-9]*,/1403715523000000000,/' "$tmp/order/$gt_csv"
expect_fail "timestamp backwards" "state_groundtruth_estimate0/data.csv:10: timestamp 1403715523000000000 is not after" \
  euroc-semireal --euroc "$tmp/order" -o "$tmp/x.lcmlog"
bad quat; sed -i '3s/,0.707107,0.000000,-0.707107,0.000000,/,0.5,0.000000,-0.5,0.000000,/' "$tmp/quat/$gt_csv"
expect_fail "non-unit quaternion" "data.csv:3: q_RS \(fields 5-8\) is not a unit quaternion" \
  euroc-semireal --euroc "$tmp/quat" -o "$tmp/x.lcmlog"
bad gap; sed -i '20,30d' "$tmp/gap/$gt_csv"
expect_fail "ground-truth gap" "state_groundtruth_estimate0/data.csv:19-20: ground-truth gap of 0.300 s" \
  euroc-semireal --euroc "$tmp/gap" -o "$tmp/x.lcmlog"
bad yaml; sed -i '/^intrinsics:/d' "$tmp/yaml/mav0/cam0/sensor.yaml"
expect_fail "sensor.yaml key" "sensor.yaml: intrinsics: expected a list of 4 numbers" \
  euroc-semireal --euroc "$tmp/yaml" -o "$tmp/x.lcmlog"
# A YAML syntax error: one line "PATH:LINE: not valid YAML (reason)", not OpenCV's own message
# ("OpenCV(4.6.0) ./modules/...: error: (-212:Parsing error) ...") with its line break.
bad yamlsyntax; sed -i 's/^resolution: \[752, 480\]/resolution: [752,/' "$tmp/yamlsyntax/mav0/cam0/sensor.yaml"
expect_fail "sensor.yaml syntax" "^sfd-sim: .*/sensor\.yaml:[0-9]+: not valid YAML \(Incorrect indentation\)\$" \
  euroc-semireal --euroc "$tmp/yamlsyntax" -o "$tmp/x.lcmlog"
[ "$(wc -l < "$tmp/err.txt")" -eq 1 ] && ! grep -q "OpenCV" "$tmp/err.txt" || {
  echo "FAIL: the sensor.yaml syntax error is not one line of sfd's own:"; cat "$tmp/err.txt"; exit 1; }
expect_fail "missing folder" "nowhere/imu0/data.csv: cannot open" \
  euroc-semireal --euroc "$tmp/nowhere" -o "$tmp/x.lcmlog"
expect_fail "no --euroc" "needs --euroc DIR and -o" euroc-semireal -o "$tmp/x.lcmlog"
expect_fail "bad rate" "--camera-hz: 0 is not in 0.1..200" euroc-semireal --euroc "$tmp/good" -o "$tmp/x.lcmlog" \
  --camera-hz 0
# --- no output may be an input (docs/deploy.md, "Reading logs and writing outputs") ------------
bad same; cp "$tmp/same/$imu_csv" "$tmp/imu.orig"; cp "$tmp/same/$gt_csv" "$tmp/gt.orig"
expect_fail "-o is the IMU input" "-o .*/imu0/\./data\.csv is the input .*imu0/data\.csv \(same file\)" \
  euroc-semireal --euroc "$tmp/same" -o "$tmp/same/mav0/imu0/./data.csv"
expect_fail "--config-out is the ground truth" "--config-out .* is the input .*state_groundtruth_estimate0/data\.csv" \
  euroc-semireal --euroc "$tmp/same" -o "$tmp/x.lcmlog" --config-out "$tmp/same/$gt_csv"
cmp "$tmp/same/$imu_csv" "$tmp/imu.orig"
cmp "$tmp/same/$gt_csv" "$tmp/gt.orig"
echo "semireal inputs: counts and every malformed input checked"
