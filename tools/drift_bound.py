#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""How much of the simulated flights' slow drift any detector can catch, and the F1 that allows
(docs/evaluation.md "How far the flights' drifts can be caught").

sfd-sim's flights (apps/sim/flight_log.cpp) slide a drifting track by v px per frame for D frames,
v uniform in [kDriftMinPx, kDriftMaxPx], D uniform in {kDriftMinFrames .. kDriftMaxFrames}, in a
random direction, with pixel noise sigma px per axis (apps/sim/main.cpp); the slide's k-th frame
is k v away from the projection of the point the track followed before. The evaluation labels
the D slid frames and the W - 1 after them spurious (W = --truth-window, 2: docs/evaluation.md
"Labels"); after the slide the track follows the scene point under it, D v away from the old one.

For each labelled observation this tool computes the probability that a test at level alpha
per observation flags it, for detectors that know more than any real one:

  oracle      knows the slide's start, direction and rate, the old point and the true poses:
              the most powerful test of all the slide's observations so far (Neyman-Pearson,
              one-sided, noncentrality sum of (offset / sigma)^2);
  known-start knows the start, the old point and the poses, not the direction or rate: the
              GLR of the ramp's 2-vector over the slide so far (chi-square, 2 dof);
  window-5    the same over the newest 5 observations only (the longest window sfd's evidence
              test sees, SFD_MAX_WINDOW = 5), the old point still known;
  single      the observation alone against the known old point (2 dof);
  remembered  the same against the old point's projection averaged over --memory N earlier
              observations (its error sigma^2 / N per axis added to the residual's; poses still
              exact: of these, the closest to a test against a point remembered from before
              the window).

The recall is pooled over labels (a long slide labels more frames), averaged over --events
Monte Carlo slides (seeded). The model assumes every slide stays in the image; a real slide that
leaves it loses its later, larger offsets, so the real ceiling is, if anything, lower.

With --results RESULTS.csv (tools/evaluate.py), the F1 each scenario would reach if the drift
recall were each bound's and every other count (true and false positives of the other kinds)
stayed as measured: 2 TP / (2 TP + FP + FN), per run, mean over the seeds of --method at
--alpha. The tool checks that the same formula gives the measured F1 before substituting.

--rate-px, --frames and --sigma-px replace the sim's constants, e.g. --rate-px 1.5 1.5 --frames
5 5 --sigma-px 0.5 --scenarios euroc-semireal for the semi-real logs' drift
(apps/sim/euroc_semireal.hpp).

Usage: drift_bound.py [--results RESULTS.csv] [--method both] [--alpha 0.01] [--events 20000]
           [--seed 1] [--truth-window 2] [--memory 10] [--sim-source apps/sim] [--rate-px MIN MAX]
           [--frames MIN MAX] [--sigma-px S] [--scenarios mistracking moving-object]
Exit 0; 2 for bad usage, an unreadable results file, or constants not found in the sim source."""
import argparse
import csv
import os
import random
import re
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py

try:
    import numpy as np
    from scipy.stats import chi2, ncx2, norm
except ImportError:
    print("drift_bound.py: numpy and scipy are missing (tools/setup.sh installs them)",
          file=sys.stderr)
    sys.exit(2)

_ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def fail(msg):
    """Bad usage or input: one line on stderr, exit 2."""
    print(f"drift_bound.py: {msg}", file=sys.stderr)
    sys.exit(2)


def sim_constants(src_dir):
    """The drift's rate and length range and the default pixel noise, read from the sim source
    so that the bound follows any change there."""
    try:
        flight = open(os.path.join(src_dir, "flight_log.cpp"), encoding="utf-8").read()
        main = open(os.path.join(src_dir, "main.cpp"), encoding="utf-8").read()
    except OSError as e:
        fail(f"{e.filename}: {e.strerror}")
    px = re.search(r"kDriftMinPx\s*=\s*([0-9.]+),\s*kDriftMaxPx\s*=\s*([0-9.]+)", flight)
    fr = re.search(r"kDriftMinFrames\s*=\s*(\d+),\s*kDriftMaxFrames\s*=\s*(\d+)", flight)
    sg = re.search(r"double pixel_noise\s*=\s*([0-9.]+);", main)
    if not (px and fr and sg):
        fail(f"{src_dir}: kDriftMinPx/kDriftMaxPx, kDriftMinFrames/kDriftMaxFrames or "
             "pixel_noise not found")
    return (float(px.group(1)), float(px.group(2)), int(fr.group(1)), int(fr.group(2)),
            float(sg.group(1)))


def bounds(consts, alpha, truth_window, events, seed, memory):
    """Pooled recall of each detector over the labels of `events` simulated slides."""
    vmin, vmax, dmin, dmax, sigma = consts
    z = norm.isf(alpha)
    thr = chi2.isf(alpha, 2)
    rng = random.Random(seed)
    lam = []  # per label: the sums of squared coefficients (all so far, newest 5, own), v^2
    for _ in range(events):
        v = (vmin + (vmax - vmin) * rng.random()) / sigma
        d = rng.randint(dmin, dmax)
        # the coefficients c of v in each label's offset: k for the k-th slid frame, d after
        coef = list(range(1, d + 1)) + [d] * (truth_window - 1)
        cum = 0
        for i, c in enumerate(coef):
            cum += c * c
            win = sum(x * x for x in coef[max(0, i - 4):i + 1])
            lam.append((cum, win, c * c, v * v))
    cum, win, own, v2 = (np.array(x, dtype=float) for x in zip(*lam))
    caught = {
        "oracle": norm.cdf(np.sqrt(cum * v2) - z),
        "known-start": ncx2.sf(thr, 2, cum * v2),
        "window-5": ncx2.sf(thr, 2, win * v2),
        "single": ncx2.sf(thr, 2, own * v2),
        "remembered": ncx2.sf(thr, 2, own * v2 / (1.0 + 1.0 / memory)),
    }
    return {k: float(p.mean()) for k, p in caught.items()}, len(lam) / events


def f1_ceilings(path, method, alpha, recall, scenarios):
    """Mean F1 per scenario, measured and with each bound's drift recall, over the runs of
    `method` at `alpha` that have drift labels."""
    try:
        rows = list(csv.DictReader(open(path, encoding="utf-8")))
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    need = ("scenario", "method", "alpha", "tp", "fp", "spurious", "f1", "drift_spurious",
            "drift_detected")
    if not rows or any(k not in rows[0] for k in need):
        fail(f"{path}: not a tools/evaluate.py results.csv (columns {', '.join(need)})")
    out = {}
    for r in rows:
        if (r["method"] != method or abs(float(r["alpha"]) - alpha) > 1e-12 or
                r["scenario"] not in scenarios):
            continue
        ds = int(r["drift_spurious"])
        if ds == 0:
            continue
        tp, fp, sp = int(r["tp"]), int(r["fp"]), int(r["spurious"])
        f1 = 2 * tp / (2 * tp + fp + sp - tp)
        if abs(f1 - float(r["f1"])) > 1e-9:
            fail(f"{path}: {r['scenario']} seed {r['seed']}: F1 {r['f1']} is not 2TP/(2TP+FP+FN)")
        s = out.setdefault(r["scenario"], {"runs": 0, "f1": 0.0, "drift": 0.0,
                                           **{k: 0.0 for k in recall}})
        s["runs"] += 1
        s["f1"] += f1
        s["drift"] += int(r["drift_detected"]) / ds
        for k, rec in recall.items():
            tp2 = tp - int(r["drift_detected"]) + rec * ds
            s[k] += 2 * tp2 / (2 * tp2 + fp + sp - tp2)
    if not out:
        fail(f"{path}: no run of method {method} at alpha {alpha} with drift labels in "
             f"{' '.join(scenarios)}")
    for s in out.values():
        for k in list(s):
            if k != "runs":
                s[k] /= s["runs"]
    return out


def main():
    ap = argparse.ArgumentParser(prog="drift_bound.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "drift_bound.py")
    ap.add_argument("--results", metavar="RESULTS.csv")
    ap.add_argument("--method", default="both")
    ap.add_argument("--alpha", type=float, default=0.01)
    ap.add_argument("--events", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--truth-window", type=int, default=2)
    ap.add_argument("--memory", type=int, default=10, metavar="N",
                    help="observations the remembered point is averaged over (10)")
    ap.add_argument("--sim-source", default=os.path.join(_ROOT, "apps", "sim"))
    ap.add_argument("--rate-px", type=float, nargs=2, metavar=("MIN", "MAX"),
                    help="slide per frame (px), instead of the sim's constants")
    ap.add_argument("--frames", type=int, nargs=2, metavar=("MIN", "MAX"),
                    help="slid frames, instead of the sim's constants")
    ap.add_argument("--sigma-px", type=float, help="pixel noise per axis (px), instead of the "
                    "sim's default")
    ap.add_argument("--scenarios", nargs="+", default=["mistracking", "moving-object"],
                    help="the scenarios of RESULTS.csv whose drifts the model describes "
                    "(mistracking moving-object)")
    a = ap.parse_args()
    if not 0.0 < a.alpha < 0.5:
        fail(f"--alpha {a.alpha}: want 0 < alpha < 0.5")
    if a.events < 1 or a.truth_window < 1 or a.memory < 1:
        fail("--events, --truth-window and --memory want integers >= 1")
    consts = list(sim_constants(a.sim_source))
    if a.rate_px:
        consts[0:2] = a.rate_px
    if a.frames:
        consts[2:4] = a.frames
    if a.sigma_px is not None:
        consts[4] = a.sigma_px
    if not (0.0 <= consts[0] <= consts[1] and 1 <= consts[2] <= consts[3] and consts[4] > 0.0):
        fail("want 0 <= rate MIN <= MAX, 1 <= frames MIN <= MAX and sigma > 0")
    rec, per_event = bounds(consts, a.alpha, a.truth_window, a.events, a.seed, a.memory)
    vmin, vmax, dmin, dmax, sigma = consts
    print(f"slides: {vmin:g}-{vmax:g} px per frame for {dmin}-{dmax} frames, pixel noise "
          f"{sigma:g} px, W = {a.truth_window} ({per_event:.2f} labels per slide), alpha = "
          f"{a.alpha:g}, {a.events} slides, seed {a.seed}")
    print("| detector | drift recall ceiling |")
    print("| --- | ---: |")
    for k, v in rec.items():
        print(f"| {k} | {v:.3f} |")
    if a.results:
        out = f1_ceilings(a.results, a.method, a.alpha, rec, a.scenarios)
        print()
        print(f"F1 of {a.method} at alpha {a.alpha:g} with the drift recall replaced, every other "
              "count as measured (mean over seeds):")
        print("| scenario | runs | drift recall measured | F1 measured | " +
              " | ".join(f"F1 {k}" for k in rec) + " |")
        print("| --- | ---: | ---: | ---: | " + " | ".join("---:" for _ in rec) + " |")
        for sc, s in sorted(out.items()):
            print(f"| {sc} | {s['runs']} | {s['drift']:.3f} | {s['f1']:.3f} | " +
                  " | ".join(f"{s[k]:.3f}" for k in rec) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
