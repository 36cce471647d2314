#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plots of `sfd-sim thesis-loop --csv-dir DIR` (Kilic 2014, Chapter IV, Figures 4-9).

usage: plot_thesis.py DIR    reads DIR/thesis_rmse.csv and DIR/thesis_time.csv, writes
                             DIR/thesis_fig4.png ... thesis_fig9.png:
  fig4 time vs measurement noise     fig5 position RMSE vs measurement noise
  fig6 time vs control input noise   fig7 position RMSE vs control input noise
  fig8 time vs mismatch ratio        fig9 position RMSE vs mismatch ratio
Time = wall clock per frame of the pipeline's association and update stages (association + EKF update), mean (markers) and
median (dotted). The thesis's ranges are shaded. Lines starting with '#' in the CSVs (the unit
definitions) are skipped. Methods often coincide (OPRF and 1-point RANSAC within a few %): each
method's points are drawn shifted sideways by a fixed fraction of the x range (the method's
offset, at most 1.5 % of it; the x value is the level) with hollow markers of different shapes and
line styles, and the legend sits below the axes, so that no curve hides another.
"""
import csv
import os
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402

METHODS = (  # name, colour, marker, line style, sideways offset (fraction of the x range), label
    ('OPRF', 'tab:blue', 'o', '-', -0.015, 'OPRF (1-point RANSAC, epipolar)'),
    ('RANSAC1', 'tab:green', 's', '--', -0.005, '1-point RANSAC (reprojection)'),
    ('RANSACF', 'tab:red', '^', '-.', 0.005, 'F-matrix RANSAC (Table 2)'),
    ('NONE', 'tab:gray', 'D', (0, (6, 2, 1, 2, 1, 2)), 0.015, 'no association'))
SWEEPS = (  # sweep, thesis range, x label, figure numbers (time, RMSE)
    ('measurement', (5, 20), 'measurement noise (%: pixel σ = p/100 · 10 px)', 4, 5),
    ('control', (0, 10), 'control input noise (%: IMU σ = p/100 · RMS true signal)', 6, 7),
    ('mismatch', (5, 20), 'matching error (% of matches mismatched)', 8, 9),
)


def read(path):
    with open(path, newline='', encoding='utf-8') as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith('#')))


def units(path):
    with open(path, encoding='utf-8') as fh:
        for line in fh:
            if line.startswith('# units:'):
                return line[len('# units:'):].strip()
    return ''


def figure(d, rows, sweep, rng, xlabel, num, kind):
    fig, ax = plt.subplots(figsize=(7, 5.2), layout='constrained')
    ax.axvspan(rng[0], rng[1], color='0.92', zorder=0, label="thesis's range")
    levels = [float(r['level_pct']) for r in rows if r['sweep'] == sweep]
    span = (max(levels) - min(levels)) if levels else 0.0
    for name, colour, marker, style, offset, label in METHODS:
        pts = sorted((r for r in rows if r['sweep'] == sweep and r['method'] == name),
                     key=lambda r: float(r['level_pct']))
        if not pts:
            continue
        x = [float(r['level_pct']) + offset * span for r in pts]
        mk = dict(marker=marker, mfc='none', mew=1.3, ms=7)
        if kind == 'time':
            ax.plot(x, [float(r['time_mean_us']) for r in pts], ls=style, c=colour, label=label,
                    **mk)
            ax.plot(x, [float(r['time_median_us']) for r in pts], ':', c=colour, lw=1)
        else:
            y = [1e3 * float(r['rmse_m']) for r in pts]
            e = [2e3 * float(r['rmse_se_m']) for r in pts]
            ax.errorbar(x, y, yerr=e, ls=style, c=colour, capsize=2, label=label, **mk)
    title = {'time': 'association time (mean: markers, median: thin dotted)',
             'rmse': 'error in position (±2 SE)'}[kind]
    ax.set_title(f'Figure {num}: {title} vs {sweep}', fontsize=10)
    ax.set_xlabel(xlabel)
    if kind == 'time':
        ax.set_ylabel('time per frame (µs), association + EKF update')
        ax.set_yscale('log')
    else:
        ax.set_ylabel('EKF position RMSE (mm)')
        ax.set_yscale('log')
    ax.grid(alpha=0.3, which='both')
    # Below the axes: inside, it covered the top curve (no association) in Figure 5.
    fig.legend(loc='outside lower center', ncol=3, fontsize=8)
    out = os.path.join(d, f'thesis_fig{num}.png')
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main():
    sys.argv[1:] = sfd_tool_cli.positional(sys.argv, __doc__, 1, 'plot_thesis.py DIR')
    d = sys.argv[1]
    rmse_csv = os.path.join(d, 'thesis_rmse.csv')
    time_csv = os.path.join(d, 'thesis_time.csv')
    if not (os.path.exists(rmse_csv) and os.path.exists(time_csv)):
        print(f'plot_thesis.py: no thesis_rmse.csv / thesis_time.csv in {d}', file=sys.stderr)
        return 2
    rmse, times = read(rmse_csv), read(time_csv)
    made = []
    for sweep, rng, xlabel, fig_time, fig_rmse in SWEEPS:
        made.append(figure(d, times, sweep, rng, xlabel, fig_time, 'time'))
        made.append(figure(d, rmse, sweep, rng, xlabel, fig_rmse, 'rmse'))
    for m in sorted(made):
        print(f'wrote {m}')
    print(f'units: {units(rmse_csv)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
