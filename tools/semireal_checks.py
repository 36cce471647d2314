#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks behind the semi-real evaluation (apps/sim/SEMIREAL.md).

  semireal_checks.py imu [--data DIR]
      Consistency of the real IMU with the ground truth (frame conventions, time alignment,
      biases): (1) the rotation the gyro integrates over each 50 ms ground-truth interval
      (zero-order hold, the ground truth's b_w subtracted) against the ground truth's relative
      rotation R_ItoW(a)^T R_ItoW(b), RMS angle, for IMU time offsets of -20..+20 ms (the minimum
      should sit at 0 if IMU and ground truth share the clock); (2) IMU-only dead reckoning
      (R' = R Exp(w dt), v' = v + (R a + g) dt, g = (0, 0, -9.81)) from a ground-truth state,
      with and without the ground truth's biases, position and velocity error after 1, 2, 5, 10 s.

  semireal_checks.py kinds OUT.lcmlog
      Detection by kind in an sfd-replay output log (-o) of a euroc-semireal log: tracks labelled
      spurious in every frame they appear are the moving group's; the other spurious labels come
      from steps (jumps, drift steps, mismatches). Prints the fraction judged SPURIOUS and
      UNTESTED per kind.

  semireal_checks.py trace OUT.lcmlog [--every 80]
      The filter's error along an sfd-replay output log: every N frames, SFD_STATE against TRUTH:
      position error (m), velocity error (m/s, against TRUTH's central difference), attitude error
      angle (deg), and the filter's position standard deviation (m, from position_var).
"""
import argparse
import collections
import os
import sys
import sfd_tool_cli  # tools/sfd_tool_cli.py

import numpy as np


def load_csv(path):
    t, v = [], []
    for line in open(path):
        line = line.strip()
        if line and not line.startswith("#"):
            f = line.split(",")
            t.append(int(f[0]))
            v.append([float(x) for x in f[1:]])
    return np.array(t, dtype=np.int64), np.array(v)


def q_to_R(q):
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def so3_exp(phi):
    a = np.linalg.norm(phi)
    K = np.array([[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]])
    if a < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + np.sin(a) / a * K + (1 - np.cos(a)) / a ** 2 * K @ K


def so3_angle(R):
    return float(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))


def gyro_rotation(ti, imu, ta, tb, bw):
    """Rotation R_b^a integrated from the gyro over [ta, tb] (zero-order hold of each sample)."""
    R = np.eye(3)
    i = int(np.searchsorted(ti, ta, side="right")) - 1  # sample holding at ta
    t = ta
    while t < tb:
        t_next = min(ti[i + 1], tb) if i + 1 < len(ti) else tb
        R = R @ so3_exp((imu[i, 0:3] - bw) * (t_next - t) * 1e-9)
        t = t_next
        i += 1
    return R


def check_imu(data):
    ti, imu = load_csv(os.path.join(data, "mav0", "imu0", "data.csv"))
    tg, gt = load_csv(os.path.join(data, "mav0", "state_groundtruth_estimate0", "data.csv"))
    print("imu0: %d rows, %d..%d ns; ground truth: %d rows, %d..%d ns" %
          (len(ti), ti[0], ti[-1], len(tg), tg[0], tg[-1]))
    print("(1) gyro vs ground-truth rotation over 50 ms (2 ground-truth intervals), RMS angle:")
    for off_ms in [-20, -10, -5, 0, 5, 10, 20]:
        off = off_ms * 1000000
        errs = []
        for j in range(len(tg) - 2):
            ta, tb = tg[j] + off, tg[j + 2] + off
            if ta < ti[0] or tb > ti[-1]:
                continue
            R_gt = q_to_R(gt[j, 3:7]).T @ q_to_R(gt[j + 2, 3:7])
            R_imu = gyro_rotation(ti, imu, ta, tb, gt[j, 10:13])
            errs.append(so3_angle(R_imu.T @ R_gt))
        e = np.array(errs)
        print("  IMU offset %+3d ms: %.3f mrad (%d intervals)" %
              (off_ms, 1e3 * np.sqrt(np.mean(e ** 2)), len(e)))
    print("(2) IMU-only dead reckoning from a ground-truth state: |position error| m, "
          "|velocity error| m/s")
    g = np.array([0.0, 0.0, -9.81])
    for start in [0, 400, 800]:
        for with_bias in [True, False]:
            t0 = tg[start]
            p, v, R = gt[start, 0:3].copy(), gt[start, 7:10].copy(), q_to_R(gt[start, 3:7])
            bw = gt[start, 10:13] if with_bias else np.zeros(3)
            ba = gt[start, 13:16] if with_bias else np.zeros(3)
            i = int(np.searchsorted(ti, t0))
            j = start
            marks = {}
            while i + 1 < len(ti) and ti[i] < t0 + 10_000_000_000:
                dt = (ti[i + 1] - ti[i]) * 1e-9
                acc = R @ (imu[i, 3:6] - ba) + g
                p = p + v * dt + 0.5 * acc * dt * dt
                v = v + acc * dt
                R = R @ so3_exp((imu[i, 0:3] - bw) * dt)
                i += 1
                while j < len(tg) and tg[j] < ti[i]:
                    j += 1
                el = ti[i] - t0
                if j < len(tg) and tg[j] == ti[i] and el in (1e9, 2e9, 5e9, 10e9):
                    marks[el // 1_000_000_000] = (np.linalg.norm(p - gt[j, 0:3]),
                                                  np.linalg.norm(v - gt[j, 7:10]))
            print("  from ground-truth row %4d, %s: %s" % (
                start + 1, "with its biases   " if with_bias else "without biases    ",
                "  ".join("%2d s: %.2f m %.2f m/s" % (k, *marks[k]) for k in sorted(marks))))


def decode_truth(data):
    """A TRUTH message: truth_t, or truth_v1_t for logs written before kind[] (LCM's fingerprint
    differs, so truth_t refuses those)."""
    from sfd import truth_t, truth_v1_t
    try:
        return truth_t.decode(data)
    except ValueError:
        return truth_v1_t.decode(data)


def check_kinds(path):
    sys.path.insert(0, os.environ.get("SFD_LCM_PYTHON", ""))
    import lcm
    from sfd import feature_verdict_t
    truth, verdict = {}, {}
    for ev in lcm.EventLog(path, "r"):
        if ev.channel == "TRUTH":
            m = decode_truth(ev.data)
            truth[m.utime] = {m.track_id[i]: m.spurious[i] for i in range(m.num_features)}
        elif ev.channel == "SFD_VERDICT":
            m = feature_verdict_t.decode(ev.data)
            verdict[m.utime] = {m.track_id[i]: m.status[i] for i in range(m.num_features)}
    labels = collections.defaultdict(list)
    for t in sorted(truth):
        for i, s in truth[t].items():
            labels[i].append(s)
    movers = {i for i, l in labels.items() if all(l)}
    c = collections.Counter()
    for t, fv in verdict.items():
        for i, st in fv.items():
            if truth.get(t, {}).get(i, 0):
                c[("moving group" if i in movers else "steps", st)] += 1
    for kind in ["moving group", "steps"]:
        n = sum(c[(kind, s)] for s in (0, 1, 2))
        if n:
            print("%-12s %6d spurious (feature, frame) pairs: SPURIOUS %.3f, UNTESTED %.3f" %
                  (kind, n, c[(kind, 2)] / n, c[(kind, 0)] / n))


def check_trace(path, every):
    sys.path.insert(0, os.environ.get("SFD_LCM_PYTHON", ""))
    import lcm
    from sfd import nav_state_t
    st, tr = {}, {}
    for ev in lcm.EventLog(path, "r"):
        if ev.channel == "SFD_STATE":
            m = nav_state_t.decode(ev.data)
            st[m.utime] = (np.array(m.position), np.array(m.velocity), m.orientation,
                           np.sqrt(np.array(m.position_var)))
        elif ev.channel == "TRUTH":
            m = decode_truth(ev.data)
            tr[m.utime] = (np.array(m.position), m.orientation)
    ts = sorted(set(st) & set(tr))
    print("   t (s)  |dp| (m)  |dv| (m/s)  attitude (deg)  position sd (m, x y z)")
    for k in range(0, len(ts), every):
        t = ts[k]
        if 0 < k < len(ts) - 1:
            v_true = (tr[ts[k + 1]][0] - tr[ts[k - 1]][0]) / ((ts[k + 1] - ts[k - 1]) * 1e-6)
            dv = "%10.3f" % np.linalg.norm(st[t][1] - v_true)
        else:
            dv = "       n/a"
        att = np.degrees(so3_angle(q_to_R(tr[t][1]).T @ q_to_R(st[t][2])))
        print("%8.2f  %8.3f  %s  %14.2f  %s" % ((t - ts[0]) * 1e-6, np.linalg.norm(st[t][0] - tr[t][0]),
                                               dv, att, " ".join("%.3f" % x for x in st[t][3])))


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sfd_tool_cli.add_version(ap, "semireal_checks.py")
    sub = ap.add_subparsers(dest="cmd", required=True)
    a_imu = sub.add_parser("imu")
    a_imu.add_argument("--data", default=os.path.join(os.path.dirname(root), "shared", "data",
                                                      "euroc_v1_02_imu_gt"))
    a_k = sub.add_parser("kinds")
    a_k.add_argument("log")
    a_t = sub.add_parser("trace")
    a_t.add_argument("log")
    a_t.add_argument("--every", type=int, default=80)
    a = ap.parse_args()
    os.environ.setdefault("SFD_LCM_PYTHON",
                          os.path.join(root, "build", "host", "lcm_types", "python"))
    if a.cmd == "imu":
        check_imu(a.data)
    elif a.cmd == "kinds":
        check_kinds(a.log)
    else:
        check_trace(a.log, a.every)


if __name__ == "__main__":
    main()
