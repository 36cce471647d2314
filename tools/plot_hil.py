#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Latency histogram of an `sfd-hil --csv` file (sfd-hil --png runs this; docs/hil.md).

usage: plot_hil.py CSV PNG

Two histograms on a log-count axis (20 us bins, wider past 20 ms): end-to-end latency (FEATURES publish -> verdict
received, column e2e_us) and the node's time per frame (SFD_TIMING total_us, node_total_us), over
the frames measured by sfd-hil (warm-up and lost frames left out). Dashed lines: p99.9 of each.
"""
import csv
import math
import sys

import sfd_tool_cli  # installed next to this script (PREFIX/share/sfd)

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402


def percentile(values, p):
    """Nearest rank, as sfd-hil reports."""
    v = sorted(values)
    r = max(1, math.ceil(p * len(v)))
    return v[min(len(v), r) - 1]


def main(argv):
    argv = [argv[0]] + sfd_tool_cli.positional(argv, __doc__, 2, 'plot_hil.py CSV PNG')
    if len(argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    e2e, node = [], []
    try:
        with open(argv[1], newline='', encoding='utf-8') as fh:
            for row in csv.DictReader(fh):
                if row['warmup'] == '1' or row['lost'] == '1':
                    continue
                if row['e2e_us']:
                    e2e.append(float(row['e2e_us']))
                if row['node_total_us']:
                    node.append(float(row['node_total_us']))
    except (OSError, KeyError, ValueError) as exc:
        print(f'plot_hil.py: {argv[1]}: {exc}', file=sys.stderr)
        return 2
    fig, ax = plt.subplots(figsize=(8, 5.0), layout='constrained')
    top = max(e2e + node + [1.0])
    width = max(20.0, top / 1000.0)
    bins = [width * k for k in range(int(top // width) + 2)]
    for values, colour, label in ((e2e, 'tab:blue', 'end-to-end (publish -> verdict)'),
                                  (node, 'tab:orange', 'node total_us (SFD_TIMING)')):
        if not values:
            continue
        p999 = percentile(values, 0.999)
        # Translucent fill plus an outline: where the two histograms overlap, both stay visible.
        ax.hist(values, bins=bins, color=colour, alpha=0.35, histtype='stepfilled')
        ax.hist(values, bins=bins, color=colour, histtype='step', linewidth=1.2,
                label=f'{label}: n = {len(values)}, p99.9 = {p999:.0f} us')
        ax.axvline(p999, color=colour, linestyle='--', linewidth=1)
    ax.set_yscale('log')
    ax.set_xlabel('latency per frame (us)')
    ax.set_ylabel('frames (log scale)')
    ax.set_title(f'sfd-hil: {argv[1].rsplit("/", 1)[-1]}')
    ax.grid(True, which='both', alpha=0.3)
    # Below the axes: inside, it covered the p99.9 lines and the tail's bins.
    fig.legend(loc='outside lower center', ncol=1, fontsize=8)
    fig.savefig(argv[2], dpi=110)
    print(f'plot_hil.py: wrote {argv[2]} ({len(e2e)} end-to-end, {len(node)} node samples)')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
