#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.review_report: tools/review.py on an sfd-replay OUT log (sfd-sim mistracking, 60
# frames, with TRUTH):
#  - it writes one self-contained HTML file with the four sections (verdicts, timing, position,
#    rejections) and 4 embedded PNG figures (base64, each a valid PNG), and links nothing outside;
#  - the numbers it prints equal sfd-replay's --summary JSON: features tested / spurious, frames
#    in / refused / processed / untested, every rejected[] counter, and the ATE (its own
#    position+yaw alignment against TRUTH, to 6 significant digits);
#  - sfd-replay's OUT carries SFD_TIMING durations of 0, which the report says; on a copy of the
#    log whose SFD_TIMING carry known durations (3 frames over 1 ms, 2 of them over 2 ms) it
#    counts exactly those against the budget lines;
#  - its strict scores against TRUTH equal the summary's (detections, false alarms, misses with
#    the UNTESTED spurious ones), its false alarms by frames since the track's last spurious
#    label add up to them, and on a copy of the log with two verdicts changed (a clean
#    observation right after a run of spurious labels made SPURIOUS, the first spurious
#    observation of a track's second run made CONSISTENT) exactly the bins they fall in move by one;
#  - a log without SFD_VERDICT is exit 2 with a one-line message naming the file.
# usage: review_report.sh BUILD_DIR SOURCE_DIR PYTHON PYTHONPATH_FOR_TYPES
set -euo pipefail
build="$1"; src="$2"; py="$3"; pytypes="$4"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$build/apps/sfd-sim" mistracking -o "$tmp/in.lcmlog" --frames 60 --seed 3 >/dev/null
"$build/apps/sfd-replay" "$tmp/in.lcmlog" -o "$tmp/out.lcmlog" --summary "$tmp/s.json" >/dev/null
export SFD_LCM_PYTHON="$pytypes"
"$py" "$src/tools/review.py" "$tmp/out.lcmlog" -o "$tmp/report.html" > "$tmp/review.txt"
cat "$tmp/review.txt"

# A log with sensor input only (no SFD_VERDICT): refused, exit 2, one line naming the file.
rc=0; "$py" "$src/tools/review.py" "$tmp/in.lcmlog" -o "$tmp/bad.html" 2> "$tmp/err.txt" || rc=$?
[ "$rc" -eq 2 ] || { echo "review.py on a log without SFD_VERDICT: exit $rc, want 2"; exit 1; }
[ "$(wc -l < "$tmp/err.txt")" -eq 1 ] &&
  grep -q "$tmp/in.lcmlog: no SFD_VERDICT" "$tmp/err.txt" || {
  echo "review.py's refusal is not one line naming the file:"; cat "$tmp/err.txt"; exit 1; }
[ ! -e "$tmp/bad.html" ] || { echo "review.py wrote a report for a refused log"; exit 1; }

PYTHONPATH="$pytypes" "$py" - "$tmp" "$src" "$py" <<'PYEOF'
import base64, json, re, subprocess, sys
import lcm
from sfd import feature_verdict_t, timing_t, truth_t
d, src, py = sys.argv[1:4]
html = open(f"{d}/report.html", encoding="utf-8").read()
out = open(f"{d}/review.txt").read()
summ = json.load(open(f"{d}/s.json"))

for sec in ("verdicts", "timing", "position", "rejections"):
    assert f'<h2 id="{sec}">' in html, f"section {sec} missing"
imgs = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
assert len(imgs) == 4, f"{len(imgs)} embedded images, want 4"
for b in imgs:
    png = base64.b64decode(b, validate=True)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000, "an embedded image is not a PNG"
assert not re.search(r'(src|href)="(?!data:|#)', html), "the report links an outside file"
assert "(4 figures)" in out, out

# Numbers printed against the JSON summary.
m = re.search(r"judged: frames (\d+) tested (\d+) consistent (\d+) spurious (\d+) untested (\d+) "
              r"frames_untested (\d+)", out)
assert m, out
frames, tested, consistent, spurious, untested, frames_untested = map(int, m.groups())
j, f = summ["judged"], summ["frames"]
assert (tested, spurious) == (j["tested"], j["spurious"]), (m.groups(), j)
assert consistent == tested - spurious and frames == f["processed"], (m.groups(), f)
assert frames_untested == f["untested"], (frames_untested, f)
assert tested + untested == summ["detection"]["labelled"], "every feature of every frame judged"
m = re.search(r"frames in (\d+) refused (\d+) processed (\d+) untested (\d+); rejected: (.*)", out)
assert m, out
assert list(map(int, m.groups()[:4])) == [f["in"], f["refused"], f["processed"], f["untested"]]
rej = dict(kv.split("=") for kv in m.group(5).split())
assert {k: int(v) for k, v in rej.items()} == summ["rejected"], (rej, summ["rejected"])
m = re.search(r"ATE ([0-9.e+-]+) m \(position\+yaw aligned\), raw RMSE ([0-9.e+-]+) m", out)
assert m, out
tr = summ["trajectory"]
assert abs(float(m.group(1)) - tr["ate_m"]) <= 1e-5 * tr["ate_m"], (m.group(1), tr["ate_m"])
assert abs(float(m.group(2)) - tr["rmse_raw_m"]) <= 1e-5 * tr["rmse_raw_m"], (m.group(2), tr)
assert re.search(r"position: %d states" % tr["frames"], out), (out, tr["frames"])
assert "every duration 0" in out and "Every duration in this log is 0" in html

# Strict scores and where the errors are, against the summary.
def anatomy(text):
    m = re.search(r"detection: tp (\d+) fp (\d+) missed (\d+) \(untested (\d+)\) f1 ([0-9.]+)",
                  text)
    assert m, text
    kinds = re.search(r"misses by kind: (.*); by place: (.*)", text)
    since = re.search(r"false alarms by frames since the track's last spurious label: (.*)", text)
    assert kinds and since, text
    parse = lambda s: {k: v for k, v in (kv.split("=") for kv in s.split())}
    return (list(map(int, m.groups()[:4])), float(m.group(5)),
            {k: int(v) for k, v in parse(kinds.group(1)).items()},
            {k: int(v) for k, v in parse(kinds.group(2)).items()},
            {k: tuple(map(int, v.split("/"))) for k, v in parse(since.group(1)).items()})
det = summ["detection"]
(tp, fp, missed, missed_untested), f1, by_kind, by_place, by_since = anatomy(out)
assert (tp, fp) == (det["tp"], det["fp"]), (tp, fp, det)
assert (missed, missed_untested) == (det["fn"] + det["untested_spurious"],
                                     det["untested_spurious"]), (missed, det)
assert abs(f1 - det["f1"]) < 1e-4, (f1, det["f1"])
assert sum(by_kind.values()) == missed == sum(by_place.values()), (by_kind, by_place, missed)
for name, k in det["by_kind"].items():
    assert by_kind[name] == k["spurious"] - k["detected"], (name, by_kind, k)
assert sum(a for a, _ in by_since.values()) == fp, by_since
assert sum(n for _, n in by_since.values()) == det["tn"] + fp, (by_since, det)

# Two verdicts changed in a copy: the first clean CONSISTENT observation that follows a track's
# spurious label in its next frame becomes SPURIOUS (bin "1"), and the first SPURIOUS
# observation that starts a track's second (or later) run of spurious labels becomes
# CONSISTENT (a miss in place 1st: the run count starts again). Labels by utime; a track's
# previous frame is its previous labelled frame.
labels = {}
for ev in lcm.EventLog(f"{d}/out.lcmlog", "r"):
    if ev.channel == "TRUTH":
        t = truth_t.decode(ev.data)
        labels[t.utime] = {t.track_id[i]: t.spurious[i] for i in range(t.num_features)}
prev, flip, seen_label = {}, {}, set()
for ev in lcm.EventLog(f"{d}/out.lcmlog", "r"):
    if ev.channel != "SFD_VERDICT":
        continue
    v = feature_verdict_t.decode(ev.data)
    lab = labels.get(v.utime, {})
    for i in range(v.num_features):
        tid = v.track_id[i]
        if tid not in lab:
            continue
        was = prev.get(tid)
        if "fa" not in flip and was == 1 and lab[tid] == 0 and v.status[i] == 1:
            flip["fa"] = (v.utime, tid)
        if "miss" not in flip and was == 0 and tid in seen_label and lab[tid] == 1 and \
                v.status[i] == 2:
            flip["miss"] = (v.utime, tid)
        prev[tid] = lab[tid]
        if lab[tid]:
            seen_label.add(tid)
assert len(flip) == 2, flip
dst = lcm.EventLog(f"{d}/flipped.lcmlog", "w", overwrite=True)
for ev in lcm.EventLog(f"{d}/out.lcmlog", "r"):
    data = ev.data
    if ev.channel == "SFD_VERDICT":
        v = feature_verdict_t.decode(data)
        v.status = list(v.status)  # decoded arrays are tuples
        for i in range(v.num_features):
            if (v.utime, v.track_id[i]) == flip["fa"]:
                v.status[i] = 2
            if (v.utime, v.track_id[i]) == flip["miss"]:
                v.status[i] = 1
        data = v.encode()
    dst.write_event(ev.timestamp, ev.channel, data)
dst.close()
r = subprocess.run([py, f"{src}/tools/review.py", f"{d}/flipped.lcmlog"], capture_output=True,
                   text=True, check=True)
(tp2, fp2, missed2, mu2), _, by_kind2, by_place2, by_since2 = anatomy(r.stdout)
assert (tp2, fp2, missed2, mu2) == (tp - 1, fp + 1, missed + 1, missed_untested), r.stdout
assert by_place2 == {**by_place, "1st": by_place["1st"] + 1}, (by_place, by_place2)
assert by_since2 == {**by_since, "1": (by_since["1"][0] + 1, by_since["1"][1])}, by_since2
assert sum(by_kind2.values()) == missed + 1, by_kind2

# Timing against the budget: the same log with known SFD_TIMING durations.
src_log = lcm.EventLog(f"{d}/out.lcmlog", "r")
dst = lcm.EventLog(f"{d}/timed.lcmlog", "w", overwrite=True)
k = 0
totals = {10: 1500, 20: 2500, 30: 4000}  # frame index -> total_us; the rest 400
for ev in src_log:
    data = ev.data
    if ev.channel == "SFD_TIMING":
        t = timing_t.decode(data)
        if t.frame_processed:
            t.total_us = totals.get(k, 400)
            t.publish_us, t.ingest_us, t.parity_us = 50, 10, 100
            t.association_us, t.update_us = 20, t.total_us - 180
            k += 1
        data = t.encode()
    dst.write_event(ev.timestamp, ev.channel, data)
dst.close()
r = subprocess.run([py, f"{src}/tools/review.py", f"{d}/timed.lcmlog"], capture_output=True,
                   text=True, check=True)
assert f"timing frames {k}, total_us over 2 ms 2\n" in r.stdout, r.stdout
h = open(f"{d}/timed.html", encoding="utf-8").read()
row = re.search(r"<tr><td>total_us</td>((?:<td>[^<]*</td>)+)</tr>", h).group(1)
cells = re.findall(r"<td>([^<]*)</td>", row)
assert cells == ["400", "4000", "4000", "4000", "3", "2"], cells  # nearest rank, 60 frames
print(f"review_report: ok ({frames} frames, {tested} tested, {spurious} spurious, "
      f"ATE {tr['ate_m']:.4f} m, {len(imgs)} figures; F1 {f1:.4f}, false alarms "
      f"{fp}, of them {by_since['1'][0]} one frame after a fault's labels)")
PYEOF
