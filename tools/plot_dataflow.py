#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The data-flow diagram of docs/interface.md: sfd-node's LCM channels, and the offline path
(sfd-replay, tools/review.py).

usage: plot_dataflow.py OUT.png
"""
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

IN_COLOUR, NODE_COLOUR, OUT_COLOUR, OFF_COLOUR = "#dbe9f6", "#fde6c8", "#dcefd9", "#eeeeee"


def box(ax, x, y, w, h, title, lines, colour, title_size=10):
    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.02,rounding_size=0.08",
                                fc=colour, ec="0.3", lw=1.0))
    ax.text(x + w / 2, y + h - 0.13, title, ha="center", va="top", fontsize=title_size,
            weight="bold")
    for k, line in enumerate(lines):
        ax.text(x + w / 2, y + h - 0.45 - 0.26 * k, line, ha="center", va="top", fontsize=8)


def arrow(ax, x0, y0, x1, y1, label="", above=True, style="-|>", ls="-"):
    ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), arrowstyle=style, mutation_scale=12,
                                 lw=1.2, color="0.2", ls=ls, shrinkA=0, shrinkB=0))
    if label:
        ax.text((x0 + x1) / 2, (y0 + y1) / 2 + (0.07 if above else -0.07), label, ha="center",
                va="bottom" if above else "top", fontsize=8, family="monospace")


def main():
    sys.argv[1:] = sfd_tool_cli.positional(sys.argv, __doc__, 1, 'plot_dataflow.py OUT.png')
    fig, ax = plt.subplots(figsize=(11, 6.6))
    ax.set_xlim(0, 11)
    ax.set_ylim(0, 6.6)
    ax.axis("off")
    ax.text(5.5, 6.5, "sfd data flow: LCM channels (default names, type, typical rate)",
            ha="center", va="top", fontsize=12, weight="bold")

    # Inputs (left).
    box(ax, 0.1, 4.85, 2.3, 0.95, "IMU driver", ["gyro rad/s, specific force m/s²",
                                                  "IMU frame"], IN_COLOUR)
    box(ax, 0.1, 3.65, 2.3, 0.95, "feature tracker", ["raw pixels, track ids",
                                                      "(yours, or sfd-euroc's)"], IN_COLOUR)
    box(ax, 0.1, 2.45, 2.3, 0.95, "calibration", ["intrinsics, distortion,",
                                                  "T_imu_cam"], IN_COLOUR)
    # The node (middle).
    box(ax, 4.35, 2.35, 2.6, 3.55, "sfd-node", [
        "drivers/lcm: decode, validate,", "count what is refused",
        "", "sfd_pipeline_t (core, no heap):", "IMU ring, time guard,",
        "parity test / OPRF / RANSAC,", "sliding-window filter", "",
        "config: apps/config/sfd.yaml"], NODE_COLOUR)
    # Outputs (right).
    box(ax, 8.6, 4.85, 2.3, 0.95, "your VIO filter", ["drops SPURIOUS tracks"], OUT_COLOUR)
    box(ax, 8.6, 3.65, 2.3, 0.95, "navigation user", ["position, velocity,",
                                                      "orientation, variances"], OUT_COLOUR)
    box(ax, 8.6, 2.45, 2.3, 0.95, "monitoring", ["stage times µs, counters;",
                                                 "~1 Hz status while idle"], OUT_COLOUR)

    for y, label, typ in ((5.33, "IMU  200 Hz", "imu_t"),
                          (4.13, "FEATURES  20 Hz", "feature_frame_t"),
                          (2.93, "CAMERA_INFO  1 Hz", "camera_info_t")):
        arrow(ax, 2.4, y, 4.35, y, label)
        ax.text(3.375, y - 0.07, typ, ha="center", va="top", fontsize=8, family="monospace")
    for y, label, typ in ((5.33, "SFD_VERDICT", "feature_verdict_t"),
                          (4.13, "SFD_STATE", "nav_state_t"),
                          (2.93, "SFD_TIMING", "timing_t")):
        arrow(ax, 6.95, y, 8.6, y, label + "  per frame")
        ax.text(7.775, y - 0.07, typ, ha="center", va="top", fontsize=8, family="monospace")

    # Offline path (bottom).
    ax.plot([0.1, 10.9], [2.05, 2.05], ls=(0, (4, 3)), c="0.6", lw=1)
    ax.text(0.1, 1.95, "offline: the same code path, from a log", ha="left", va="top",
            fontsize=9, style="italic", color="0.3")
    box(ax, 0.1, 0.15, 2.3, 1.3, "LCM log", ["lcm-logger recording,",
                                             "sfd-sim -o, sfd-euroc -o;", "TRUTH optional"],
        OFF_COLOUR)
    box(ax, 4.35, 0.15, 2.6, 1.3, "sfd-replay", ["as fast as possible,", "deterministic;",
                                                 "scores against TRUTH"], OFF_COLOUR)
    box(ax, 8.6, 0.15, 2.3, 1.3, "tools/review.py", ["one HTML report:", "verdicts, timing,",
                                                     "position, rejections"], OFF_COLOUR)
    arrow(ax, 2.4, 0.8, 4.35, 0.8, "IN.lcmlog")
    arrow(ax, 6.95, 0.8, 8.6, 0.8, "OUT.lcmlog")
    ax.text(7.78, 0.73, "(+ summary JSON)", ha="center", va="top", fontsize=8,
            family="monospace")
    fig.tight_layout()
    fig.savefig(sys.argv[1], dpi=90)
    print(f"wrote {sys.argv[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
