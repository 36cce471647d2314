#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Semi-real EuRoC V1_02 evaluation (apps/sim/SEMIREAL.md): writes `sfd-sim euroc-semireal` logs
(real IMU and ground-truth motion, simulated landmarks, spurious features labelled in TRUTH) for
each seed, replays each through `sfd-replay` with every method and a few filter configurations,
and writes the scores (precision, recall, F1, false-alarm rate against TRUTH; position RMSE of
SFD_STATE against TRUTH) as CSV and markdown.

Configurations (each starts from the one `--config-out` writes: filter started from TRUTH, the
ground truth's gyro and accelerometer biases at the start, pixel_sigma_px = the simulated noise):
  default           the node's other defaults (filter.consider_position 1)
  consider0         filter.consider_position 0 (the camera updates also correct the position)
  consider0_sigma1  consider0 and pixel_sigma_px 1.0
  consider0_nobias  consider0 without the ground truth's biases (initial biases 0)

Precision, recall, F1 and the false-alarm rate are pooled over the seeds (sums of TP, FP, TN, FN);
the RMSE is given as the mean over seeds with its range. Replays are deterministic; only the
per-frame time (timing.json, wall clock) varies from run to run.

usage: tools/semireal.py [--build build/host] [--data DIR] [--out out/semireal] [--seeds 1,2,3]
                         [--spurious-fraction 0.1]
"""
import argparse
import csv
import json
import os
import subprocess
import sys

METHODS = ["none", "parity", "oprf", "ransac1", "ransacf", "both"]
VARIANTS = {
    "default": "node defaults (filter.consider_position 1), ground-truth biases, pixel_sigma_px = simulated",
    "consider0": "filter.consider_position 0, ground-truth biases, pixel_sigma_px = simulated",
    "consider0_sigma1": "filter.consider_position 0, ground-truth biases, pixel_sigma_px 1.0",
    "consider0_nobias": "filter.consider_position 0, initial biases 0, pixel_sigma_px = simulated",
}
CLEAN_VARIANTS = ["default", "consider0", "consider0_sigma1"]


def variant_config(base, name):
    """The configuration text of a variant from the one sfd-sim wrote."""
    lines = base.splitlines()
    out = []
    for line in lines:
        if name == "consider0_sigma1" and line.startswith("pixel_sigma_px:"):
            line = "pixel_sigma_px: 1.0"
        if name == "consider0_nobias" and line.startswith("gyro_bias_rad_s:"):
            line = "gyro_bias_rad_s: [ 0.0, 0.0, 0.0 ]"
        if name == "consider0_nobias" and line.strip().startswith("init_accel_bias_m_s2:"):
            line = "   init_accel_bias_m_s2: [ 0.0, 0.0, 0.0 ]"
        out.append(line)
    if name.startswith("consider0"):
        out.append("   # variant %s" % name)
        out.append("   consider_position: 0")
    return "\n".join(out) + "\n"


def run(cmd, log):
    log.write("$ " + " ".join(cmd) + "\n")
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    log.write(r.stdout)
    if r.returncode != 0:
        sys.stderr.write(r.stderr)
        sys.exit("semireal.py: failed (%d): %s" % (r.returncode, " ".join(cmd)))
    return r.stdout


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.path.join(root, "build", "host"))
    ap.add_argument("--data", default=os.path.join(os.path.dirname(root), "shared", "data",
                                                   "euroc_v1_02_imu_gt"))
    ap.add_argument("--out", default=os.path.join(root, "out", "semireal"))
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--spurious-fraction", default="0.1")
    a = ap.parse_args()
    if not os.path.isfile(os.path.join(a.data, "mav0", "imu0", "data.csv")):
        sys.exit("semireal.py: %s: no mav0/imu0/data.csv (the shared EuRoC V1_02 data)" % a.data)
    seeds = [int(s) for s in a.seeds.split(",")]
    sim = os.path.join(a.build, "apps", "sfd-sim")
    replay = os.path.join(a.build, "apps", "sfd-replay")
    os.makedirs(os.path.join(a.out, "runs"), exist_ok=True)
    log = open(os.path.join(a.out, "commands.log"), "w")
    rows = []
    gen_lines = []
    for kind, frac, variants in [("spurious", a.spurious_fraction, list(VARIANTS)),
                                 ("clean", "0", CLEAN_VARIANTS)]:
        for seed in seeds:
            stem = os.path.join(a.out, "v1_02_%s_s%d" % (kind, seed))
            out = run([sim, "euroc-semireal", "--euroc", a.data, "-o", stem + ".lcmlog",
                       "--config-out", stem + ".yaml", "--seed", str(seed),
                       "--spurious-fraction", frac], log)
            gen_lines.append(out.strip().splitlines()[0])
            base = open(stem + ".yaml").read()
            for v in variants:
                cfg = os.path.join(a.out, "runs", "%s_s%d_%s.yaml" % (kind, seed, v))
                open(cfg, "w").write(variant_config(base, v))
                for m in METHODS:
                    summ = os.path.join(a.out, "runs", "%s_s%d_%s_%s.json" % (kind, seed, v, m))
                    run([replay, stem + ".lcmlog", "--config", cfg, "--method", m,
                         "--summary", summ], log)
                    s = json.load(open(summ))["methods"][m]
                    t = json.load(open(summ + ".timing.json"))
                    rows.append(dict(log=kind, seed=seed, variant=v, method=m,
                                     tp=s["tp"], fp=s["fp"], tn=s["tn"], fn=s["fn"],
                                     untested_spurious=s["untested_spurious"],
                                     untested_consistent=s["untested_consistent"],
                                     precision=s["precision"], recall=s["recall"], f1=s["f1"],
                                     false_alarm_rate=s["false_alarm_rate"],
                                     state_frames=s.get("state_frames", 0),
                                     position_rmse_m=s.get("position_rmse_m", float("nan")),
                                     frame_us_median=t["frame_us"]["median"]))
    with open(os.path.join(a.out, "semireal.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    md = ["# Semi-real EuRoC V1_02 evaluation", "",
          "Written by `tools/semireal.py --seeds %s --spurious-fraction %s` (commands in "
          "`commands.log`). Logs:" % (a.seeds, a.spurious_fraction), ""]
    md += ["- `%s`" % g for g in gen_lines]
    md.append("")
    for kind, variants in [("spurious", list(VARIANTS)), ("clean", CLEAN_VARIANTS)]:
        for v in variants:
            md.append("## %s log, %s" % ("spurious-feature" if kind == "spurious" else
                                          "clean (no spurious features)", v))
            md += ["", VARIANTS[v] + "; seeds " + a.seeds + " (scores pooled, RMSE mean [min, max])",
                   "", "| method | precision | recall | F1 | false-alarm rate | position RMSE (m) |",
                   "| --- | --- | --- | --- | --- | --- |"]
            for m in METHODS:
                r = [x for x in rows if x["log"] == kind and x["variant"] == v and x["method"] == m]
                tp, fp, tn, fn = (sum(x[k] for x in r) for k in ("tp", "fp", "tn", "fn"))
                p = tp / (tp + fp) if tp + fp else 0.0
                rc = tp / (tp + fn) if tp + fn else 0.0
                f1 = 2 * p * rc / (p + rc) if p + rc else 0.0
                far = fp / (fp + tn) if fp + tn else 0.0
                e = [x["position_rmse_m"] for x in r]
                md.append("| %s | %.3f | %.3f | %.3f | %.4f | %.3f [%.3f, %.3f] |" %
                          (m, p, rc, f1, far, sum(e) / len(e), min(e), max(e)))
            md.append("")
    open(os.path.join(a.out, "semireal.md"), "w").write("\n".join(md))
    print("\n".join(md))
    print("semireal.py: wrote %s and %s" % (os.path.join(a.out, "semireal.csv"),
                                            os.path.join(a.out, "semireal.md")))


if __name__ == "__main__":
    main()
