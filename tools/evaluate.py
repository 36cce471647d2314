#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Evaluation sweeps (docs/evaluation.md): scenarios x methods x seeds x parameter grid on Dask.

Each (scenario, seed) log is written once by `sfd-sim` (a task); every replay of it through
`sfd-replay --config apps/config/sfd.yaml` (the shipped configuration, at-rest start) is a task
that depends on it. The scores come from sfd-replay's JSON summary (apps/common/sfd_eval.hpp);
this tool only gathers and aggregates them (mean, sd, min, max over seeds; pooled counts).

Outputs in --out: results.csv (one row per run, sorted by scenario, seed, method, parameters;
every column is deterministic except those named time_*, which are wall clock), summary.md
(per scenario, method x scores as mean +- sd [min-max] over seeds at the reference point),
pr_curves.png, ate.png, kind_recall.png, commands.log, logs/ and runs/ (the JSON summaries).

Execution: a distributed LocalCluster (--workers N processes, 1 thread each) by default,
--scheduler tcp://HOST:PORT for a running cluster (workers need the same checkout and --out on a
shared filesystem at the same paths), --serial for no Dask. The rows do not depend on which.

Exit: 0 ok, 2 bad usage (or missing binaries), 1 a run failed (its command and stderr printed).
"""
import argparse
import csv
import datetime
import json
import math
import os
import platform
import re
import shlex
import subprocess
import sys
import time
import sfd_tool_cli  # tools/sfd_tool_cli.py

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
METHODS = ["none", "parity", "oprf", "ransac1", "ransacf", "both", "parity-oracle"]
# Not a method of the product: parity's test with TRUTH's poses in place of the filter
# (sfd-replay --oracle-poses), the ceiling of what the test can see; sfd-replay's arguments.
METHOD_ARGS = {"parity-oracle": ["--method", "parity", "--oracle-poses"]}
KINDS = ["jump", "drift", "moving", "mismatch", "unspecified"]
# Scenario -> extra sfd-sim arguments ("{data}" = --data). Edit here (or --sim-args) as sfd-sim's
# options change. worst-case: 30 % random pixels; at its default 1.0 every observation is spurious
# (a capacity test with no clean observation: precision and false-alarm rate say nothing).
SCENARIOS = {
    "paper-uav": [],
    "mistracking": [],
    "moving-object": [],
    "worst-case": ["--random-fraction", "0.3"],
    "euroc-semireal": ["--euroc", "{data}"],
}
FLIGHTS = {"paper-uav", "mistracking", "moving-object", "worst-case"}  # take --frames
# Grid key -> (sfd-replay flag, apps/config/sfd.yaml key giving its reference value).
GRID = {"alpha": ("--false-alarm-rate", "false_alarm_rate"),
        "window": ("--window-frames", "window_frames"),
        "group": ("--group-size", "group_size"),
        "pixel-sigma": ("--pixel-sigma-px", "pixel_sigma_px"),
        "depth-default": ("--default-depth-m", "default_depth_m"),
        "hold": ("--alarm-hold-ratio", "alarm_hold_ratio"),
        "hold-frames": ("--alarm-hold-frames", "alarm_hold_frames"),
        "hold-max": ("--alarm-hold-max-statistic", "alarm_hold_max_statistic"),
        "hold-min": ("--alarm-hold-min-statistic", "alarm_hold_min_statistic"),
        "hold-alpha": ("--alarm-hold-alpha-scale", "alarm_hold_alpha_scale"),
        "hold-dir": ("--alarm-hold-direction-alpha", "alarm_hold_direction_alpha"),
        "ramp": ("--evidence-ramp-share", "evidence_ramp_share")}
PRESETS = {
    "quick": dict(scenarios=["mistracking", "moving-object"], seeds="1,2",
                  methods=",".join(METHODS), grid=["alpha=0.01,0.1"], frames=200),
    "full": dict(scenarios=list(SCENARIOS), seeds="1,2,3,4,5,6,7,8,9,10", methods=",".join(METHODS),
                 grid=["alpha=0.001,0.003,0.01,0.03,0.1"], frames=800),
}
# CSV column -> path in sfd-replay's summary JSON (null -> empty cell).
COLUMNS = [("events", "events"), ("filter_start", "filter_start"),
           ("frames_in", "frames.in"), ("frames_processed", "frames.processed"),
           ("frames_untested", "frames.untested"), ("judged_tested", "judged.tested"),
           ("judged_spurious", "judged.spurious"), ("truth_frames", "truth.frames")]
COLUMNS += [(k, "detection." + k) for k in
            ("labelled", "spurious", "clean", "tp", "fp", "tn", "fn", "untested_spurious",
             "untested_clean", "precision", "recall", "f1", "false_alarm_rate", "coverage",
             "recall_tested", "false_alarm_rate_tested")]
COLUMNS += [("%s_%s" % (k, f), "detection.by_kind.%s.%s" % (k, f))
            for k in KINDS for f in ("spurious", "detected", "untested", "recall", "events",
                                     "caught_1", "caught_3", "caught_5", "caught_10")]
COLUMNS += [("traj_frames", "trajectory.frames")]
COLUMNS += [(k, "trajectory." + k) for k in ("distance_m", "rmse_raw_m", "ate_m", "align_yaw_rad",
                                              "final_error_m", "drift_percent")]
COLUMNS += [("rpe_1s_" + k, "trajectory.rpe_1s." + k) for k in ("segments", "mean_m", "rmse_m")]
COLUMNS += [("rpe_10m_" + k, "trajectory.rpe_10m." + k)
            for k in ("segments", "mean_m", "rmse_m", "mean_percent")]
COLUMNS += [("nees_" + k, "trajectory.nees_position." + k)
            for k in ("frames", "mean", "in_band_95")]
TIME_COLUMNS = [("time_frame_median_us", "frame_us.median"), ("time_frame_p99_us", "frame_us.p99"),
                ("time_wall_s", "wall_s")]  # wall clock: excluded from every equality check


def lookup(d, path):
    for p in path.split("."):
        if not isinstance(d, dict):
            return None
        d = d.get(p)
    return d


def run_cmd(cmd):
    """(returncode, stdout, stderr) of a command; never raises."""
    try:
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=1800)
        return r.returncode, r.stdout, r.stderr
    except (OSError, subprocess.TimeoutExpired) as e:
        return -1, "", "%s: %s" % (type(e).__name__, e)


def gen_task(job):
    """Write one (scenario, seed) log. A task: returns a dict, never raises."""
    os.makedirs(os.path.dirname(job["log"]), exist_ok=True)
    rc, out, err = run_cmd(job["cmd"])
    return dict(ok=rc == 0, cmd=job["cmd"], rc=rc, stderr=err,
                stdout=out.strip().splitlines()[0] if out.strip() else "")


def replay_task(gen, job):
    """Replay one log with one method and parameter point; the CSV row. Never raises."""
    if not gen["ok"]:
        return dict(ok=False, cmd=gen["cmd"], rc=gen["rc"], stderr=gen["stderr"])
    os.makedirs(os.path.dirname(job["json"]), exist_ok=True)
    rc, _, err = run_cmd(job["cmd"])
    if rc != 0:
        return dict(ok=False, cmd=job["cmd"], rc=rc, stderr=err)
    try:
        with open(job["json"]) as f:
            s = json.load(f)
        with open(job["json"] + ".timing.json") as f:
            t = json.load(f)
    except (OSError, ValueError) as e:
        return dict(ok=False, cmd=job["cmd"], rc=0, stderr="unreadable summary: %s" % e)
    row = dict(job["key"])
    row.update((c, lookup(s, p)) for c, p in COLUMNS)
    row["rejected_total"] = sum(v for v in (s.get("rejected") or {}).values() if isinstance(v, int))
    row["json"] = job["json_rel"]
    row.update((c, lookup(t, p)) for c, p in TIME_COLUMNS)
    return dict(ok=True, cmd=job["cmd"], row=row)


def config_value(config, key):
    """A top-level scalar of the YAML configuration (the grid's reference values)."""
    with open(config) as f:
        for line in f:
            m = re.match(r"^%s:\s*([-+0-9.eE]+)" % re.escape(key), line)
            if m:
                return float(m.group(1))
    return None


def num(s):
    return float(s)


def plan(a, grid, config):
    """The jobs: a list of log jobs and a list of replay jobs (each naming its log)."""
    sim = os.path.join(a.build, "apps", "sfd-sim")
    replay = os.path.join(a.build, "apps", "sfd-replay")
    gens, reps = {}, []
    points = [{}]
    for k, vals in grid.items():
        points = [dict(p, **{k: v}) for p in points for v in vals]
    for sc in a.scenarios:
        for seed in a.seeds:
            name = "%s_s%d" % (sc, seed)
            log = os.path.join(a.out, "logs", name + ".lcmlog")
            extra = [x.replace("{data}", a.data) for x in a.sim_args.get(sc, SCENARIOS[sc])]
            if sc in FLIGHTS and a.frames:
                extra = ["--frames", str(a.frames)] + extra
            cmd = [sim, sc, "-o", log, "--seed", str(seed)] + extra
            gens[name] = dict(name=name, log=log, cmd=cmd)
            for m in a.methods:
                for p in points:
                    tag = "_".join("%s%s" % (k, v) for k, v in p.items())
                    rel = os.path.join("runs", name, "%s_%s.json" % (m, tag))
                    cmd = ([replay, log, "--config", config] +
                           METHOD_ARGS.get(m, ["--method", m]) +
                           ["--summary", os.path.join(a.out, rel)])
                    for k, v in p.items():
                        cmd += [GRID[k][0], v]
                    key = dict(scenario=sc, seed=seed, method=m, **p)
                    reps.append(dict(log=name, key=key, cmd=cmd, json=os.path.join(a.out, rel),
                                     json_rel=rel, name="replay-%s-%s-%s" % (name, m, tag)))
    return gens, reps


def execute(a, gens, reps):
    """Run every job; (gen results by name, replay results in plan order)."""
    done, n = [0], len(reps)
    # A progress line on a terminal only (stderr a tty, CI unset or empty), rewritten at most
    # twice a second, as the sfd tools do (docs/deploy.md, "Command line"); quiet otherwise.
    tty = sys.stderr.isatty() and not os.environ.get("CI")
    t0, last = time.monotonic(), [0.0]

    def progress():
        done[0] += 1
        if not tty:
            return
        now = time.monotonic()
        if done[0] < n and now - last[0] < 0.5:
            return
        last[0] = now
        rate = done[0] / max(now - t0, 1e-9)
        left = (n - done[0]) / rate if rate > 0 else 0.0
        print("\revaluate.py: %d/%d runs, %.1f runs/s, %.0f%%, %.0f s left\033[K"
              % (done[0], n, rate, 100.0 * done[0] / n, left), end="\n" if done[0] == n else "",
              file=sys.stderr, flush=True)

    if a.serial:
        g = {k: gen_task(j) for k, j in gens.items()}
        res = []
        for r in reps:
            res.append(replay_task(g[r["log"]], r))
            progress()
        return g, res
    import logging
    from distributed import Client, LocalCluster, as_completed
    cluster = None
    if a.scheduler:
        try:
            client = Client(a.scheduler, timeout=30)
        except (OSError, ValueError) as e:
            print("evaluate.py: no Dask scheduler at %s: %s" % (a.scheduler, e), file=sys.stderr)
            sys.exit(2)
        for what in (gens[next(iter(gens))]["cmd"][0], reps[0]["cmd"][0], a.out):
            seen = client.run(os.path.exists, what)
            if not seen or not all(seen.values()):
                print("evaluate.py: %s is not visible on workers %s (or no worker): the workers "
                      "need the same checkout and --out on a shared filesystem" %
                      (what, [w for w, ok in seen.items() if not ok]), file=sys.stderr)
                client.close()
                sys.exit(2)
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        client = Client(cluster)
    run = "-%d-%d" % (os.getpid(), time.time_ns())  # distinct keys per invocation (shared cluster)
    try:
        gf = {k: client.submit(gen_task, j, key="gen-" + k + run, pure=False)
              for k, j in gens.items()}
        rf = [client.submit(replay_task, gf[r["log"]], r, key=r["name"] + run, pure=False)
              for r in reps]
        index = {f.key: i for i, f in enumerate(rf)}
        res = [None] * n
        for f in as_completed(rf):
            try:
                res[index[f.key]] = f.result()
            except Exception as e:  # a worker died or the task could not run
                res[index[f.key]] = dict(ok=False, cmd=reps[index[f.key]]["cmd"], rc=-1,
                                         stderr="dask: %s: %s" % (type(e).__name__, e))
            progress()
        g = {}
        for k, f in gf.items():
            try:
                g[k] = f.result()
            except Exception as e:
                g[k] = dict(ok=False, cmd=gens[k]["cmd"], rc=-1, stderr="dask: %s" % e, stdout="")
        return g, res
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


# ------------------------------------------------------------------------------------- aggregates
def vals(rows, col):
    return [r[col] for r in rows if isinstance(r.get(col), (int, float)) and math.isfinite(r[col])]


def stats(v):
    """mean, sd (n - 1; 0 for one value), min, max; None for no value."""
    if not v:
        return None
    m = sum(v) / len(v)
    sd = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else 0.0
    return m, sd, min(v), max(v)


def cell(rows, col, fmt):
    v = vals(rows, col)
    s = stats(v)
    if s is None:
        return "—"
    f = lambda x: fmt % x
    txt = f(s[0]) if len(v) == 1 else "%s ± %s [%s–%s]" % (f(s[0]), f(s[1]), f(s[2]), f(s[3]))
    return txt + (" (n=%d)" % len(v) if len(v) < len(rows) else "")


def pooled(rows, num_cols, den_cols):
    n = sum(r[c] or 0 for r in rows for c in num_cols)
    d = sum(r[c] or 0 for r in rows for c in den_cols)
    return n / d if d else None


def pooled_pr(rows):
    """(precision, strict recall, F1) from the counts summed over runs."""
    p = pooled(rows, ["tp"], ["tp", "fp"])
    r = pooled(rows, ["tp"], ["spurious"])
    f = pooled(rows, ["tp", "tp"], ["tp", "tp", "fp", "fn", "untested_spurious"])
    return p, r, f


def at_ref(rows, ref):
    return [r for r in rows if all(r[k] == v for k, v in ref.items())]


def summary_md(a, rows, ref, grid, skipped, gens, wall):
    seeds = ",".join(str(s) for s in a.seeds)
    md = ["# sfd evaluation sweep", "",
          "`%s` (%s, %s; %s, %.0f s wall). Configuration `apps/config/sfd.yaml` (at-rest start). "
          "Scores from sfd-replay's JSON (docs/evaluation.md); cells are mean ± sd [min–max] over "
          "seeds %s of each run's score; \"pooled\" sums the counts over the seeds." %
          (" ".join(shlex.quote(x) for x in a.argv), datetime.date.today().isoformat(),
           platform.node() or "?", "serial" if a.serial else a.scheduler or
           "LocalCluster %d workers" % a.workers, wall, seeds), "",
          "Reference point of the tables: %s. Grid: %s. Time per frame is wall clock (median µs "
          "per run, under the sweep's own load) and not a benchmark." %
          (", ".join("%s = %s" % kv for kv in ref.items()),
           "; ".join("%s ∈ {%s}" % (k, ", ".join(v)) for k, v in grid.items())), ""]
    for sc, why in skipped:
        md += ["**%s skipped**: %s" % (sc, why), ""]
    for sc in a.scenarios:
        rs = [r for r in rows if r["scenario"] == sc]
        r0 = at_ref(rs, ref)
        frac = stats([r["spurious"] / r["labelled"] for r in r0 if r["labelled"]])
        cmd = gens["%s_s%d" % (sc, a.seeds[0])]["cmd"]
        cmd = [sc] + [os.path.relpath(x, ROOT) if x == a.data else x for x in cmd[6:]]
        md += ["## %s" % sc, "",
               "Logs: `sfd-sim %s -o LOG --seed S`; spurious observations: %s of the labelled "
               "ones (mean over seeds)." % (" ".join(map(shlex.quote, cmd)),
                                            "%.1f %%" % (100 * frac[0]) if frac else "—"), "",
               "| method | F1 | F1 pooled | precision | recall (strict) | coverage | "
               "false-alarm rate | ATE (m) | drift (%) | RPE 10 m (m) | time/frame (µs) |",
               "|" + " --- |" * 11]
        for m in a.methods:
            x = [r for r in r0 if r["method"] == m]
            f1p = pooled_pr(x)[2]
            md.append("| %s | %s |" % (m, " | ".join([
                cell(x, "f1", "%.3f"), "—" if f1p is None else "%.3f" % f1p,
                cell(x, "precision", "%.3f"), cell(x, "recall", "%.3f"),
                cell(x, "coverage", "%.3f"), cell(x, "false_alarm_rate", "%.4f"),
                cell(x, "ate_m", "%.3f"), cell(x, "drift_percent", "%.2f"),
                cell(x, "rpe_10m_mean_m", "%.3f"), cell(x, "time_frame_median_us", "%.0f")])))
        kinds = [k for k in KINDS if sum(r["%s_spurious" % k] or 0 for r in r0)]
        if kinds:
            md += ["", "Recall per fault kind (strict; mean ± sd over seeds):", "",
                   "| method | " + " | ".join(kinds) + " |", "|" + " --- |" * (len(kinds) + 1)]
            for m in a.methods:
                x = [r for r in r0 if r["method"] == m]
                md.append("| %s | %s |" % (m, " | ".join(
                    cell(x, "%s_recall" % k, "%.3f").split(" [")[0] for k in kinds)))
            md += ["", "Fault events caught within 10 frames (a track's run of one fault kind; "
                   "caught when one of its own observations within 10 frames of its first is "
                   "judged SPURIOUS; mean ± sd over seeds):", "",
                   "| method | " + " | ".join(kinds) + " |", "|" + " --- |" * (len(kinds) + 1)]
            for m in a.methods:
                x = [r for r in r0 if r["method"] == m]
                md.append("| %s | %s |" % (m, " | ".join(
                    cell(x, "%s_caught_10" % k, "%.3f").split(" [")[0] for k in kinds)))
        if len(grid.get("alpha", [])) > 1:
            other = {k: v for k, v in ref.items() if k != "alpha"}
            md += ["", "Precision / strict recall pooled over seeds, per α:", "",
                   "| method | " + " | ".join("α = %s" % v for v in grid["alpha"]) + " |",
                   "|" + " --- |" * (len(grid["alpha"]) + 1)]
            for m in a.methods:
                cells = []
                for v in grid["alpha"]:
                    p, r, _ = pooled_pr(at_ref(rs, dict(other, alpha=v, method=m)))
                    cells.append("%s / %s" % ("—" if p is None else "%.3f" % p,
                                              "—" if r is None else "%.3f" % r))
                md.append("| %s | %s |" % (m, " | ".join(cells)))
        md.append("")
    return "\n".join(md)


# ------------------------------------------------------------------------------------------ plots
def plots(a, rows, ref, grid):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colors = {m: plt.get_cmap("tab10")(i) for i, m in enumerate(METHODS)}
    scs = [s for s in a.scenarios if any(r["scenario"] == s for r in rows)]
    ncol = min(3, len(scs))
    nrow = (len(scs) + ncol - 1) // ncol
    legend_kw = dict(loc="lower center", ncol=len(a.methods), frameon=False)
    # At least 9.2 in wide, so that the title and a one-row legend of every method fit when the
    # sweep has one or two scenarios (a 4.6 in figure cut both).
    fig_w = max(4.6 * ncol, 9.2)

    # Precision vs strict recall along the alpha sweep (pooled over seeds).
    fig, axs = plt.subplots(nrow, ncol, figsize=(fig_w, 4.2 * nrow + 0.9), squeeze=False)
    other = {k: v for k, v in ref.items() if k != "alpha"}
    # Without an alpha sweep the rows have no alpha column: one point per method, at the
    # configuration's alpha.
    alphas = grid.get("alpha", [None])
    for ax, sc in zip(axs.flat, scs):
        for m in a.methods:
            pts = [(pooled_pr(at_ref(rows, dict(other, scenario=sc, method=m,
                                                **({} if v is None else {"alpha": v})))), v)
                   for v in alphas]
            pts = [(r, p, v) for (p, r, _), v in pts if p is not None and r is not None]
            if not pts:
                continue
            ax.plot([x[0] for x in pts], [x[1] for x in pts], "-o", ms=4, color=colors[m], label=m)
            for r, p, v in pts:
                if v == ref.get("alpha"):
                    ax.plot([r], [p], "o", ms=9, mfc="none", color=colors[m])
        ax.set(xlim=(-0.02, 1.02), ylim=(-0.02, 1.02), xlabel="recall (strict)",
               ylabel="precision", title=sc)
        ax.grid(alpha=0.3)
    for ax in list(axs.flat)[len(scs):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], color=colors[m], marker="o", label=m) for m in a.methods]
    fig.legend(handles=[h for h in handles if h.get_label() != "none"], **legend_kw)
    sweep = ("α = %s (ringed: %s)" % (", ".join(grid["alpha"]), ref["alpha"])
             if "alpha" in grid else "at the configuration's α (no α sweep)")
    fig.suptitle("Precision vs strict recall, pooled over %d seeds; %s; none: no precision"
                 % (len(a.seeds), sweep), fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 0.96))
    fig.savefig(os.path.join(a.out, "pr_curves.png"), dpi=110)
    plt.close(fig)

    # ATE per method and scenario, every seed.
    fig, ax = plt.subplots(figsize=(max(6.5, 2.2 + 1.6 * len(scs)), 4.8))
    w = 0.8 / len(a.methods)
    for i, sc in enumerate(scs):
        for j, m in enumerate(a.methods):
            v = vals(at_ref(rows, dict(ref, scenario=sc, method=m)), "ate_m")
            x = i - 0.4 + w * (j + 0.5)
            ax.plot([x] * len(v), v, "o", ms=3.5, alpha=0.6, color=colors[m])
            if v:
                ax.plot([x - w * 0.4, x + w * 0.4], [sum(v) / len(v)] * 2, "-", lw=2,
                        color=colors[m])
    ax.set_yscale("log")
    ax.set_xticks(range(len(scs)), scs)
    ax.set_ylabel("ATE after position+yaw alignment (m)")
    ax.set_title("ATE per seed (dots) and mean (bar), %s" %
                 ", ".join("%s = %s" % kv for kv in ref.items()), fontsize=10)
    ax.grid(alpha=0.3, axis="y", which="both")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "ate.png"), dpi=110)
    plt.close(fig)

    # Recall per fault kind (pooled over seeds; error bar: sd of the per-run recall).
    fig, axs = plt.subplots(nrow, ncol, figsize=(fig_w, 3.8 * nrow + 0.9), squeeze=False)
    for ax, sc in zip(axs.flat, scs):
        r0 = at_ref(rows, dict(ref, scenario=sc))
        kinds = [k for k in KINDS if sum(r["%s_spurious" % k] or 0 for r in r0)]
        for j, m in enumerate(a.methods):
            x = [r for r in r0 if r["method"] == m]
            for i, k in enumerate(kinds):
                rec = pooled(x, ["%s_detected" % k], ["%s_spurious" % k])
                s = stats(vals(x, "%s_recall" % k))
                ax.bar(i - 0.4 + w * (j + 0.5), rec or 0, w, color=colors[m],
                       yerr=s[1] if s else None, capsize=1.5, error_kw=dict(lw=0.7))
        ax.set_xticks(range(len(kinds)), kinds)
        ax.set(ylim=(0, 1.05), ylabel="recall (strict)", title=sc)
        ax.grid(alpha=0.3, axis="y")
    for ax in list(axs.flat)[len(scs):]:
        ax.axis("off")
    fig.legend(handles=[plt.Rectangle((0, 0), 1, 1, color=colors[m], label=m) for m in a.methods],
               **legend_kw)
    fig.suptitle("Recall per fault kind, pooled over %d seeds (bar: sd over seeds), %s" %
                 (len(a.seeds), ", ".join("%s = %s" % kv for kv in ref.items())), fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 0.96))
    fig.savefig(os.path.join(a.out, "kind_recall.png"), dpi=110)
    plt.close(fig)


# ------------------------------------------------------------------------------------------- main
def fmt_csv(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ""
    return str(v)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 1)[1])
    sfd_tool_cli.add_version(ap, "evaluate.py")
    ap.add_argument("--preset", choices=sorted(PRESETS), default="quick",
                    help="quick (the test suite's) or full (docs/evaluation.md); default quick")
    ap.add_argument("--scenarios", help="comma list of " + ", ".join(SCENARIOS))
    ap.add_argument("--seeds", help="comma list of seeds")
    ap.add_argument("--methods", help="comma list of " + ", ".join(METHODS))
    ap.add_argument("--alpha", help="comma list of false-alarm levels (= --grid alpha=...)")
    ap.add_argument("--grid", action="append", metavar="KEY=V1,V2",
                    help="sfd-replay parameter grid, keys: " + ", ".join(GRID) + " (repeatable)")
    ap.add_argument("--frames", type=int, help="sfd-sim flights: --frames N (0: sfd-sim's default)")
    ap.add_argument("--sim-args", action="append", metavar="SCENARIO=ARGS", default=[],
                    help="replace a scenario's extra sfd-sim arguments, e.g. "
                         "'worst-case=--random-fraction 0.5'")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "host"),
                    help="build tree with apps/sfd-sim and apps/sfd-replay (build/host)")
    ap.add_argument("--data", default=os.path.join(os.path.dirname(ROOT), "shared", "data",
                                                   "euroc_v1_02_imu_gt"),
                    help="EuRoC V1_02 IMU + ground truth for euroc-semireal")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "evaluate"),
                    help="work and output directory (out/evaluate)")
    ex = ap.add_mutually_exclusive_group()
    ex.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="LocalCluster worker processes (default: CPU count)")
    ex.add_argument("--scheduler", help="tcp://HOST:PORT of a running Dask scheduler")
    ex.add_argument("--serial", action="store_true", help="run in this process, no Dask")
    a = ap.parse_args(argv)
    a.argv = ["tools/evaluate.py"] + list(argv)
    p = PRESETS[a.preset]
    a.explicit_scenarios = a.scenarios.split(",") if a.scenarios else []
    a.scenarios = a.explicit_scenarios or list(p["scenarios"])
    a.methods = (a.methods or p["methods"]).split(",")
    try:
        a.seeds = sorted({int(s) for s in (a.seeds or p["seeds"]).split(",")})
    except ValueError:
        ap.error("--seeds: integers")
    a.frames = p["frames"] if a.frames is None else a.frames
    bad = [s for s in a.scenarios if s not in SCENARIOS]
    bad += [m for m in a.methods if m not in METHODS]
    if bad or a.workers < 1 or a.frames < 0:
        ap.error("unknown scenario/method %s (or --workers < 1, --frames < 0)" % ",".join(bad))
    grid = {}
    specs = (a.grid if a.grid else list(p["grid"])) + (["alpha=" + a.alpha] if a.alpha else [])
    for g in specs:
        k, _, v = g.partition("=")
        if k not in GRID or not v:
            ap.error("--grid %s: KEY=V1,V2 with KEY one of %s" % (g, ", ".join(GRID)))
        try:
            grid[k] = sorted(dict.fromkeys(v.split(",")), key=num)
        except ValueError:
            ap.error("--grid %s: numbers" % g)
    a.grid = grid
    sa = {}
    for s in a.sim_args:
        k, _, v = s.partition("=")
        if k not in SCENARIOS:
            ap.error("--sim-args %s: unknown scenario" % s)
        sa[k] = shlex.split(v)
    a.sim_args = sa
    a.build, a.data, a.out = (os.path.abspath(x) for x in (a.build, a.data, a.out))
    return a


def main(argv):
    a = parse_args(argv)
    config = os.path.join(ROOT, "apps", "config", "sfd.yaml")
    for b in ("sfd-sim", "sfd-replay"):
        if not os.access(os.path.join(a.build, "apps", b), os.X_OK):
            print("evaluate.py: %s/apps/%s missing: build it (cmake --build --preset host --target "
                  "sfd-sim sfd-replay) or pass --build" % (a.build, b), file=sys.stderr)
            return 2
    skipped = []
    if "euroc-semireal" in a.scenarios and "euroc-semireal" not in a.sim_args and \
            not os.path.isfile(os.path.join(a.data, "mav0", "imu0", "data.csv")):
        why = "%s has no mav0/imu0/data.csv (the shared EuRoC V1_02 data, ../shared/data)" % a.data
        if "euroc-semireal" in a.explicit_scenarios:
            print("evaluate.py: euroc-semireal: " + why, file=sys.stderr)
            return 2
        print("evaluate.py: SKIPPING euroc-semireal: " + why, file=sys.stderr)
        skipped.append(("euroc-semireal", why))
        a.scenarios.remove("euroc-semireal")
    if not a.scenarios:
        print("evaluate.py: no scenario left to run", file=sys.stderr)
        return 2
    # Reference point: the configuration's value when in the grid, else the grid's first value.
    ref = {}
    for k, vs in a.grid.items():
        c = config_value(config, GRID[k][1])
        ref[k] = next((v for v in vs if c is not None and num(v) == c), vs[0])
    os.makedirs(a.out, exist_ok=True)
    gens, reps = plan(a, a.grid, config)
    print("evaluate.py: %d logs, %d replays (%s) -> %s" % (
        len(gens), len(reps), "serial" if a.serial else a.scheduler or
        "LocalCluster, %d workers" % a.workers, a.out), file=sys.stderr, flush=True)
    t0 = time.monotonic()
    g, res = execute(a, gens, reps)
    wall = time.monotonic() - t0
    with open(os.path.join(a.out, "commands.log"), "w") as f:
        for k in sorted(gens):
            f.write("$ %s\n%s\n" % (" ".join(map(shlex.quote, gens[k]["cmd"])),
                                    g[k].get("stdout", "")))
        for r in reps:
            f.write("$ %s\n" % " ".join(map(shlex.quote, r["cmd"])))
    failed = [r for r in res if not r["ok"]]
    if failed:
        seen = set()
        for r in failed:
            c = " ".join(map(shlex.quote, r["cmd"]))
            if c not in seen:
                seen.add(c)
                print("evaluate.py: FAILED (exit %s): %s\n%s" % (r["rc"], c, r["stderr"].rstrip()),
                      file=sys.stderr)
        print("evaluate.py: %d of %d runs failed" % (len(failed), len(res)), file=sys.stderr)
        return 1
    scen = {s: i for i, s in enumerate(SCENARIOS)}
    rows = sorted((r["row"] for r in res), key=lambda r: (
        scen[r["scenario"]], r["seed"], METHODS.index(r["method"]),
        tuple(num(r[k]) for k in a.grid)))
    cols = ["scenario", "seed", "method"] + list(a.grid) + [c for c, _ in COLUMNS] + \
        ["rejected_total", "json"] + [c for c, _ in TIME_COLUMNS]
    with open(os.path.join(a.out, "results.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(cols)
        for r in rows:
            w.writerow([fmt_csv(r[c]) for c in cols])
    md = summary_md(a, rows, ref, a.grid, skipped, gens, wall)
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(md + "\n")
    plots(a, rows, ref, a.grid)
    print(md)
    print("evaluate.py: %d runs in %.1f s; wrote results.csv, summary.md, pr_curves.png, ate.png, "
          "kind_recall.png in %s" % (len(rows), wall, a.out), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
