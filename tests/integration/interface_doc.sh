#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The runnable parts of docs/interface.md, taken from the document itself so it cannot drift:
#  publisher        integration.interface_publisher: the "A FEATURES publisher in Python" block
#                   is at most 10 lines of code; run with LCM_DEFAULT_URL pointing at an LCM log
#                   file, it publishes ten FEATURES messages that decode back to what it set, and
#                   sfd-replay reads all ten as frames (refused as no_camera_info: no calibration
#                   was sent; none as undecodable);
#  three_commands   integration.interface_three_commands: the "Replay your own log in three
#                   commands" block (sfd-euroc, sfd-replay, tools/review.py) on the shared EuRoC
#                   excerpt, with the repository paths mapped to this build; its report exists
#                   with its sections and figures, and its counts equal sfd-replay's summary.
#                   Skipped (77) when ../shared/data is absent.
#  figures          integration.interface_figures: every image docs/interface.md shows is a
#                   PNG file committed in the repository, and the three figures issue 19 asks
#                   for are among them (data flow, a verdict overlay on a EuRoC frame, the ROC).
# usage: interface_doc.sh publisher|three_commands|figures BUILD_DIR SOURCE_DIR PYTHON PYTHONPATH DATA_DIR
set -euo pipefail
mode="$1"; build="$2"; src="$3"; py="$4"; pytypes="$5"; datadir="$6"
doc="$src/docs/interface.md"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# The first fenced block of LANG after the line matching PATTERN.
block() {
  awk -v pat="$1" -v lang="$2" '
    index($0, pat) { found = 1 }
    found && !inb && $0 == "```" lang { inb = 1; next }
    inb && $0 == "```" { exit }
    inb { print }' "$doc"
}

case "$mode" in
figures)
  "$py" - "$doc" "$src" <<'PYEOF'
import os, re, subprocess, sys
doc, src = sys.argv[1:3]
links = re.findall(r"!\[([^\]]*)\]\(([^)]+)\)", open(doc, encoding="utf-8").read())
# committed: the files git tracks (no check outside a git checkout, e.g. a source tarball)
tracked = set(subprocess.run(["git", "-C", src, "ls-files", "docs"], capture_output=True,
                             text=True, check=False).stdout.split())
bad = 0
for alt, path in links:
    rel = os.path.relpath(os.path.normpath(os.path.join(os.path.dirname(doc), path)), src)
    full = os.path.join(src, rel)
    if not os.path.isfile(full) or open(full, "rb").read(8) != b"\x89PNG\r\n\x1a\n":
        print("docs/interface.md: %s: not a PNG file" % path); bad = 1
    elif tracked and rel not in tracked:
        print("docs/interface.md: %s: not committed" % path); bad = 1
alts = " | ".join(a.lower() for a, _ in links)
for want in ("data flow", "euroc", "roc"):  # whole words: "euroc" holds "roc"
    if not re.search(r"\b%s\b" % want, alts):
        print("docs/interface.md: no figure whose caption names %r (images: %s)" % (want, alts))
        bad = 1
print("interface_figures: %d images, all committed PNGs: %s" % (len(links), alts))
sys.exit(bad)
PYEOF
  ;;
publisher)
  block "integration.interface_publisher runs the block below" python > "$tmp/pub.py"
  code_lines=$(grep -cv '^[[:space:]]*$' "$tmp/pub.py" || true)
  [ "$code_lines" -ge 5 ] && [ "$code_lines" -le 10 ] || {
    echo "docs/interface.md's publisher has $code_lines lines of code, want 5..10"; exit 1; }
  LCM_DEFAULT_URL="file://$tmp/pub.lcmlog?mode=w" PYTHONPATH="$pytypes" "$py" "$tmp/pub.py"
  "$build/apps/sfd-replay" "$tmp/pub.lcmlog" --summary "$tmp/s.json" >/dev/null
  PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import json, sys
import lcm
from sfd import feature_frame_t
d = sys.argv[1]
msgs = [(ev.channel, feature_frame_t.decode(ev.data)) for ev in lcm.EventLog(f"{d}/pub.lcmlog", "r")]
assert [c for c, _ in msgs] == ["FEATURES"] * 10, [c for c, _ in msgs]
for k, (_, m) in enumerate(msgs):
    assert m.utime == 1_000_000 + 50_000 * k and m.camera_id == 0 and m.num_features == 2, k
    assert list(m.track_id[:2]) == [7, 8] and list(m.u[:2]) == [320.5 + k, 100.0], (k, m.u[:2])
    assert list(m.v[:2]) == [240.0, 50.25] and list(m.depth[:2]) == [0.0, 0.0], k
s = json.load(open(f"{d}/s.json"))
assert s["frames"] == {"in": 10, "refused": 10, "processed": 0, "untested": 0}, s["frames"]
r = s["rejected"]
assert r["no_camera_info"] == 10 and r["decode"] == 0 and r["count"] == 0, r
print("interface_publisher: ok (10 FEATURES decoded; sfd-replay read 10 frames, "
      "refused for want of CAMERA_INFO only)")
PYEOF
  ;;
three_commands)
  if [ ! -d "$datadir/euroc_v1_01_flight10/frontend/cam0" ]; then
    echo "SKIPPED: $datadir/euroc_v1_01_flight10 not present (real EuRoC data lives in" \
         "../shared/data next to the repo)"
    exit 77
  fi
  block "## Replay your own log in three commands" sh > "$tmp/doc.sh"
  [ "$(grep -c '^[^ ].*' "$tmp/doc.sh")" -eq 4 ] || {  # D=..., and the three commands
    echo "docs/interface.md's three-command block changed shape:"; cat "$tmp/doc.sh"; exit 1; }
  # The repository's relative paths, mapped onto this build, source tree, Python and data.
  sed -e "s#\.\./shared/data#$datadir#g" -e "s#build/host/#$build/#g" \
      -e "s#\.venv/bin/python#$py#g" -e "s# tools/# $src/tools/#g" "$tmp/doc.sh" > "$tmp/run.sh"
  (cd "$tmp" && SFD_LCM_PYTHON="$pytypes" bash -euo pipefail run.sh) | tee "$tmp/out.txt"
  grep -q "^review.py v101.out.lcmlog: wrote v101.html (3 figures)$" "$tmp/out.txt"
  PYTHONPATH="$pytypes" "$py" - "$tmp" <<'PYEOF'
import json, re, sys
d = sys.argv[1]
h = open(f"{d}/v101.html", encoding="utf-8").read()
out = open(f"{d}/out.txt").read()
s = json.load(open(f"{d}/v101.json"))
for sec in ("verdicts", "timing", "position", "rejections"):
    assert f'<h2 id="{sec}">' in h, sec
assert "No position error" in h  # 0.45 s in flight: no SFD_STATE from an at-rest start
assert len(re.findall(r'src="data:image/png;base64,', h)) == 3
m = re.search(r"judged: frames (\d+) tested (\d+) consistent \d+ spurious (\d+)", out)
assert m and int(m.group(1)) == s["frames"]["processed"] == 10, (m and m.groups(), s["frames"])
assert (int(m.group(2)), int(m.group(3))) == (s["judged"]["tested"], s["judged"]["spurious"])
print("interface_three_commands: ok")
PYEOF
  ;;
*)
  echo "interface_doc.sh: unknown mode '$mode' (publisher, three_commands)" >&2
  exit 2
  ;;
esac
