#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Overlays of sfd-replay verdicts on real images, and the fraction judged spurious per frame.

usage: euroc_overlay.py --images DIR --out-dir DIR [--every-frame] [--gt CSV --calib YAML]
                        RUN=OUT.lcmlog [RUN=...]

Each RUN names one sfd-replay OUT log (e.g. fb/parity=out/euroc/fb_parity.out.lcmlog); the log
holds the input FEATURES (copied by sfd-replay) and the SFD_VERDICT the node published for them.
Images are found by time: a frame with utime U (us) is the file <ns>.png/.jpg of --images with
ns // 1000 == U (sfd-euroc writes utime = ns // 1000).

Writes into --out-dir:
  spurious_fraction.csv  run, frame index, utime, features, tested, spurious, fraction
                         (spurious / tested; empty when nothing was tested)
  spurious_fraction.md   the same as a table: one row per run, one column per frame
  flagged_tracks.csv     every SPURIOUS verdict: run, frame, track id, u, v, displacement
                         from the previous frame (px), statistic, stage
  <run>/frame_<k>.png    (with --every-frame, else only frames with a SPURIOUS verdict) the
                         image with each feature as a dot coloured by verdict (green consistent,
                         red spurious, grey untested) and a line to its previous position
                         (its track motion since the last frame), red circles around spurious.
With --gt (EuRoC ground truth: t [ns], p xyz, q wxyz) and --calib (EuRoC camera sensor.yaml), an
independent check of every track: its epipolar (Sampson) distance between the previous frame
and this one under the ground-truth motion (Hartley & Zisserman, eq. 11.9), in pixels (normalized
coordinates times fx); a correct track has a small one (ground-truth and calibration errors
only), a mistrack across its epipolar line a large one (a mistrack along the line is invisible).
It goes into flagged_tracks.csv (epi_px), epipolar.md (distribution for flagged and not flagged
features per run) and the PNGs (a yellow square around a track with epi_px > --epi-px).
With --crops ID,ID,... --crops-run RUN: crops_<RUN>.png, one row per track id, one 61 x 61 px
crop per frame centred on the track (a cross coloured by verdict), to judge by eye whether a
track stays on its point.
Deterministic: same logs and images give the same CSV/markdown (PNG bytes depend on matplotlib).
"""
import argparse
import csv
import os
import sys
import sfd_tool_cli  # tools/sfd_tool_cli.py

import lcm
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

try:  # the generated LCM types: PYTHONPATH, else $SFD_LCM_PYTHON, else build/host's (review.py)
    from sfd import feature_frame_t, feature_verdict_t  # noqa: E402
except ImportError:
    for _p in (os.environ.get("SFD_LCM_PYTHON", ""), os.path.join(
            os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "build", "host",
            "lcm_types", "python")):
        if _p and os.path.isdir(os.path.join(_p, "sfd")):
            sys.path.insert(0, _p)
            break
    try:
        from sfd import feature_frame_t, feature_verdict_t  # noqa: E402
    except ImportError:  # reported by main() after --help / --version
        feature_frame_t = feature_verdict_t = None

STATUS_NAME = {0: "untested", 1: "consistent", 2: "spurious"}
STAGE_NAME = {0: "none", 1: "parity", 2: "oprf", 3: "ransac1", 4: "ransacf"}


def read_run(path, features_channel="FEATURES", verdict_channel="SFD_VERDICT"):
    """Frames of one OUT log: {utime: (features dict id->(u, v), verdict list)}."""
    frames, verdicts = {}, {}
    for ev in lcm.EventLog(path, "r"):
        if ev.channel == features_channel:
            f = feature_frame_t.decode(ev.data)
            n = f.num_features
            frames[f.utime] = {f.track_id[i]: (f.u[i], f.v[i]) for i in range(n)}
        elif ev.channel == verdict_channel:
            v = feature_verdict_t.decode(ev.data)
            n = v.num_features
            verdicts[v.utime] = [(v.track_id[i], v.status[i], v.statistic[i], v.stage[i])
                                 for i in range(n)]
    return frames, verdicts


def read_calib(path):
    """EuRoC camera sensor.yaml: (fx, fy, cx, cy), radtan (k1, k2, p1, p2), T_BS (4x4)."""
    txt = open(path).read()

    def seq(key):
        t = txt[txt.index(key):]
        t = t[t.index("[") + 1:t.index("]")]
        return [float(x) for x in t.replace("\n", " ").split(",")]
    if "radial-tangential" not in txt:
        sys.exit(f"euroc_overlay: {path}: only radial-tangential distortion is supported")
    T = np.array(seq("data:")).reshape(4, 4)
    return seq("intrinsics:"), seq("distortion_coefficients:"), T


def undistort(uv, intr, dist, iterations=30):
    """Normalized undistorted coordinates of raw pixels (radtan, fixed-point iteration)."""
    fx, fy, cx, cy = intr
    k1, k2, p1, p2 = dist
    xd = np.array([(uv[:, 0] - cx) / fx, (uv[:, 1] - cy) / fy]).T
    x = xd.copy()
    for _ in range(iterations):
        r2 = (x ** 2).sum(1)
        rad = 1 + k1 * r2 + k2 * r2 * r2
        dx = 2 * p1 * x[:, 0] * x[:, 1] + p2 * (r2 + 2 * x[:, 0] ** 2)
        dy = p1 * (r2 + 2 * x[:, 1] ** 2) + 2 * p2 * x[:, 0] * x[:, 1]
        x = np.array([(xd[:, 0] - dx) / rad, (xd[:, 1] - dy) / rad]).T
    return x


def quat_to_R(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def read_gt(path):
    t, p, q = [], [], []
    for row in csv.reader(open(path)):
        if not row or row[0].strip().startswith("#"):
            continue
        t.append(int(row[0]))
        p.append([float(v) for v in row[1:4]])
        q.append([float(v) for v in row[4:8]])
    return np.array(t, dtype=np.int64), np.array(p), np.array(q)


def camera_pose(gt, utime, T_BS):
    """World pose (R_WC, p_WC) of the camera at utime (us): GT interpolated (linear, normalized
    linear for the quaternion: the rows are 50 ms apart), composed with T_BS."""
    t, p, q = gt
    tn = utime * 1000
    i = int(np.searchsorted(t, tn))
    if i < len(t) and t[i] == tn:
        pw, qw = p[i], q[i]
    elif i == 0 or i >= len(t):
        return None
    else:
        s = (tn - t[i - 1]) / (t[i] - t[i - 1])
        qb = q[i] if np.dot(q[i - 1], q[i]) >= 0 else -q[i]
        pw, qw = (1 - s) * p[i - 1] + s * p[i], (1 - s) * q[i - 1] + s * qb
    R_WB = quat_to_R(np.asarray(qw))
    return R_WB @ T_BS[:3, :3], pw + R_WB @ T_BS[:3, 3]


def epipolar_px(pose_a, pose_b, xa, xb, fx):
    """Sampson distance (px) of normalized correspondences xa (frame a) -> xb (frame b)."""
    R_WCa, p_a = pose_a
    R_WCb, p_b = pose_b
    R = R_WCb.T @ R_WCa
    t = R_WCb.T @ (p_a - p_b)
    tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    E = tx @ R
    a = np.c_[xa, np.ones(len(xa))]
    b = np.c_[xb, np.ones(len(xb))]
    Ea = a @ E.T
    Etb = b @ E
    num = (b * Ea).sum(1) ** 2
    den = Ea[:, 0] ** 2 + Ea[:, 1] ** 2 + Etb[:, 0] ** 2 + Etb[:, 1] ** 2
    return fx * np.sqrt(num / den)


def draw_crops(images, frames, verdicts, ids, png, half=30):
    utimes = sorted(frames)
    fig, axs = plt.subplots(len(ids), len(utimes), figsize=(1.2 * len(utimes), 1.3 * len(ids)),
                            squeeze=False)
    colours = {0: "#b0b0b0", 1: "#20d020", 2: "#ff2020"}
    for r, tid in enumerate(ids):
        for k, ut in enumerate(utimes):
            ax = axs[r, k]
            ax.axis("off")
            if tid not in frames[ut] or ut not in images:
                continue
            img = plt.imread(images[ut])
            img = img[..., 0] if img.ndim == 3 else img
            u, v = frames[ut][tid]
            ui, vi = int(round(u)), int(round(v))
            pad = np.pad(img, half)
            ax.imshow(pad[vi:vi + 2 * half + 1, ui:ui + 2 * half + 1], cmap="gray", vmin=0,
                      vmax=255 if img.dtype == np.uint8 else 1.0,
                      extent=(ui - half - 0.5, ui + half + 0.5, vi + half + 0.5, vi - half - 0.5))
            status = dict((t, s) for t, s, _, _ in verdicts.get(ut, [])).get(tid, 0)
            ax.plot(u, v, "+", color=colours[status], ms=10, mew=1.5)
            ax.set_title(f"{tid} f{k}", fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)


def image_index(folder):
    out = {}
    for name in sorted(os.listdir(folder)):
        stem, ext = os.path.splitext(name)
        if ext.lower() in (".png", ".jpg", ".jpeg") and stem.isdigit():
            out[int(stem) // 1000] = os.path.join(folder, name)
    return out


def draw(img_path, title, feats, prev_feats, verdict, png, epi=None, epi_limit=2.0):
    img = plt.imread(img_path)
    if img.ndim == 3:
        img = img[..., 0]
    h, w = img.shape[:2]
    fig = plt.figure(figsize=(w / 80.0, h / 80.0), dpi=80)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.imshow(img, cmap="gray", vmin=0, vmax=255 if img.dtype == np.uint8 else 1.0)
    colours = {0: "#b0b0b0", 1: "#20d020", 2: "#ff2020"}
    for tid, status, _, _ in verdict:
        if tid not in feats:
            continue
        u, v = feats[tid]
        if tid in prev_feats:
            pu, pv = prev_feats[tid]
            ax.plot([pu, u], [pv, v], "-", color=colours[status], lw=1.0)
        ax.plot(u, v, "o", ms=3.0, color=colours[status])
        if status == 2:
            ax.plot(u, v, "o", ms=11.0, mfc="none", mec="#ff2020", mew=1.5)
            ax.text(u + 7, v - 5, str(tid), color="#ffff40", fontsize=8)
        if epi is not None and epi.get(tid, 0.0) > epi_limit:
            ax.plot(u, v, "s", ms=15.0, mfc="none", mec="#ffff00", mew=1.2)
    ax.text(5, 15, title, color="#ffff40", fontsize=10,
            bbox=dict(facecolor="black", alpha=0.6, lw=0))
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.axis("off")
    fig.savefig(png, dpi=80)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sfd_tool_cli.add_version(ap, "euroc_overlay.py")
    ap.add_argument("--images", required=True, help="folder of <ns>.png/.jpg frames")
    ap.add_argument("--out-dir", required=True)
    ap.add_argument("--every-frame", action="store_true",
                    help="write a PNG for every judged frame, not only those with SPURIOUS")
    ap.add_argument("--gt", help="EuRoC ground-truth CSV: epipolar check of every track")
    ap.add_argument("--calib", help="EuRoC camera sensor.yaml (with --gt)")
    ap.add_argument("--epi-px", type=float, default=2.0,
                    help="epipolar distance marked in the PNGs (px, default 2)")
    ap.add_argument("--crops", help="track ids (comma-separated) for crops_<RUN>.png")
    ap.add_argument("--crops-run", help="the RUN whose verdicts colour the crops")
    ap.add_argument("runs", nargs="+", help="RUN=OUT.lcmlog (sfd-replay -o)")
    a = ap.parse_args()
    if feature_frame_t is None:
        print("euroc_overlay.py: no generated LCM types (package sfd): build the host preset or "
              "set SFD_LCM_PYTHON", file=sys.stderr)
        return 2
    if bool(a.gt) != bool(a.calib):
        sys.exit("euroc_overlay: --gt and --calib go together")
    gt = read_gt(a.gt) if a.gt else None
    calib = read_calib(a.calib) if a.calib else None
    epi_stats = {}
    images = image_index(a.images)
    if not images:
        sys.exit(f"euroc_overlay: {a.images}: no <ns>.png/.jpg images")
    os.makedirs(a.out_dir, exist_ok=True)
    rows, flagged, table = [], [], {}
    for spec in a.runs:
        if "=" not in spec:
            sys.exit(f"euroc_overlay: expected RUN=OUT.lcmlog, got {spec}")
        run, path = spec.split("=", 1)
        if not os.path.isfile(path):
            sys.exit(f"euroc_overlay: {path}: no such file")
        frames, verdicts = read_run(path)
        if not verdicts:
            sys.exit(f"euroc_overlay: {path}: no SFD_VERDICT (is it an sfd-replay -o log?)")
        if a.crops and run == a.crops_run:
            ids = [int(x) for x in a.crops.split(",") if x.strip()]
            draw_crops(images, frames, verdicts, ids,
                       os.path.join(a.out_dir, f"crops_{run.replace('/', '_')}.png"))
        run_dir = os.path.join(a.out_dir, run.replace("/", "_"))
        os.makedirs(run_dir, exist_ok=True)
        utimes = sorted(frames)
        table[run] = []
        for k, ut in enumerate(utimes):
            feats = frames[ut]
            prev = frames[utimes[k - 1]] if k > 0 else {}
            verdict = verdicts.get(ut, [])
            epi = None
            if gt is not None and k > 0:
                pa, pb = camera_pose(gt, utimes[k - 1], calib[2]), camera_pose(gt, ut, calib[2])
                common = [tid for tid in sorted(feats) if tid in prev]
                if pa is not None and pb is not None and common:
                    xa = undistort(np.array([prev[t] for t in common]), calib[0], calib[1])
                    xb = undistort(np.array([feats[t] for t in common]), calib[0], calib[1])
                    d = epipolar_px(pa, pb, xa, xb, calib[0][0])
                    epi = dict(zip(common, d))
                    st = epi_stats.setdefault(run, {"flagged": [], "kept": []})
                    for tid, s_, _, _ in verdict:
                        if s_ != 0 and tid in epi:
                            st["flagged" if s_ == 2 else "kept"].append(epi[tid])
            tested = sum(1 for _, s, _, _ in verdict if s != 0)
            spurious = sum(1 for _, s, _, _ in verdict if s == 2)
            frac = spurious / tested if tested else None
            rows.append([run, k, ut, len(feats), tested, spurious,
                         "" if frac is None else f"{frac:.4f}"])
            table[run].append("–" if frac is None else f"{100 * frac:.1f}% ({spurious}/{tested})")
            for tid, s, stat, stage in verdict:
                if s != 2 or tid not in feats:
                    continue
                u, v = feats[tid]
                disp = ""
                if tid in prev:
                    disp = f"{np.hypot(u - prev[tid][0], v - prev[tid][1]):.2f}"
                e = "" if epi is None or tid not in epi else f"{epi[tid]:.3f}"
                flagged.append([run, k, ut, tid, f"{u:.1f}", f"{v:.1f}", disp, f"{stat:.3f}",
                                STAGE_NAME.get(stage, str(stage)), e])
            if (spurious > 0 or a.every_frame) and ut in images and verdict:
                title = (f"{run}  frame {k}  {spurious}/{tested} spurious"
                         if tested else f"{run}  frame {k}  untested")
                draw(images[ut], title, feats, prev, verdict,
                     os.path.join(run_dir, f"frame_{k}.png"), epi, a.epi_px)
    with open(os.path.join(a.out_dir, "spurious_fraction.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "frame", "utime", "features", "tested", "spurious", "fraction"])
        w.writerows(rows)
    with open(os.path.join(a.out_dir, "flagged_tracks.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "frame", "utime", "track_id", "u_px", "v_px", "disp_px", "statistic",
                    "stage", "epi_px"])
        w.writerows(flagged)
    n = max(len(v) for v in table.values())
    with open(os.path.join(a.out_dir, "spurious_fraction.md"), "w") as f:
        f.write("| run | " + " | ".join(f"frame {k}" for k in range(n)) + " |\n")
        f.write("| --- |" + " --- |" * n + "\n")
        for run, cells in table.items():
            f.write(f"| {run} | " + " | ".join(cells) + " |\n")
    print(open(os.path.join(a.out_dir, "spurious_fraction.md")).read(), end="")
    if epi_stats:
        with open(os.path.join(a.out_dir, "epipolar.md"), "w") as f:
            f.write(f"Epipolar (Sampson) distance under the ground-truth motion, previous frame to "
                    f"this one, of the tested features (px)\n\n| run | verdict | n | median | "
                    f"p90 | max | > {a.epi_px:g} px |\n| --- | --- | --- | --- | --- | --- | --- |\n")
            for run, st in epi_stats.items():
                for key in ["flagged", "kept"]:
                    v = np.array(st[key])
                    if len(v) == 0:
                        f.write(f"| {run} | {key} | 0 | – | – | – | – |\n")
                        continue
                    # Nearest rank (numpy's inverted_cdf), the one rule of sfd_eval.hpp.
                    med, p90 = np.percentile(v, [50, 90], method="inverted_cdf")
                    f.write(f"| {run} | {key} | {len(v)} | {med:.3f} | "
                            f"{p90:.3f} | {v.max():.3f} | "
                            f"{int((v > a.epi_px).sum())} |\n")
        print(open(os.path.join(a.out_dir, "epipolar.md")).read(), end="")
    print(f"euroc_overlay: {len(rows)} frames, {len(flagged)} spurious verdicts; "
          f"wrote {a.out_dir}/spurious_fraction.{{csv,md}}, flagged_tracks.csv, <run>/frame_*.png")


if __name__ == "__main__":
    sys.exit(main())
