#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Copies an sfd log with every feature TRUTH labels spurious removed from its FEATURES
messages: the input a perfect detector would leave the filter (evaluation only; it reads TRUTH).
Replaying the copy (`sfd-replay OUT --method none`) measures the trajectory the window filter
reaches when no labelled fault reaches it, the floor of issue 16's drift figure
(docs/evaluation.md "Drift with perfect detection").

Usage: strip_spurious.py IN.lcmlog OUT.lcmlog [--frame-stride K]

--frame-stride K keeps only every K-th FEATURES message (the first, the (K+1)-th, ...) and the
TRUTH of those frames: the same flight seen by a camera K times slower, for the drift's
dependence on the spacing of the window filter's clones (docs/evaluation.md "The floor depends on
the spacing of the clones"). IMU and CAMERA_INFO are kept whole.

Every other event is copied unchanged, in order, with its timestamp (with --frame-stride, the
TRUTH of a left-out frame is left out too, unless a kept FEATURES message has the same time). A
FEATURES message keeps its other features in their order; one whose frame has no TRUTH is copied
unchanged. The generated Python LCM types are found as `sfd` on PYTHONPATH, else in $SFD_LCM_PYTHON, else in
build/host/lcm_types/python next to this script. Exit 0; 2 for bad usage or an unreadable log."""
import argparse
import os
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py


def fail(msg):
    """Bad usage or input: one line on stderr, exit 2."""
    print(f"strip_spurious.py: {msg}", file=sys.stderr)
    sys.exit(2)


def import_types():
    """lcm and the generated LCM types (package sfd)."""
    try:
        import lcm
    except ImportError:
        fail("the Python module 'lcm' is missing (tools/setup.sh installs it)")
    sfd = sfd_tool_cli.import_lcm_types("strip_spurious.py")
    return lcm, sfd.feature_frame_t, sfd.truth_t


def main():
    ap = argparse.ArgumentParser(prog="strip_spurious.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "strip_spurious.py")
    ap.add_argument("input", metavar="IN.lcmlog")
    ap.add_argument("output", metavar="OUT.lcmlog")
    ap.add_argument("--frame-stride", type=int, default=1, metavar="K",
                    help="keep every K-th frame (FEATURES and its TRUTH), K >= 1 (1)")
    a = ap.parse_args()
    if a.frame_stride < 1:
        fail(f"--frame-stride {a.frame_stride}: want an integer >= 1")
    if os.path.abspath(a.input) == os.path.abspath(a.output) or (
            os.path.exists(a.output) and os.path.samefile(a.input, a.output)):
        fail(f"OUT {a.output} is IN")
    lcm, feature_frame_t, truth_t = import_types()
    try:
        events = list(lcm.EventLog(a.input, "r"))
    except (IOError, OSError, ValueError) as e:
        fail(f"{a.input}: {e}")
    spurious = {}  # frame time -> labelled spurious track ids
    # The stride counts FEATURES messages in log order: message j is kept when j % K == 0. The
    # TRUTH of a left-out frame goes with it, unless a kept message has the same time.
    skip = set()  # indices (in events) of the messages left out
    kept_times, left_times = set(), set()
    truth_at = []  # (index in events, frame time) of every TRUTH message
    frames = left_out = 0
    for k, e in enumerate(events):
        if e.channel == "FEATURES":
            if a.frame_stride > 1:
                ut = feature_frame_t.decode(e.data).utime
                if frames % a.frame_stride:
                    skip.add(k)
                    left_times.add(ut)
                    left_out += 1
                else:
                    kept_times.add(ut)
            frames += 1
        if e.channel == "TRUTH":
            t = truth_t.decode(e.data)
            spurious[t.utime] = {t.track_id[i] for i in range(t.num_features) if t.spurious[i]}
            truth_at.append((k, t.utime))
    truth_left = left_times - kept_times
    skip.update(k for k, ut in truth_at if ut in truth_left)
    removed = kept = written = 0
    out = lcm.EventLog(a.output, "w", overwrite=True)
    for k, e in enumerate(events):
        data = e.data
        if k in skip:
            continue
        if e.channel == "FEATURES":
            f = feature_frame_t.decode(e.data)
            bad = spurious.get(f.utime, set())
            keep = [i for i in range(f.num_features) if f.track_id[i] not in bad]
            removed += f.num_features - len(keep)
            kept += len(keep)
            g = feature_frame_t()
            g.utime, g.camera_id, g.num_features = f.utime, f.camera_id, len(keep)
            for name in ("track_id", "u", "v", "depth", "depth_var"):
                src, dst = getattr(f, name), list(getattr(g, name))
                for j, i in enumerate(keep):
                    dst[j] = src[i]
                setattr(g, name, dst)
            data = g.encode()
        out.write_event(e.timestamp, e.channel, data)
        written += 1
    out.close()
    print(f"strip_spurious.py: {a.output}: {written} of {len(events)} events, {kept} features "
          f"kept, {removed} labelled spurious removed, {left_out} of {frames} frames left out")


if __name__ == "__main__":
    main()
