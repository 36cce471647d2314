#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A one-page report of an sfd run, in the manner of PX4's Flight Review.

usage: review.py LOG [-o REPORT.html]

LOG is an LCM log holding sfd's outputs: an sfd-replay OUT log (the input events plus the
published ones), or a recording of a live sfd-node made with lcm-logger. REPORT (default: LOG
with .html for its .lcmlog ending) is one self-contained HTML file, its figures embedded as
base64 PNGs, with four sections:

  verdicts    per frame (SFD_VERDICT): consistent / spurious / untested counts, the spurious
              fraction of the tested features (with TRUTH's own fraction when the log labels
              features), and the spurious and consistent verdicts by the stage that decided;
              where TRUTH labels the features, the strict scores (an UNTESTED spurious
              observation is a miss, as sfd-replay scores) and where the errors are: the
              misses by fault kind and by the observation's place in its run of spurious labels
              (1st, 2nd, 3rd or later), and the false alarms by how many of the track's frames
              ago its last spurious label was (a fault seen late, after its labels end, or a
              track never labelled);
  timing      per frame (SFD_TIMING, frame_processed = 1): ingest, parity, association,
              update, total and processing (total - publish) in us against SPEC's budget for the
              whole pipeline (p99.9 <= 1 ms, max <= 2 ms: ../shared/SPEC.md "Figures to reach",
              docs/timing.md "With the window filter"), hypotheses drawn; sfd-replay writes its
              durations as 0 (its OUT log is byte-identical run to run), which the section says;
  position    SFD_STATE against TRUTH (when the log has TRUTH poses): TRUTH's position is
              interpolated linearly in time at each SFD_STATE utime (exact where the times
              coincide, as in sfd-sim logs), then the estimate is aligned onto it by the 4-DOF
              position + yaw least-squares fit of sfd-replay's ATE (apps/common/sfd_eval.cpp
              align_posyaw); the error is shown aligned and raw;
  rejections  the node's input counters (SFD_TIMING rejected[], frames_in / refused /
              processed / untested; docs/rejections.md) over time and at the end.

Every figure is drawn against the log's own event timestamps (seconds since its first event),
which stay in order when a message's utime jumps (a restarted publisher, a time glitch).
It prints the report's headline numbers (the same names as sfd-replay's --summary JSON) on
stdout. Channel names are sfd's defaults (FEATURES, SFD_VERDICT, SFD_STATE, SFD_TIMING, TRUTH).
The generated Python LCM types are found as `sfd` on PYTHONPATH, else in
$SFD_LCM_PYTHON, else in build/host/lcm_types/python next to this script.
Exit 0; 2 on a bad argument or a log that cannot be read or holds no SFD_VERDICT.
"""
import argparse
import base64
import html
import io
import os
import sys
import sfd_tool_cli  # tools/sfd_tool_cli.py

import numpy as np


def fail(msg):
    """Bad usage or input: one line on stderr, exit 2."""
    print(f"review.py: {msg}", file=sys.stderr)
    sys.exit(2)


try:
    import lcm
except ImportError:  # the venv has it (tools/requirements.txt)
    fail("the Python module 'lcm' is missing (tools/setup.sh installs it)")


def import_types():
    """The generated LCM types (package sfd)."""
    return sfd_tool_cli.import_lcm_types("review.py")


STATUS = ((1, "consistent", "tab:green"), (2, "spurious", "tab:red"), (0, "untested", "0.6"))
STAGES = ((1, "parity"), (2, "oprf"), (3, "ransac1"), (4, "ransacf"), (0, "none"))
STAGE_COLOUR = {1: "tab:blue", 2: "tab:orange", 3: "tab:purple", 4: "tab:brown", 0: "0.5"}
STAGE_DURATIONS = (("ingest_us", "tab:cyan"), ("parity_us", "tab:blue"),
                   ("association_us", "tab:orange"), ("update_us", "tab:purple"),
                   ("publish_us", "tab:pink"))
DURATION_NAMES = ("total_us", "processing_us") + tuple(n for n, _ in STAGE_DURATIONS)
# truth_t's KIND_* values (lcm_types/truth_t.lcm)
KIND_NAMES = {1: "jump", 2: "drift", 3: "moving", 4: "mismatch", 5: "unspecified"}
KIND_UNSPECIFIED = 5
# False alarms by the number of the track's frames since its last spurious label.
SINCE_BINS = ("1", "2", "3-5", "6-10", ">10", "never")
# SPEC "Figures to reach": whole pipeline on the host, 200 features per frame, L = 5.
BUDGET_P999_US = 1000.0
BUDGET_MAX_US = 2000.0


def reason_names(timing_t):
    """rejected[] index -> name, from timing_t's REJECT_* constants (sfd-replay's JSON names)."""
    names = ["?"] * timing_t.NUM_REASONS
    for attr in dir(timing_t):
        if attr.startswith("REJECT_"):
            names[getattr(timing_t, attr)] = attr[len("REJECT_"):].lower()
    return names


def decode_truth(sfd, data):
    """TRUTH: truth_t, or truth_v1_t for logs written before kind[] (other fingerprint)."""
    try:
        return sfd.truth_t.decode(data)
    except ValueError:
        return sfd.truth_v1_t.decode(data)


class Run:
    """Everything review.py takes from one log."""

    def __init__(self):
        # Each list is in log order, with the event's log timestamp (us): the x axis of every
        # figure, since the messages' own utimes can jump (a restarted publisher, a glitch).
        self.verdicts = []    # (log time, utime, status array, stage array, track ids)
        self.timing = []      # (log time, timing_t)
        self.states = []      # (log time, utime, position, position_var)
        self.truth = {}       # utime -> (position, {track_id: spurious})
        self.kinds = {}       # utime -> {track_id: kind} (KIND_UNSPECIFIED in truth_v1_t logs)
        self.undecodable = {}  # channel -> count
        self.events = 0
        self.first_log_us = None


def read_log(path, sfd):
    run = Run()
    try:
        log = lcm.EventLog(path, "r")
    except (IOError, OSError) as e:
        fail(f"{path}: cannot open the log ({e})")
    try:
        for ev in log:
            run.events += 1
            if run.first_log_us is None:
                run.first_log_us = ev.timestamp
            try:
                if ev.channel == "SFD_VERDICT":
                    m = sfd.feature_verdict_t.decode(ev.data)
                    n = m.num_features
                    run.verdicts.append((ev.timestamp, m.utime, np.array(m.status[:n], dtype=int),
                                         np.array(m.stage[:n], dtype=int), list(m.track_id[:n])))
                elif ev.channel == "SFD_TIMING":
                    run.timing.append((ev.timestamp, sfd.timing_t.decode(ev.data)))
                elif ev.channel == "SFD_STATE":
                    m = sfd.nav_state_t.decode(ev.data)
                    run.states.append((ev.timestamp, m.utime, np.array(m.position),
                                       np.array(m.position_var)))
                elif ev.channel == "TRUTH":
                    m = decode_truth(sfd, ev.data)
                    n = m.num_features
                    run.truth[m.utime] = (np.array(m.position),
                                          dict(zip(m.track_id[:n], m.spurious[:n])))
                    kind = getattr(m, "kind", None)
                    run.kinds[m.utime] = {
                        tid: (int(kind[i]) if kind is not None else
                              (KIND_UNSPECIFIED if m.spurious[i] else 0))
                        for i, tid in enumerate(m.track_id[:n])}
            except ValueError:
                run.undecodable[ev.channel] = run.undecodable.get(ev.channel, 0) + 1
    except (IOError, OSError, ValueError) as e:
        fail(f"{path}: not a readable LCM log after {run.events} events ({e})")
    if not run.verdicts:
        fail(f"{path}: no SFD_VERDICT event (not an sfd output log: replay it with "
                 "sfd-replay first)")
    return run


# ------------------------------------------------------------------------------------------------
# Statistics


def verdict_stats(run):
    """Per verdict, in log order: counts by status, by (status, stage), spurious fractions."""
    counts = {name: np.array([int(np.sum(v[2] == s)) for v in run.verdicts])
              for s, name, _ in STATUS}
    by_stage = {}  # (status name, stage) -> per-frame counts
    for s, sname, _ in STATUS[:2]:
        for g, _ in STAGES:
            c = np.array([int(np.sum((v[2] == s) & (v[3] == g))) for v in run.verdicts])
            if c.any():
                by_stage[(sname, g)] = c
    tested = counts["consistent"] + counts["spurious"]
    frac = np.full(len(tested), np.nan)
    frac[tested > 0] = counts["spurious"][tested > 0] / tested[tested > 0]
    # TRUTH's spurious fraction of the features of the same frame, where TRUTH labels features.
    truth_frac = np.full(len(run.verdicts), np.nan)
    for i, v in enumerate(run.verdicts):
        lab = run.truth.get(v[1], (None, {}))[1]
        if lab:
            truth_frac[i] = sum(1 for x in lab.values() if x) / len(lab)
    return counts, by_stage, frac, truth_frac


def since_bin(since):
    """SINCE_BINS's name for a track whose last spurious label was `since` of its frames ago."""
    if since is None:
        return "never"
    if since <= 2:
        return str(since)
    return "3-5" if since <= 5 else ("6-10" if since <= 10 else ">10")


def error_anatomy(run):
    """Strict scores against TRUTH and where the errors are; None when no verdict's frame has
    TRUTH labels. Every observation a verdict lists and TRUTH labels counts, as sfd-replay scores
    it (apps/common/sfd_eval.cpp): spurious + SPURIOUS a detection, spurious + CONSISTENT or
    UNTESTED a miss, clean + SPURIOUS a false alarm, clean + UNTESTED nothing. The frames of a
    track are counted over the frames TRUTH labels it in, in log order of the verdicts."""
    tp = fp = missed = missed_untested = 0
    miss_kind = {name: 0 for name in KIND_NAMES.values()}
    miss_place = {"1st": 0, "2nd": 0, "3rd+": 0}
    fa_since = {b: 0 for b in SINCE_BINS}
    tested_since = {b: 0 for b in SINCE_BINS}
    frame_no, last_label, run_len = {}, {}, {}
    labelled = False
    for v in run.verdicts:
        lab = run.truth.get(v[1], (None, {}))[1]
        if not lab:
            continue
        kinds = run.kinds.get(v[1], {})
        labelled = True
        for status, tid in zip(v[2], v[4]):
            if tid not in lab:
                continue
            k = frame_no.get(tid, 0)
            frame_no[tid] = k + 1
            if lab[tid]:
                run_len[tid] = run_len.get(tid, 0) + 1 if last_label.get(tid) == k - 1 else 1
                last_label[tid] = k
                if status == 2:
                    tp += 1
                    continue
                missed += 1
                missed_untested += int(status == 0)
                name = KIND_NAMES.get(kinds.get(tid, KIND_UNSPECIFIED), "unspecified")
                miss_kind[name] += 1
                n = run_len[tid]
                miss_place["1st" if n == 1 else ("2nd" if n == 2 else "3rd+")] += 1
            elif status != 0:
                b = since_bin(k - last_label[tid] if tid in last_label else None)
                tested_since[b] += 1
                if status == 2:
                    fp += 1
                    fa_since[b] += 1
    if not labelled:
        return None
    f1 = 2 * tp / (2 * tp + fp + missed) if tp + fp + missed else float("nan")
    return {"tp": tp, "fp": fp, "missed": missed, "missed_untested": missed_untested, "f1": f1,
            "miss_kind": miss_kind, "miss_place": miss_place, "fa_since": fa_since,
            "tested_since": tested_since}


def align_posyaw(est, gt):
    """sfd_eval.cpp align_posyaw: yaw and t minimising sum |R_z(yaw) est + t - gt|^2."""
    me, mg = est.mean(axis=0), gt.mean(axis=0)
    e, g = est - me, gt - mg
    s = float(np.sum(e[:, 0] * g[:, 1] - e[:, 1] * g[:, 0]))
    c = float(np.sum(e[:, 0] * g[:, 0] + e[:, 1] * g[:, 1]))
    yaw = 0.0 if s == 0.0 and c == 0.0 else float(np.arctan2(s, c))
    R = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0],
                  [0.0, 0.0, 1.0]])
    return yaw, R, mg - R @ me


# TRUTH is interpolated only between two poses at most this far apart (a gap in TRUTH, or a time
# base that jumped, is not bridged).
MAX_TRUTH_GAP_US = 1_000_000


def position_stats(run):
    """SFD_STATE against TRUTH interpolated at the state utimes; None without both."""
    poses = sorted((u, p) for u, (p, _) in run.truth.items())
    if not run.states or not poses:
        return None
    tt = np.array([u for u, _ in poses], dtype=np.int64)
    tp = np.array([p for _, p in poses])
    keep, gt, exact = [], [], 0
    for i, (_, u, _, _) in enumerate(run.states):
        j = int(np.searchsorted(tt, u))
        if j < len(tt) and tt[j] == u:
            keep.append(i)
            gt.append(tp[j])
            exact += 1
        elif 0 < j < len(tt) and tt[j] - tt[j - 1] <= MAX_TRUTH_GAP_US:
            w = (u - tt[j - 1]) / (tt[j] - tt[j - 1])
            keep.append(i)
            gt.append((1.0 - w) * tp[j - 1] + w * tp[j])
    if not keep:
        return None
    st = [run.states[i] for i in keep]
    est = np.array([s[2] for s in st])
    var = np.array([s[3] for s in st])
    gt = np.array(gt)
    yaw, R, t = align_posyaw(est, gt)
    aligned = est @ R.T + t
    err = aligned - gt
    raw = est - gt
    return {"log_us": np.array([s[0] for s in st], dtype=np.int64), "est": est,
            "aligned": aligned, "gt": gt, "err": err, "raw": raw, "n": len(st),
            "sd": np.sqrt(np.maximum(var.sum(axis=1), 0.0)), "yaw": yaw, "exact": exact,
            "ate_m": float(np.sqrt(np.mean(np.sum(err * err, axis=1)))),
            "rmse_raw_m": float(np.sqrt(np.mean(np.sum(raw * raw, axis=1)))),
            "states": len(run.states)}


def timing_stats(run):
    proc = [(lt, m) for lt, m in run.timing if m.frame_processed == 1]
    if not proc:
        return None
    d = {"log_us": np.array([lt for lt, _ in proc], dtype=np.int64)}
    for name in ("ingest_us", "parity_us", "association_us", "update_us", "total_us",
                 "publish_us", "hypotheses_used", "budget_exhausted", "features_in"):
        d[name] = np.array([getattr(m, name) for _, m in proc], dtype=float)
    d["processing_us"] = d["total_us"] - d["publish_us"]
    d["all_zero"] = not any(d[k].any() for k in DURATION_NAMES)
    return d


def nearest_rank(x, q):
    """sfd_eval's percentile rule (numpy method inverted_cdf)."""
    return float(np.percentile(x, 100.0 * q, method="inverted_cdf")) if len(x) else float("nan")


# ------------------------------------------------------------------------------------------------
# Figures

XLABEL = "log time (s)"


def png_of(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    import matplotlib.pyplot as plt
    plt.close(fig)
    return buf.getvalue()


def outside_legend(ax, **kw):
    """Legend to the right of the axes: it can never cover a curve."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8, **kw)


def fig_verdicts(plt, x, counts, by_stage, frac, truth_frac):
    fig, axs = plt.subplots(4, 1, figsize=(9.5, 10.0), sharex=True, layout="constrained")
    # Stacked areas (a step per frame): with hundreds of frames, bars would alias.
    ys = [counts[name] for _, name, _ in STATUS]
    axs[0].stackplot(x, *ys, colors=[c for _, _, c in STATUS], step="mid",
                     labels=[n for _, n, _ in STATUS], linewidth=0)
    axs[0].set_ylabel("features per frame")
    axs[0].set_title("verdicts per frame (SFD_VERDICT)", fontsize=10)
    outside_legend(axs[0])
    axs[1].plot(x, 100.0 * frac, "-", c="tab:red", lw=1.0, label="judged SPURIOUS\n(of tested)")
    if np.isfinite(truth_frac).any():
        axs[1].plot(x, 100.0 * truth_frac, "-", c="k", lw=0.8, alpha=0.6,
                    label="TRUTH spurious\n(of all)")
    axs[1].set_ylabel("spurious (%)")
    axs[1].set_ylim(bottom=0)
    axs[1].set_title("spurious fraction", fontsize=10)
    outside_legend(axs[1])
    for ax, sname in ((axs[2], "spurious"), (axs[3], "consistent")):
        drawn = False
        for g, gname in STAGES:
            c = by_stage.get((sname, g))
            if c is not None:
                ax.plot(x, c, "-", c=STAGE_COLOUR[g], lw=0.9, label=gname)
                drawn = True
        ax.set_ylabel("features per frame")
        ax.set_ylim(bottom=0)
        ax.set_title(f"{sname.upper()} verdicts by the stage that decided"
                     + ("" if drawn else ": none"), fontsize=10)
        if drawn:
            outside_legend(ax)
    axs[3].set_xlabel(XLABEL)
    for ax in axs:
        ax.grid(alpha=0.3)
    return png_of(fig)


def fig_timing(plt, x, tm):
    fig, axs = plt.subplots(3, 1, figsize=(9.5, 8.0), sharex=True, layout="constrained",
                            height_ratios=(3, 3, 1.2))
    floor = 1.0  # log axes: a 0 is drawn at 1 us

    ax = axs[0]
    # total_us wide and pale under processing_us (total − publish): the two are close, and the
    # thin one on top keeps both visible.
    ax.plot(x, np.maximum(tm["total_us"], floor), "-", c="0.7", lw=3.0, label="total_us")
    ax.plot(x, np.maximum(tm["processing_us"], floor), "-", c="k", lw=0.8,
            label="processing_us\n(total − publish)")
    ax.axhline(BUDGET_P999_US, c="tab:red", ls="--", lw=1, label="budget p99.9 (1 ms)")
    ax.axhline(BUDGET_MAX_US, c="tab:red", ls="-", lw=1, label="budget max (2 ms)")
    ax.set_yscale("log")
    ax.set_ylabel("µs per frame")
    title = "node time per frame (SFD_TIMING) against SPEC's budget"
    if tm["all_zero"]:
        title += ": every duration is 0 in this log (sfd-replay writes none)"
    ax.set_title(title, fontsize=10)
    outside_legend(ax)

    ax = axs[1]
    for name, colour in STAGE_DURATIONS:
        ax.plot(x, np.maximum(tm[name], floor), "-", c=colour, lw=0.8, label=name)
    ax.set_yscale("log")
    ax.set_ylabel("µs per frame")
    ax.set_title("per-stage time (a 0 is drawn at 1 µs)", fontsize=10)
    outside_legend(ax)

    ax = axs[2]
    ax.step(x, tm["hypotheses_used"], where="mid", c="tab:orange", lw=0.8, label="hypotheses")
    ex = tm["budget_exhausted"] > 0
    if ex.any():
        ax.plot(x[ex], tm["hypotheses_used"][ex], "v", c="tab:red", ms=4,
                label="budget exhausted")
    ax.set_ylabel("hypotheses")
    ax.set_xlabel(XLABEL)
    outside_legend(ax)
    for a in axs:
        a.grid(alpha=0.3, which="both")
    return png_of(fig)


def fig_position(plt, x, ps):
    fig = plt.figure(figsize=(9.5, 7.0), layout="constrained")
    gs = fig.add_gridspec(2, 2)
    ax = fig.add_subplot(gs[0, :])
    for k, (axis, colour) in enumerate(zip("xyz", ("tab:red", "tab:green", "tab:blue"))):
        ax.plot(x, ps["err"][:, k], "-", c=colour, lw=0.9, label=f"aligned {axis}")
    ax.plot(x, np.linalg.norm(ps["err"], axis=1), "-", c="k", lw=1.4, label="aligned |e|")
    ax.plot(x, ps["sd"], "--", c="0.4", lw=1, label="filter σ\n√(σx²+σy²+σz²)")
    ax.set_ylabel("position error (m)")
    ax.set_xlabel(XLABEL)
    ax.set_title(f"SFD_STATE − TRUTH after position+yaw alignment: ATE {ps['ate_m']:.4g} m",
                 fontsize=10)
    ax.grid(alpha=0.3)
    outside_legend(ax)
    ax2 = fig.add_subplot(gs[1, 0])
    ax2.plot(x, np.linalg.norm(ps["raw"], axis=1), "-", c="tab:gray", lw=1.2)
    ax2.set_ylabel("|e| (m)")
    ax2.set_xlabel(XLABEL)
    ax2.set_title(f"raw, not aligned: RMSE {ps['rmse_raw_m']:.3g} m", fontsize=10)
    ax2.grid(alpha=0.3)
    ax3 = fig.add_subplot(gs[1, 1])
    ax3.plot(ps["gt"][:, 0], ps["gt"][:, 1], "-", c="0.6", lw=3.0, label="TRUTH")
    ax3.plot(ps["aligned"][:, 0], ps["aligned"][:, 1], "-", c="tab:blue", lw=0.9,
             label="SFD_STATE,\naligned")
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_aspect("equal", adjustable="datalim")
    ax3.set_title("top view", fontsize=10)
    ax3.grid(alpha=0.3)
    outside_legend(ax3)
    return png_of(fig)


def fig_rejections(plt, x, run, names):
    fig, axs = plt.subplots(2, 1, figsize=(9.5, 6.0), sharex=True, layout="constrained")
    msgs = [m for _, m in run.timing]
    # frames_in is drawn wide and pale under the others: it equals frames_processed while
    # nothing is refused, and must not hide it.
    for key, colour, style, lw in (("frames_in", "0.75", "-", 4.0),
                                   ("frames_processed", "tab:green", "-", 1.2),
                                   ("frames_untested", "0.3", "--", 1.1),
                                   ("frames_refused", "tab:red", "-", 1.1)):
        axs[0].step(x, [getattr(m, key) for m in msgs], style, where="post", c=colour, lw=lw,
                    label=key)
    axs[0].set_yscale("symlog", linthresh=10)  # the few refused / untested stay apart
    axs[0].set_ylim(bottom=0)
    axs[0].set_ylabel("frames since start")
    axs[0].set_title("frame counters (SFD_TIMING, status reports included)", fontsize=10)
    outside_legend(axs[0])
    rej = np.array([m.rejected for m in msgs], dtype=float)
    nonzero = [i for i in range(rej.shape[1]) if rej[:, i].any()]
    cmap = plt.get_cmap("tab10")
    styles = ("-", "--", ":", "-.")
    for j, i in enumerate(nonzero):
        axs[1].step(x, rej[:, i], styles[(j // 10) % 4], where="post", c=cmap(j % 10), lw=1.2,
                    label=f"{i} {names[i]}")
    axs[1].set_yscale("symlog", linthresh=10)
    axs[1].set_ylim(bottom=0)
    axs[1].set_ylabel("count since start")
    axs[1].set_xlabel(XLABEL)
    axs[1].set_title("rejected[] by reason" + ("" if nonzero else ": all 0 in this log"),
                     fontsize=10)
    if nonzero:
        outside_legend(axs[1])
    for a in axs:
        a.grid(alpha=0.3)
    return png_of(fig)


# ------------------------------------------------------------------------------------------------
# Report


def table(rows, header=None):
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def img(png, alt):
    return (f'<img alt="{html.escape(alt)}" src="data:image/png;base64,'
            f'{base64.b64encode(png).decode("ascii")}">')


def fmt_us(x):
    return "n/a" if not np.isfinite(x) else f"{x:.0f}"


def main():
    ap = argparse.ArgumentParser(prog="review.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "review.py")
    ap.add_argument("log", help="an sfd-replay OUT log or an lcm-logger recording of sfd-node")
    ap.add_argument("-o", "--output", help="report file (default: LOG with .html)")
    a = ap.parse_args()
    if not os.path.isfile(a.log):
        fail(f"{a.log}: no such file")
    out = a.output or (a.log[:-len(".lcmlog")] if a.log.endswith(".lcmlog") else a.log) + ".html"
    if os.path.abspath(out) == os.path.abspath(a.log):
        fail(f"-o {out}: is the input log")

    sfd = import_types()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = read_log(a.log, sfd)
    names = reason_names(sfd.timing_t)
    counts, by_stage, frac, truth_frac = verdict_stats(run)
    nframes = len(run.verdicts)

    def secs(log_us):
        """x axis: seconds since the log's first event, by the log's own timestamps."""
        return (np.asarray(log_us, dtype=np.int64) - run.first_log_us) * 1e-6

    tested = int(counts["consistent"].sum() + counts["spurious"].sum())
    spurious = int(counts["spurious"].sum())
    consistent = int(counts["consistent"].sum())
    untested = int(counts["untested"].sum())
    frames_untested = int(np.sum((counts["consistent"] + counts["spurious"]) == 0))
    headline = [("frames judged (SFD_VERDICT)", nframes),
                ("frames with no tested feature", frames_untested),
                ("features judged", tested + untested), ("tested", tested),
                ("consistent", consistent), ("spurious", spurious), ("untested", untested),
                ("spurious fraction of tested", f"{spurious / tested:.4f}" if tested else "n/a")]
    figures, sections = 0, []

    # Verdicts.
    stage_rows = []
    for g, gname in STAGES:
        c = by_stage.get(("consistent", g))
        s = by_stage.get(("spurious", g))
        if c is not None or s is not None:
            stage_rows.append((gname, int(c.sum()) if c is not None else 0,
                               int(s.sum()) if s is not None else 0))
    sec = ['<h2 id="verdicts">Verdicts</h2>', table(headline),
           "<p>Verdicts by the stage that decided (a feature no stage tested has stage none):</p>",
           table(stage_rows, ("stage", "consistent", "spurious")),
           img(fig_verdicts(plt, secs([v[0] for v in run.verdicts]), counts, by_stage, frac,
                            truth_frac), "verdicts")]
    figures += 1
    an = error_anatomy(run)
    anatomy_lines = []
    if an is not None:
        sec.append("<p>Against TRUTH, strict scoring (an UNTESTED spurious observation is a miss, "
                   "as sfd-replay scores; docs/evaluation.md “Detection scores”):</p>")
        sec.append(table([("detections", an["tp"]), ("false alarms", an["fp"]),
                          ("misses (of them UNTESTED)",
                           f"{an['missed']} ({an['missed_untested']})"),
                          ("F1", f"{an['f1']:.4f}")]))
        sec.append("<p>Misses by fault kind (TRUTH's kind[]) and by the observation's place in "
                   "its track's run of spurious labels (a step's first labelled frame is where "
                   "the smallest offset is):</p>")
        sec.append(table([tuple(an["miss_kind"].values()) + tuple(an["miss_place"].values())],
                         tuple(an["miss_kind"]) + ("1st", "2nd", "3rd+")))
        sec.append("<p>False alarms by how many of the track's frames ago its last spurious "
                   "label was: at 1–2 the fault is seen after its labels end (a detector with a "
                   "memory longer than the label window); “never” is a track never labelled "
                   "spurious. The tested clean observations of each class give the rate:</p>")
        sec.append(table([("false alarms",) + tuple(an["fa_since"].values()),
                          ("clean tested",) + tuple(an["tested_since"].values())],
                         ("frames since",) + SINCE_BINS))
        anatomy_lines.append(
            f"detection: tp {an['tp']} fp {an['fp']} missed {an['missed']} "
            f"(untested {an['missed_untested']}) f1 {an['f1']:.4f}")
        anatomy_lines.append("misses by kind: " + " ".join(
            f"{k}={v}" for k, v in an["miss_kind"].items()) + "; by place: " + " ".join(
            f"{k}={v}" for k, v in an["miss_place"].items()))
        anatomy_lines.append("false alarms by frames since the track's last spurious label: " +
                             " ".join(f"{b}={an['fa_since'][b]}/{an['tested_since'][b]}"
                                      for b in SINCE_BINS))
    sections.append("\n".join(sec))

    # Timing.
    tm = timing_stats(run)
    sec = ['<h2 id="timing">Timing</h2>',
           "<p>Budget lines: SPEC's whole-pipeline figure on the host, 200 features per frame, "
           "L = 5: p99.9 ≤ 1 ms and max ≤ 2 ms per frame (../shared/SPEC.md, “Figures to "
           "reach”; docs/timing.md, “With the window filter”). processing_us = total_us − "
           "publish_us, the node's time without its sends.</p>"]
    timing_lines = []
    if tm is None:
        sec.append("<p>No SFD_TIMING with frame_processed = 1 in this log.</p>")
    else:
        rows = []
        for name in DURATION_NAMES:
            y = np.sort(tm[name])
            rows.append((name, fmt_us(nearest_rank(y, 0.5)), fmt_us(nearest_rank(y, 0.99)),
                         fmt_us(nearest_rank(y, 0.999)), fmt_us(y[-1]),
                         int(np.sum(y > BUDGET_P999_US)), int(np.sum(y > BUDGET_MAX_US))))
        over = int(np.sum(tm["total_us"] > BUDGET_MAX_US))
        timing_lines.append(f"timing frames {len(tm['log_us'])}, total_us over 2 ms {over}"
                            + (" (every duration 0: sfd-replay writes none)"
                               if tm["all_zero"] else ""))
        if tm["all_zero"]:
            sec.append("<p><b>Every duration in this log is 0.</b> sfd-replay publishes SFD_TIMING "
                       "with durations 0 so that its OUT log is byte-identical run to run (its "
                       "wall-clock figures are in SUMMARY.timing.json). Record a live sfd-node "
                       "with lcm-logger to see real times.</p>")
        sec.append(table(rows, ("duration", "median µs", "p99", "p99.9", "max", "frames > 1 ms",
                                "frames > 2 ms")))
        sec.append(table([("frames timed", len(tm["log_us"])),
                          ("hypotheses per frame, mean / max",
                           f"{tm['hypotheses_used'].mean():.1f} / "
                           f"{tm['hypotheses_used'].max():.0f}"),
                          ("frames with the hypothesis budget exhausted",
                           int(tm["budget_exhausted"].sum()))]))
        sec.append(img(fig_timing(plt, secs(tm["log_us"]), tm), "timing"))
        figures += 1
    sections.append("\n".join(sec))

    # Position.
    ps = position_stats(run)
    sec = ['<h2 id="position">Position error</h2>']
    pos_lines = []
    if ps is None:
        sec.append("<p>No position error: the log needs both SFD_STATE and TRUTH poses "
                   f"(SFD_STATE {len(run.states)}, TRUTH {len(run.truth)}).</p>")
    else:
        how = ("TRUTH interpolated linearly at each SFD_STATE utime "
               f"({ps['exact']} of {ps['n']} at a TRUTH utime exactly"
               f"{', so unchanged' if ps['exact'] == ps['n'] else ''}); "
               f"{ps['states'] - ps['n']} SFD_STATE without TRUTH around them (outside its time "
               f"span or in a gap over {MAX_TRUTH_GAP_US / 1e6:g} s) left out")
        sec.append(f"<p>Aligned: the estimate is fitted onto TRUTH by position + yaw (4-DOF least "
                   f"squares, sfd-replay's ATE). {html.escape(how)}.</p>")
        sec.append(table([("states compared", ps["n"]),
                          ("ATE, position+yaw aligned (m)", f"{ps['ate_m']:.6g}"),
                          ("alignment yaw (rad)", f"{ps['yaw']:.6g}"),
                          ("raw RMSE, not aligned (m)", f"{ps['rmse_raw_m']:.6g}"),
                          ("final error, aligned (m)",
                           f"{np.linalg.norm(ps['err'][-1]):.6g}")]))
        sec.append(img(fig_position(plt, secs(ps["log_us"]), ps), "position error"))
        figures += 1
        pos_lines.append(f"position: {ps['n']} states, ATE {ps['ate_m']:.6g} m "
                         f"(position+yaw aligned), raw RMSE {ps['rmse_raw_m']:.6g} m; {how}")
    sections.append("\n".join(sec))

    # Rejections.
    sec = ['<h2 id="rejections">Rejected input</h2>',
           "<p>Counters since the node started, from the last SFD_TIMING "
           "(docs/rejections.md explains each reason).</p>"]
    rej_line = ""
    if not run.timing:
        sec.append("<p>No SFD_TIMING in this log.</p>")
    else:
        last = run.timing[-1][1]
        frames = [("frames_in", last.frames_in), ("frames_refused", last.frames_refused),
                  ("frames_processed", last.frames_processed),
                  ("frames_untested", last.frames_untested), ("imu_in", last.imu_in),
                  ("camera_info_in", last.camera_info_in),
                  ("status reports (frame_processed 0)",
                   sum(1 for _, m in run.timing if m.frame_processed == 0))]
        sec.append(table(frames))
        sec.append(table([(i, names[i], last.rejected[i]) for i in range(len(names))],
                         ("#", "reason", "count")))
        sec.append(img(fig_rejections(plt, secs([lt for lt, _ in run.timing]), run, names),
                       "rejections"))
        figures += 1
        rej_line = ("frames in {} refused {} processed {} untested {}; rejected: {}".format(
            last.frames_in, last.frames_refused, last.frames_processed, last.frames_untested,
            " ".join(f"{names[i]}={last.rejected[i]}" for i in range(len(names)))))
    sections.append("\n".join(sec))

    if run.undecodable:
        sections.append("<p>Undecodable events, by channel: " + html.escape(
            ", ".join(f"{k} {v}" for k, v in sorted(run.undecodable.items()))) + "</p>")
    title = f"sfd review: {os.path.basename(a.log)}"
    doc = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>
body {{ font-family: sans-serif; max-width: 60em; margin: 1em auto; padding: 0 1em; }}
table {{ border-collapse: collapse; margin: 0.5em 0; }}
td, th {{ border: 1px solid #bbb; padding: 2px 8px; text-align: right; }}
td:first-child, th:first-child {{ text-align: left; }}
img {{ max-width: 100%; }}
</style></head><body>
<h1>{html.escape(title)}</h1>
<p>{html.escape(os.path.abspath(a.log))}: {run.events} events, {nframes} verdicts,
{len(run.timing)} SFD_TIMING, {len(run.states)} SFD_STATE, {len(run.truth)} TRUTH.
Written by tools/review.py.</p>
<p><a href="#verdicts">verdicts</a> · <a href="#timing">timing</a> ·
<a href="#position">position error</a> · <a href="#rejections">rejected input</a></p>
{chr(10).join(sections)}
</body></html>
"""
    tmp = out + ".tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(doc)
        os.replace(tmp, out)
    except OSError as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        print(f"review.py: -o {out}: cannot write ({e.strerror})", file=sys.stderr)
        return 1
    print(f"review.py {a.log}: wrote {out} ({figures} figures)")
    print(f"judged: frames {nframes} tested {tested} consistent {consistent} spurious {spurious} "
          f"untested {untested} frames_untested {frames_untested}")
    for line in anatomy_lines + timing_lines + pos_lines + ([rej_line] if rej_line else []):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
