#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plots of sfd-sim's paper reproduction (Tornqvist et al. 2008, Figures 1-3) and the isolation
comparison, from the CSV files `sfd-sim paper-uav|isolation --csv-dir DIR` writes.

usage: plot_paper.py DIR     writes DIR/paper_fig1.png, paper_fig2_known.png,
                             paper_fig3_unknown.png, isolation.png (for the CSVs present)
"""
import csv
import os
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline='', encoding='utf-8') as fh:
        return list(csv.DictReader(fh))


def fig1(d):
    rows = read(os.path.join(d, 'paper_fig1.csv'))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), sharex=True, sharey=True)
    for ax, dv, title in zip(axes, ('0', '9'), ('Cov(ẑ) = 0', 'Cov(ẑ) = 3²')):
        sel = [r for r in rows if r['depth_var'] == dv]
        for faulty, colour, label in (('0', 'tab:blue', 'consistent features'),
                                      ('1', 'tab:red', 'faulty feature (k = 0.02)')):
            pts = [r for r in sel if r['faulty'] == faulty]
            ax.scatter([float(r['zy_x']) for r in pts], [float(r['zy_y']) for r in pts], s=3,
                       c=colour, label=label)
        ax.set_title(f'Figure 1: 300 realizations of Ẑy, {title}')
        ax.set_xlabel('ẑ x (m)')
        ax.set_ylabel('ẑ y (m)')
        ax.set_aspect('equal', adjustable='box')
        ax.legend(loc='best', fontsize=8)
    fig.tight_layout()
    out = os.path.join(d, 'paper_fig1.png')
    fig.savefig(out, dpi=110)
    return out


def roc(d, known, name, title):
    rows = [r for r in read(os.path.join(d, 'paper_roc.csv')) if r['known'] == known]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), sharey=True)
    for ax, dv, sub in zip(axes, ('0', '9'), ('Cov(ẑ) = 0', 'Cov(ẑ) = 3²')):
        for k, colour in (('0', 'tab:gray'), ('0.02', 'tab:blue'), ('0.03', 'tab:red')):
            pts = [r for r in rows if r['depth_var'] == dv and r['k'] == k]
            pts.sort(key=lambda r: float(r['pfa_design']))
            x = [float(r['pfa_design']) for r in pts]
            ax.plot(x, [float(r['pd_empirical']) for r in pts], '-', c=colour,
                    label=f'k = {k} (Monte Carlo)')
            ax.plot(x, [float(r['pd_theory']) for r in pts], '--', c=colour,
                    label=f'k = {k} (non-central χ²)')
        nu = pts[0]['nu'] if pts else '?'
        ax.set_title(f'{title}, {sub}, ν = {nu}')
        ax.set_xlabel('P_fa')
        ax.set_ylabel('P_d')
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.grid(alpha=0.3)
        ax.legend(loc='lower right', fontsize=7)
    fig.tight_layout()
    out = os.path.join(d, name)
    fig.savefig(out, dpi=110)
    return out


def isolation(d):
    rows = read(os.path.join(d, 'isolation.csv'))
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for method, colour, label in (('paper', 'tab:red', "paper: discard the failing group"),
                                  ('isolation', 'tab:blue', 'sfd: isolate inside the group')):
        pts = sorted((r for r in rows if r['method'] == method), key=lambda r: float(r['recall']))
        ax.plot([float(r['recall']) for r in pts], [float(r['consistent_kept']) for r in pts],
                'o-', c=colour, ms=3, label=label)
    ax.set_xlabel('detection probability of spurious features (recall)')
    ax.set_ylabel('fraction of consistent features kept')
    ax.set_title('Isolation gain at equal detection probability')
    ax.grid(alpha=0.3)
    ax.legend(loc='lower left', fontsize=8)
    fig.tight_layout()
    out = os.path.join(d, 'isolation.png')
    fig.savefig(out, dpi=110)
    return out


def main():
    sys.argv[1:] = sfd_tool_cli.positional(sys.argv, __doc__, 1, 'plot_paper.py DIR')
    d = sys.argv[1]
    made = []
    if os.path.exists(os.path.join(d, 'paper_fig1.csv')):
        made.append(fig1(d))
    if os.path.exists(os.path.join(d, 'paper_roc.csv')):
        made.append(roc(d, '1', 'paper_fig2_known.png', 'Figure 2: known translation'))
        made.append(roc(d, '0', 'paper_fig3_unknown.png', 'Figure 3: unknown translation'))
    if os.path.exists(os.path.join(d, 'isolation.csv')):
        made.append(isolation(d))
    if not made:
        print(f'plot_paper.py: no CSV files in {d}', file=sys.stderr)
        return 2
    for m in made:
        print(f'wrote {m}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
