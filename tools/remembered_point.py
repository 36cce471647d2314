#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Offline experiment (evaluation only: it reads TRUTH's poses): what a test of each observation
against the track's point remembered from before the detector's window would add to a replay's
verdicts (docs/evaluation.md "How much of the drift any test can catch").

For every observation the replay judged (CONSISTENT or SPURIOUS), the track's remembered point is
triangulated (Gauss-Newton; the depth priors as measurements, variance at least 1e-4 m^2) from
its own earlier observations that are at least --window frames older, newest --memory of them,
since the track's last flag, at TRUE camera poses (TRUTH's IMU pose and CAMERA_INFO's
T_imu_cam). The observation is tested against the point's projection: NIS = r^T S^-1 r with S
the pixel noise (--sigma-px per axis, through the undistortion's Jacobian) plus the point's
covariance projected; an observation is flagged when NIS exceeds the chi-square (2 dof)
threshold at --alpha. A flag, the replay's or this test's, starts the track's memory again.
At least 3 remembered observations are needed; with fewer the observation is not tested here.

Printed: how many clean observations had a remembered point and their mean NIS (2 when
calibrated); the replay's true and false positives, F1 (strict: UNTESTED spurious = miss) and
false-alarm rate; and the same with this test's flags among the replay's CONSISTENT verdicts
added, per kind.

Usage: remembered_point.py IN.lcmlog REPLAY.lcmlog --sigma-px S [--window 5] [--memory 10]
           [--alpha 0.003]
IN is an sfd-sim log (with TRUTH and CAMERA_INFO), REPLAY the sfd-replay OUT log of it.
The sims' pixel noise by default (sfd-sim --pixel-sigma-px): 1 px on the flights, 0.5 px on
euroc-semireal.
Exit 0; 2 for bad usage or an unreadable log."""
import argparse
import collections
import math
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py


def fail(msg):
    """Bad usage or input: one line on stderr, exit 2."""
    print(f"remembered_point.py: {msg}", file=sys.stderr)
    sys.exit(2)


def quat_rot(q, np):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def main():
    ap = argparse.ArgumentParser(prog="remembered_point.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "remembered_point.py")
    ap.add_argument("input", metavar="IN.lcmlog")
    ap.add_argument("replay", metavar="REPLAY.lcmlog")
    ap.add_argument("--sigma-px", type=float, required=True)
    ap.add_argument("--window", type=int, default=5)
    ap.add_argument("--memory", type=int, default=10)
    ap.add_argument("--alpha", type=float, default=0.003)
    a = ap.parse_args()
    if not (a.sigma_px > 0 and a.window >= 1 and a.memory >= 3 and 0 < a.alpha < 0.5):
        fail("want --sigma-px > 0, --window >= 1, --memory >= 3, 0 < --alpha < 0.5")
    try:
        import lcm
        import numpy as np
    except ImportError:
        fail("the Python modules 'lcm' and 'numpy' are needed (tools/setup.sh installs them)")
    sfd = sfd_tool_cli.import_lcm_types("remembered_point.py")
    cam, feats, truth, verd = None, {}, {}, {}
    try:
        for e in lcm.EventLog(a.input, "r"):
            if e.channel == "CAMERA_INFO" and cam is None:
                cam = sfd.camera_info_t.decode(e.data)
            elif e.channel == "FEATURES":
                m = sfd.feature_frame_t.decode(e.data)
                feats[m.utime] = m
            elif e.channel == "TRUTH":
                m = sfd.truth_t.decode(e.data)
                truth[m.utime] = m
        for e in lcm.EventLog(a.replay, "r"):
            if e.channel == "SFD_VERDICT":
                m = sfd.feature_verdict_t.decode(e.data)
                verd[m.utime] = {m.track_id[i]: m.status[i] for i in range(m.num_features)}
    except (IOError, ValueError) as e:
        fail(f"cannot read the logs: {e}")
    if cam is None or not truth or not verd:
        fail("IN needs CAMERA_INFO, FEATURES and TRUTH; REPLAY needs SFD_VERDICT")
    if cam.distortion_model != 1 and any(cam.distortion):
        fail("only the pinhole and radtan camera models are handled")
    fx, fy, cx, cy = cam.fx, cam.fy, cam.cx, cam.cy
    k1, k2, p1, p2 = cam.distortion if cam.distortion_model == 1 else (0.0, 0.0, 0.0, 0.0)
    T = np.array(cam.T_imu_cam).reshape(4, 4)
    R_IC, t_IC = T[:3, :3], T[:3, 3]
    thr = -2.0 * math.log(a.alpha)

    def distort(x, y):
        r2 = x * x + y * y
        rad = 1 + k1 * r2 + k2 * r2 * r2
        return (x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)

    def undistort(u, v):
        xd, yd = (u - cx) / fx, (v - cy) / fy
        x, y = xd.copy(), yd.copy()
        for _ in range(30):  # fixed point; converges for the EuRoC lens inside the image
            dx, dy = distort(x, y)
            x, y = x - (dx - xd), y - (dy - yd)
        return x, y

    def proj_jac(q, R_CW):
        return np.array([[1 / q[2], 0, -q[0] / q[2] ** 2], [0, 1 / q[2], -q[1] / q[2] ** 2]]) @ R_CW

    # track: [(frame, xn, Cn^-1, R_CW, p_C, depth, depth var, flagged)]
    hist = collections.defaultdict(list)
    rec = []  # (kind, replay status, NIS or None)
    h = 1e-3
    for fi, t in enumerate(sorted(u for u in feats if u in truth)):
        F, Tr, V = feats[t], truth[t], verd.get(t, {})
        kind = {Tr.track_id[i]: Tr.kind[i] for i in range(Tr.num_features)}
        R_WI = quat_rot(Tr.orientation, np)
        R_CW = (R_WI @ R_IC).T
        p_C = np.array(Tr.position) + R_WI @ t_IC
        n = F.num_features
        u, v = np.array(F.u[:n]), np.array(F.v[:n])
        x, y = undistort(u, v)
        xu, yu = undistort(u + h, v)
        xv, yv = undistort(u, v + h)
        for i in range(n):
            tid, st = F.track_id[i], V.get(F.track_id[i], 0)
            J = np.array([[(xu[i] - x[i]) / h, (xv[i] - x[i]) / h],
                          [(yu[i] - y[i]) / h, (yv[i] - y[i]) / h]])
            Cn = a.sigma_px ** 2 * (J @ J.T)
            H = hist[tid]
            last_flag = max([o[0] for o in H if o[7]], default=-1)
            old = [o for o in H if last_flag < o[0] <= fi - a.window][-a.memory:]
            nis = None
            if st in (1, 2) and len(old) >= 3:
                o0 = old[-1]
                d0 = o0[5] if o0[5] > 0 else 5.0
                p = o0[4] + o0[3].T @ (np.array([o0[1][0], o0[1][1], 1.0]) * d0)
                ok = True
                for _ in range(5):
                    A, b = np.zeros((3, 3)), np.zeros(3)
                    for (_, xn, Wi, Rcw, pc, dep, dv, _f) in old:
                        q = Rcw @ (p - pc)
                        if q[2] <= 1e-3:
                            ok = False
                            break
                        Jp = proj_jac(q, Rcw)
                        A += Jp.T @ Wi @ Jp
                        b += Jp.T @ Wi @ (np.array(xn) - q[:2] / q[2])
                        if dep > 0:
                            var = max(dv, 1e-4)
                            A += np.outer(Rcw[2], Rcw[2]) / var
                            b += Rcw[2] * (dep - q[2]) / var
                    if not ok:
                        break
                    try:
                        dp = np.linalg.solve(A, b)
                    except np.linalg.LinAlgError:
                        ok = False
                        break
                    p = p + dp
                    if np.linalg.norm(dp) < 1e-9:
                        break
                q = R_CW @ (p - p_C)
                if ok and q[2] > 1e-3:
                    Jp = proj_jac(q, R_CW)
                    S = Cn + Jp @ np.linalg.inv(A) @ Jp.T
                    r = np.array([x[i], y[i]]) - q[:2] / q[2]
                    nis = float(r @ np.linalg.solve(S, r))
            rec.append((kind.get(tid, -1), st, nis))
            flagged = st == 2 or (st == 1 and nis is not None and nis > thr)
            # the weight Cn^-1 kept, not Cn: every later triangulation of the track reads it
            H.append((fi, (x[i], y[i]), np.linalg.inv(Cn), R_CW, p_C, F.depth[i],
                      F.depth_var[i], flagged))
            if len(H) > a.window + a.memory + 40:
                del H[0]

    names = {0: "clean", 1: "jump", 2: "drift", 3: "moving", 4: "mismatch", 5: "unspecified"}
    tot = collections.Counter(k for k, _, _ in rec if k >= 0)
    tp = sum(1 for k, s, _ in rec if k > 0 and s == 2)
    fp = sum(1 for k, s, _ in rec if k == 0 and s == 2)
    sp = sum(1 for k, _, _ in rec if k > 0)
    extra = collections.Counter(k for k, s, z in rec if k >= 0 and s == 1 and z is not None and
                                z > thr)
    cl = [z for k, s, z in rec if k == 0 and s == 1 and z is not None]
    tp2, fp2 = tp + sum(extra[k] for k in tot if k > 0), fp + extra[0]

    def f1(t, f):
        return 2 * t / (2 * t + f + sp - t) if sp else float("nan")

    print(f"clean CONSISTENT observations with a remembered point: {len(cl)} of {tot[0]}, mean "
          f"NIS {sum(cl) / max(1, len(cl)):.3f} (2 when calibrated)")
    print(f"replay: TP {tp}, FP {fp}, spurious {sp}, F1 {f1(tp, fp):.4f}, false alarms "
          f"{fp / max(1, tot[0]):.4f}")
    print(f"+ remembered point at alpha {a.alpha:g} (window {a.window}, memory {a.memory}): TP "
          f"{tp2}, FP {fp2}, F1 {f1(tp2, fp2):.4f}, false alarms {fp2 / max(1, tot[0]):.4f}")
    print("recall per kind, replay -> with the test: " + ", ".join(
        f"{names.get(k, k)} {sum(1 for kk, s, _ in rec if kk == k and s == 2) / tot[k]:.3f} -> "
        f"{(sum(1 for kk, s, _ in rec if kk == k and s == 2) + extra[k]) / tot[k]:.3f}"
        for k in sorted(tot) if k > 0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
