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
from sfd import timing_t
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
      f"ATE {tr['ate_m']:.4f} m, {len(imgs)} figures)")
PYEOF
