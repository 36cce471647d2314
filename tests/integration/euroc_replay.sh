#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.euroc_replay: real data. sfd-euroc converts the 10 in-flight EuRoC V1_01 frames of
# ../shared/data/euroc_v1_01_flight10 (with and without the tracker's forward-backward check);
# sfd-replay runs every method on both logs with the filter started from TRUTH; checks:
#  - message counts: 10 FEATURES, 1 CAMERA_INFO, 10 TRUTH (no labels), every IMU sample of the
#    CSV inside [first frame - 1 s, last frame + 50 ms], FEATURES within the bound, ids unique in a
#    frame and never reused after a track is lost;
#  - CAMERA_INFO equals cam0_sensor.yaml (intrinsics, distortion, T_BS), read here independently;
#  - the conversion is byte-identical when repeated, and the same through --euroc (standard
#    layout, made of symbolic links to the same files);
#  - every method processes the 10 frames, judges features, and the summary says "not scored"
#    (null scores) instead of scoring against labels real data does not have;
#  - -o naming an input (the --imu file, through ./) is exit 2 and leaves it unchanged; -o
#    /dev/full is exit 1 naming the path (docs/deploy.md, "Reading logs and writing outputs").
# Skips (CTest SKIP_RETURN_CODE 77) with a message when the shared data is absent.
# usage: euroc_replay.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES DATA_DIR
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"; data="$4/euroc_v1_01_flight10"
if [ ! -d "$data/frontend/cam0" ]; then
  echo "SKIPPED: $data not present (real EuRoC data lives in ../shared/data next to the repo)"
  exit 77
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
common=(--images "$data/frontend/cam0" --frames "$data/derived/frames.csv"
        --imu "$data/derived/imu0/data.csv" --calib "$data/derived/calib/cam0_sensor.yaml"
        --gt "$data/derived/groundtruth/V1_01_easy.csv")
"$build/apps/sfd-euroc" "${common[@]}" -o "$tmp/fb.lcmlog"
"$build/apps/sfd-euroc" "${common[@]}" -o "$tmp/fb2.lcmlog" >/dev/null
cmp "$tmp/fb.lcmlog" "$tmp/fb2.lcmlog"
"$build/apps/sfd-euroc" "${common[@]}" --no-fb-check -o "$tmp/nofb.lcmlog"
# The standard EuRoC layout (--euroc), built from the same files with symbolic links, gives the
# same log byte for byte.
mav="$tmp/seq/mav0"
mkdir -p "$mav/cam0/data" "$mav/imu0" "$mav/state_groundtruth_estimate0"
for f in "$data"/frontend/cam0/*.jpg; do ln -s "$f" "$mav/cam0/data/"; done
ln -s "$data/derived/frames.csv" "$mav/cam0/data.csv"
ln -s "$data/derived/calib/cam0_sensor.yaml" "$mav/cam0/sensor.yaml"
ln -s "$data/derived/imu0/data.csv" "$mav/imu0/data.csv"
ln -s "$data/derived/groundtruth/V1_01_easy.csv" "$mav/state_groundtruth_estimate0/data.csv"
"$build/apps/sfd-euroc" --euroc "$tmp/seq" -o "$tmp/layout.lcmlog" >/dev/null
cmp "$tmp/fb.lcmlog" "$tmp/layout.lcmlog"
# Bad input gives a clear error naming the file and the line (exit 2), not a crash.
printf '#t\n1,2,3\n' > "$tmp/bad.csv"
if "$build/apps/sfd-euroc" "${common[@]}" --imu "$tmp/bad.csv" -o "$tmp/x.lcmlog" 2> "$tmp/err.txt"; then
  echo "sfd-euroc accepted a malformed IMU CSV"; exit 1
fi
grep -q "bad.csv:2:" "$tmp/err.txt" || { cat "$tmp/err.txt"; exit 1; }

printf '%%YAML:1.0\n---\nfilter:\n   init_from_truth: 1\n' > "$tmp/cfg.yaml"
for log in fb nofb; do
  for m in none parity oprf ransac1 ransacf both; do
    "$build/apps/sfd-replay" "$tmp/$log.lcmlog" --config "$tmp/cfg.yaml" --method "$m" \
      -o "$tmp/${log}_$m.out.lcmlog" --summary "$tmp/${log}_$m.json" > "$tmp/${log}_$m.txt"
    grep -q "verdicts not scored" "$tmp/${log}_$m.txt" || { cat "$tmp/${log}_$m.txt"; exit 1; }
  done
done
PYTHONPATH="$pytypes" "$py" - "$tmp" "$data" <<'PYEOF'
import collections, csv, json, sys
import lcm
from sfd import camera_info_t, feature_frame_t, truth_t
d, data = sys.argv[1], sys.argv[2]

# cam0_sensor.yaml, read with a minimal parser of its flat keys (independent of the app's reader).
txt = open(f"{data}/derived/calib/cam0_sensor.yaml").read()
def seq(key):
    s = txt[txt.index(key):]
    s = s[s.index("[") + 1:s.index("]")]
    return [float(x) for x in s.replace("\n", " ").split(",")]
intr, dist, T = seq("intrinsics:"), seq("distortion_coefficients:"), seq("data:")
res = seq("resolution:")
ns = [int(r[0]) for r in csv.reader(open(f"{data}/derived/imu0/data.csv")) if r and r[0][0] != "#"]
frames_ns = [int(r[0]) for r in csv.reader(open(f"{data}/derived/frames.csv")) if r and r[0][0] != "#"]
imu_expected = sum(1 for t in ns if frames_ns[0] - 1_000_000_000 <= t <= frames_ns[-1] + 50_000_000)

for log in ["fb", "nofb"]:
    c = collections.Counter()
    seen_ids, prev_ids, lost = set(), set(), set()
    for ev in lcm.EventLog(f"{d}/{log}.lcmlog", "r"):
        c[ev.channel] += 1
        if ev.channel == "CAMERA_INFO":
            ci = camera_info_t.decode(ev.data)
            assert (ci.width, ci.height) == tuple(int(x) for x in res), (ci.width, ci.height)
            assert [ci.fx, ci.fy, ci.cx, ci.cy] == intr, (ci.fx, ci.fy, ci.cx, ci.cy)
            assert list(ci.distortion) == dist and ci.distortion_model == camera_info_t.RADTAN
            assert list(ci.T_imu_cam) == T, ci.T_imu_cam
        elif ev.channel == "FEATURES":
            ff = feature_frame_t.decode(ev.data)
            assert 50 <= ff.num_features <= 150, ff.num_features
            ids = list(ff.track_id[:ff.num_features])
            assert len(set(ids)) == len(ids) and ids == sorted(ids)
            assert not (set(ids) & lost), "a lost track id came back"
            lost |= prev_ids - set(ids)
            prev_ids = set(ids)
            assert all(0 <= u < 752 and 0 <= v < 480 for u, v in
                       zip(ff.u[:ff.num_features], ff.v[:ff.num_features]))
            assert ff.utime == frames_ns[c["FEATURES"] - 1] // 1000
        elif ev.channel == "TRUTH":
            tr = truth_t.decode(ev.data)
            assert tr.num_features == 0  # real data: no labels
            assert abs(sum(q * q for q in tr.orientation) - 1) < 1e-9
    assert c == {"IMU": imu_expected, "CAMERA_INFO": 1, "FEATURES": 10, "TRUTH": 10}, c
    for m in ["none", "parity", "oprf", "ransac1", "ransacf", "both"]:
        s = json.load(open(f"{d}/{log}_{m}.json"))
        assert s["frames"]["in"] == 10 and s["frames"]["processed"] == 10, (m, s["frames"])
        assert s["method"] == m and s["truth"]["frames"] == 10, (m, s["truth"])
        assert s["detection"] is None, (m, s["detection"])  # real data: no labels, no scores
        j, tr = s["judged"], s["trajectory"]
        if m != "none":
            assert j["tested"] > 500, (m, j)  # most features of 7-8 frames judged
        assert tr["frames"] >= 8, (m, tr)
        print(f"{log:5s} {m:8s} tested {j['tested']:5d} spurious {j['spurious']:4d} "
              f"rmse {tr['rmse_raw_m']:.4f} m ate {tr['ate_m']:.4f} m")
    print(f"{log}: {dict(c)}; CAMERA_INFO equals cam0_sensor.yaml")
print("euroc replay: conversion, counts, calibration and every method checked")
PYEOF

# No output may be an input; write failures are exit 1 naming the path.
cp "$data/derived/imu0/data.csv" "$tmp/imu.csv"
chmod u+w "$tmp/imu.csv"
rc=0; "$build/apps/sfd-euroc" "${common[@]}" --imu "$tmp/imu.csv" -o "$tmp/./imu.csv" \
  > /dev/null 2> "$tmp/err.txt" || rc=$?
cmp -s "$tmp/imu.csv" "$data/derived/imu0/data.csv" && [ "$rc" -eq 2 ] &&
  grep -q "is the input --imu" "$tmp/err.txt" || {
  cat "$tmp/err.txt"; echo "sfd-euroc -o = --imu: exit $rc"; exit 1; }
rc=0; "$build/apps/sfd-euroc" "${common[@]}" -o /dev/full > /dev/null 2> "$tmp/err.txt" || rc=$?
[ "$rc" -eq 1 ] && grep -q "^sfd-euroc: -o /dev/full: write failed" "$tmp/err.txt" || {
  cat "$tmp/err.txt"; echo "sfd-euroc -o /dev/full: exit $rc"; exit 1; }
echo "sfd-euroc: -o = --imu refused (exit 2), -o /dev/full exit 1"
