#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.sim_faults: the fault model, rest start and IMU of sfd-sim's flight logs
# (apps/sim/SIMULATION.md), on short logs with a fixed seed, pixel noise 0 and exact depth priors:
#  - kinds per scenario: paper-uav jumps only; mistracking jump, drift, mismatch; moving-object
#    those and moving; worst-case mismatch only (every feature at --random-fraction 1; at 0.5,
#    half of them random pixels in every frame, each labelled in its frame and the 2 after);
#    TRUTH spurious = (kind != clean);
#  - at rest (exact pixels): every step of a static track (a mismatch's return included) labels it
#    spurious in the truth_window frames from the step and nothing else does; drift steps 0.3-2 px per frame, constant within
#    an event, 3-10 of them; mismatches 15-60 px away and back the next frame; jumps 5-30 px;
#  - in 3-D (pixels back-projected with the depth prior and TRUTH): a clean track follows one
#    static point; a jump or a drift's lock moves the track to another static point; moving
#    points move at 1-15 m/s; paper-uav's fault step is exactly k(-1, 1) (normalized: -k fx,
#    +k fy px) from the old point's projection, onto another static point;
#  - the first 2 s at rest (TRUTH constant; accel norm = g within noise, gyro = the given bias),
#    the white noise of gyro and accelerometer = density / sqrt(dt) within 10 %;
#  - same seed, byte-identical log.
# usage: sim_faults.sh BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
sim="$build/apps/sfd-sim"
common=(--seed 4 --frames 120 --pixel-sigma-px 0 --depth-var-m2 0)
for sc in paper-uav mistracking moving-object worst-case; do
  "$sim" "$sc" -o "$tmp/$sc.lcmlog" "${common[@]}" >/dev/null
done
"$sim" moving-object -o "$tmp/again.lcmlog" "${common[@]}" >/dev/null
cmp "$tmp/moving-object.lcmlog" "$tmp/again.lcmlog"
"$sim" worst-case -o "$tmp/worst-half.lcmlog" "${common[@]}" --features 64 \
  --random-fraction 0.5 >/dev/null
"$sim" mistracking -o "$tmp/imu.lcmlog" --seed 9 --frames 60 --gyro-bias-rad-s 0.01,-0.02,0.005 \
  --accel-bias-m-s2 0,0,0 >/dev/null
"$sim" mistracking -o "$tmp/imu2.lcmlog" --seed 9 --frames 60 --gyro-bias-rad-s 0.01,-0.02,0.005 \
  --accel-bias-m-s2 0,0,0 >/dev/null
cmp "$tmp/imu.lcmlog" "$tmp/imu2.lcmlog"
PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import collections, math, sys
import numpy as np
import lcm
from sfd import camera_info_t, feature_frame_t, imu_t, truth_t

d = sys.argv[1]
CLEAN, JUMP, DRIFT, MOVING, MISMATCH = 0, 1, 2, 3, 4
W = 2          # --truth-window default
REST_S = 2.0   # --rest-s default
G = 9.81


def load(path):
    out = {"imu": [], "frames": [], "info": None}
    feats = {}
    for ev in lcm.EventLog(path, "r"):
        if ev.channel == "IMU":
            out["imu"].append(imu_t.decode(ev.data))
        elif ev.channel == "CAMERA_INFO" and out["info"] is None:
            out["info"] = camera_info_t.decode(ev.data)
        elif ev.channel == "FEATURES":
            m = feature_frame_t.decode(ev.data)
            feats[m.utime] = m
        elif ev.channel == "TRUTH":
            t = truth_t.decode(ev.data)
            f = feats.pop(t.utime)
            n = f.num_features
            assert t.num_features == n and list(t.track_id[:n]) == list(f.track_id[:n])
            for i in range(n):
                assert (t.spurious[i] != 0) == (t.kind[i] != CLEAN), (t.utime, i)
            out["frames"].append((t, f))
    return out


def q_to_R(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def backproject(info, t, u, v, z):
    """World point of pixel (u, v) at depth z (camera z) for TRUTH pose t (radtan undistortion
    by fixed-point iteration)."""
    k1, k2, p1, p2 = info.distortion
    xd, yd = (u - info.cx) / info.fx, (v - info.cy) / info.fy
    x, y = xd, yd
    for _ in range(200):
        r2 = x * x + y * y
        rad = 1 + k1 * r2 + k2 * r2 * r2
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x, y = (xd - dx) / rad, (yd - dy) / rad
    T = np.array(info.T_imu_cam).reshape(4, 4)
    c = np.array([x * z, y * z, z])
    return q_to_R(t.orientation) @ (T[:3, :3] @ c + T[:3, 3]) + np.array(t.position)


def tracks(log):
    """track id -> list of (frame index, u, v, depth, kind)."""
    tr = collections.defaultdict(list)
    for fi, (t, f) in enumerate(log["frames"]):
        for i in range(f.num_features):
            tr[f.track_id[i]].append((fi, f.u[i], f.v[i], f.depth[i], t.kind[i]))
    return tr


def kind_counts(log):
    c = collections.Counter()
    for t, f in log["frames"]:
        c.update(t.kind[:t.num_features])
    return c


logs = {sc: load(f"{d}/{sc}.lcmlog")
        for sc in ["paper-uav", "mistracking", "moving-object", "worst-case"]}
expect = {"paper-uav": {JUMP}, "mistracking": {JUMP, DRIFT, MISMATCH},
          "moving-object": {JUMP, DRIFT, MOVING, MISMATCH}, "worst-case": {MISMATCH}}
for sc, log in logs.items():
    c = kind_counts(log)
    n = sum(c.values())
    kinds = {k for k in c if k != CLEAN}
    print(f"{sc:14s} {len(log['frames'])} frames, spurious " +
          ", ".join(f"{k}: {100.0 * c[k] / n:.2f}%" for k in sorted(kinds)))
    assert kinds == expect[sc], (sc, c)
assert kind_counts(logs["worst-case"])[CLEAN] == 0
# worst-case at --random-fraction 0.5: 32 of the 64 features are random pixels in every frame,
# each labelled like a one-frame mismatch (its frame and the W = 2 after it). During the 2 s at
# rest the clean pixel of a track never changes (no noise, no motion): the random ones are
# those that differ from the track's most frequent pixel.
half_log = load(f"{d}/worst-half.lcmlog")
rest = [(t, f) for t, f in half_log["frames"] if t.utime - half_log["frames"][0][0].utime <= 1_900_000]
assert len(rest) >= 30, len(rest)
seen = collections.defaultdict(collections.Counter)
for t, f in rest:
    for i in range(f.num_features):
        seen[f.track_id[i]][(f.u[i], f.v[i])] += 1
clean_px = {tid: c.most_common(1)[0][0] for tid, c in seen.items()}
random_at = []
for k, (t, f) in enumerate(rest):
    r = {f.track_id[i] for i in range(f.num_features)
         if (f.u[i], f.v[i]) != clean_px[f.track_id[i]]}
    assert len(r) == 32, (k, len(r))
    random_at.append(r)
    for i in range(t.num_features):
        tid = t.track_id[i]
        want = any(tid in random_at[k - j] for j in range(3) if k - j >= 0)
        assert (t.kind[i] == MISMATCH) == want and t.kind[i] in (CLEAN, MISMATCH), (k, tid)
for sc in ["mistracking", "moving-object"]:
    c = kind_counts(logs[sc])
    frac = 1.0 - c[CLEAN] / sum(c.values())
    assert 0.06 < frac < 0.14, (sc, frac)  # --outlier-ratio 0.1

# The rest: frames at t <= 2 s, exact pixels (no noise, no motion).
for sc in ["mistracking", "moving-object"]:
    log = logs[sc]
    info = log["info"]
    frames = log["frames"]
    t0 = frames[0][0].utime
    rest = [i for i, (t, f) in enumerate(frames) if (t.utime - t0) * 1e-6 <= REST_S]
    assert len(rest) == 41, len(rest)
    for i in rest:
        assert frames[i][0].position == frames[0][0].position
        assert frames[i][0].orientation == frames[0][0].orientation
    steps = collections.Counter()
    drift_steps, mismatch, jumps = [], [], []
    n_returns = 0
    for tid, obs in tracks(log).items():
        obs = [o for o in obs if o[0] in rest]
        kinds = {o[4] for o in obs}
        if MOVING in kinds:
            assert kinds == {MOVING}, (tid, kinds)
            for a, b in zip(obs, obs[1:]):
                if b[0] == a[0] + 1:
                    assert math.hypot(b[1] - a[1], b[2] - a[2]) > 0.05, (tid, a, b)
            continue
        # frames of a step: the observation moved since the previous frame
        step_frames = {}
        for a, b in zip(obs, obs[1:]):
            assert b[0] == a[0] + 1, (tid, a, b)  # a static track is seen in every frame
            dist = math.hypot(b[1] - a[1], b[2] - a[2])
            if dist > 1e-6:
                step_frames[b[0]] = (dist, b[4], b[1] - a[1], b[2] - a[2])
        # a mismatch's return to its own point the next frame (a labelling step too)
        returns = {fi for fi, s in step_frames.items() if s[1] == MISMATCH and
                   fi - 1 in step_frames and step_frames[fi - 1][1] == MISMATCH and
                   abs(step_frames[fi - 1][2] + s[2]) < 1e-6 and
                   abs(step_frames[fi - 1][3] + s[3]) < 1e-6}
        n_returns += len(returns)
        first = obs[0][0] if obs else None
        for o in obs[1:]:
            fi = o[0]
            near = [s for s in step_frames if fi - W < s <= fi]
            if o[0] - first < W:  # a step before the first observed frame is not seen
                continue
            assert (o[4] != CLEAN) == bool(near), (sc, tid, fi, o, step_frames)
            if near:
                assert o[4] == step_frames[max(near)][1], (sc, tid, fi, o, step_frames)
        # step sizes by kind, in order
        seq = sorted(step_frames.items())
        j = 0
        while j < len(seq):
            fi, (dist, kind, du, dv) = seq[j]
            steps[kind] += 1
            if kind == DRIFT:
                # one event: consecutive frames, the same step (the lock within 1e-3 px)
                run = [dist]
                while j + 1 < len(seq) and seq[j + 1][0] == seq[j][0] + 1 and \
                        seq[j + 1][1][1] == DRIFT and \
                        math.hypot(seq[j + 1][1][2] - du, seq[j + 1][1][3] - dv) < 1e-3:
                    j += 1
                    run.append(seq[j][1][0])
                drift_steps.append(run)
            elif kind == MISMATCH:
                mismatch.append(dist)
            elif kind == JUMP:
                jumps.append(dist)
            j += 1
    assert drift_steps and mismatch and jumps, (sc, steps)
    for run in drift_steps:
        assert all(0.3 - 1e-6 <= s <= 2.0 + 1e-6 for s in run), run
        # one step per frame, constant within the event (the lock frame within 1e-3 px); a
        # run cut by the end of the rest is shorter
        assert max(run) - min(run) < 1e-3, run
        assert len(run) <= 10, run
    assert any(len(r) >= 3 for r in drift_steps)
    for m in mismatch:
        assert 15.0 - 1e-3 <= m <= 60.0 + 1e-3, m
    # every mismatch is back on its point the next frame (but one cut by the end of the rest)
    assert len(mismatch) - 2 * n_returns <= 3, (len(mismatch), n_returns)
    for m in jumps:
        assert 5.0 - 1e-3 <= m <= 30.0 + 1e-3, m
    print(f"{sc:14s} at rest: {len(jumps)} jumps {min(jumps):.1f}-{max(jumps):.1f} px, "
          f"{len(drift_steps)} drifts {min(min(r) for r in drift_steps):.2f}-"
          f"{max(max(r) for r in drift_steps):.2f} px/frame, {n_returns} mismatches "
          f"{min(mismatch):.1f}-{max(mismatch):.1f} px and back")

    # 3-D: back-projection with the exact depth prior and TRUTH.
    n_clean = n_switch = 0
    speeds = []
    for tid, obs in tracks(log).items():
        pts = [(o[0], backproject(info, frames[o[0]][0], o[1], o[2], o[3]), o[4]) for o in obs]
        if all(o[4] == MOVING for o in obs):
            for a, b in zip(pts, pts[1:]):
                if b[0] == a[0] + 1:
                    speeds.append(np.linalg.norm(b[1] - a[1]) / 0.05)
            continue
        # consecutive frames with both observations clean: the same static point
        for a, b in zip(pts, pts[1:]):
            if b[0] == a[0] + 1 and a[2] == CLEAN and b[2] == CLEAN:
                assert np.linalg.norm(b[1] - a[1]) < 1e-4, (sc, tid, a, b)
                n_clean += 1
        # a jump / drift lock: the static point after the label window is another one
        for k in range(1, len(pts)):
            if pts[k][2] == JUMP and pts[k - 1][2] == CLEAN:
                after = [p for p in pts[k:] if p[2] == CLEAN]
                if after and after[0][0] - pts[k][0] == W:
                    assert np.linalg.norm(after[0][1] - pts[k - 1][1]) > 0.05, (sc, tid)
                    assert np.linalg.norm(after[0][1] - pts[k][1]) < 1e-4, (sc, tid)
                    n_switch += 1
    assert n_clean > 1000 and n_switch > 10, (n_clean, n_switch)
    if sc == "moving-object":
        assert speeds and min(speeds) > 1.0 - 1e-3 and max(speeds) < 15.0 + 1e-3, \
            (min(speeds), max(speeds))
        print(f"{sc:14s} moving points: {len(speeds)} steps at {min(speeds):.2f}-"
              f"{max(speeds):.2f} m/s")
    print(f"{sc:14s} 3-D: {n_clean} clean steps on one static point, {n_switch} jumps onto "
          f"another static point")

# paper-uav: the paper's fault k(-1, 1) (normalized; -k fx, +k fy px) is a step onto the ground
# point under the shifted pixel: in the step frame the pixel is the old point's projection plus
# the fault, and every clean observation is a projection of one static point (until 2026-11 the
# offset was added to the old point's projection, so clean observations matched no point).
def project(info, t, pw):
    """Pixel of world point pw for TRUTH pose t (radtan distortion)."""
    T = np.array(info.T_imu_cam).reshape(4, 4)
    c = T[:3, :3].T @ (q_to_R(t.orientation).T @ (np.asarray(pw) - np.array(t.position)) -
                       T[:3, 3])
    x, y = c[0] / c[2], c[1] / c[2]
    k1, k2, p1, p2 = info.distortion
    r2 = x * x + y * y
    rad = 1 + k1 * r2 + k2 * r2 * r2
    xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return info.fx * xd + info.cx, info.fy * yd + info.cy


K_FAULT = 0.02  # --fault-magnitude default
log = logs["paper-uav"]
info, frames = log["info"], log["frames"]
n_clean = n_step = 0
for tid, obs in tracks(log).items():
    pts = [(o[0], backproject(info, frames[o[0]][0], o[1], o[2], o[3]), o[4], o[1], o[2])
           for o in obs]
    for a, b in zip(pts, pts[1:]):
        if b[0] != a[0] + 1:
            continue
        if a[2] == CLEAN and b[2] == CLEAN:
            assert np.linalg.norm(b[1] - a[1]) < 1e-4, ("paper-uav", tid, a, b)
            n_clean += 1
        elif a[2] == CLEAN and b[2] == JUMP:
            u, v = project(info, frames[b[0]][0], a[1])
            assert abs(b[3] - u + K_FAULT * info.fx) < 1e-3, ("paper-uav", tid, b, u)
            assert abs(b[4] - v - K_FAULT * info.fy) < 1e-3, ("paper-uav", tid, b, v)
            n_step += 1
assert n_clean > 1000 and n_step > 100, (n_clean, n_step)
print(f"paper-uav      3-D: {n_clean} clean steps on one static point, {n_step} fault steps of "
      f"exactly ({-K_FAULT * info.fx:.2f}, {K_FAULT * info.fy:.2f}) px")

# IMU at rest with the given biases.
log = load(f"{d}/imu.lcmlog")
imu = log["imu"]
t0 = imu[0].utime
rest = [m for m in imu if (m.utime - t0) * 1e-6 < REST_S]
assert len(rest) >= 200, len(rest)
dt = 0.005
sg, sa = 3.4e-4 / math.sqrt(dt), 4.0e-3 / math.sqrt(dt)
gyro = np.array([m.gyro for m in rest])
acc = np.array([m.accel for m in rest])
bias = np.array([0.01, -0.02, 0.005])
assert np.all(np.abs(gyro - bias) < 5 * sg + 1e-3), np.abs(gyro - bias).max()
norms = np.linalg.norm(acc, axis=1)
assert np.all(np.abs(norms - G) < 5 * sa + 0.02), np.abs(norms - G).max()
assert abs(np.linalg.norm(acc.mean(axis=0)) - G) < 0.02, acc.mean(axis=0)
assert np.all(np.abs(gyro.mean(axis=0) - bias) < 1e-3), gyro.mean(axis=0)
# white noise from first differences (the bias random walk adds < 1 % there)
gs = np.diff(gyro, axis=0).std() / math.sqrt(2)
as_ = np.diff(acc, axis=0).std() / math.sqrt(2)
print(f"IMU at rest: {len(rest)} samples, gyro noise {gs:.3e} rad/s (expected {sg:.3e}), "
      f"accel noise {as_:.4f} m/s^2 (expected {sa:.4f}), |mean accel| "
      f"{np.linalg.norm(acc.mean(axis=0)):.4f} m/s^2")
assert abs(gs / sg - 1) < 0.1 and abs(as_ / sa - 1) < 0.1, (gs, sg, as_, sa)
# TRUTH constant over the rest, moving after it
frames = log["frames"]
ft0 = frames[0][0].utime
for t, f in frames:
    if (t.utime - ft0) * 1e-6 <= REST_S:
        assert t.position == frames[0][0].position
assert frames[-1][0].position != frames[0][0].position
print("sim faults: kinds, label windows, fault geometry, rest start, IMU noise, determinism "
      "checked")
PYEOF
