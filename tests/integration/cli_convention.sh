#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.cli_convention: the one command-line convention of every executable (docs/deploy.md,
# "Command line"):
#  - `--version` prints "TOOL MAJOR.MINOR.PATCH" of core/include/sfd/sfd_version.h, exit 0;
#  - `--help` exit 0 on every tool and subcommand (sfd-sim SCENARIO, sfd-bench parity/assoc);
#  - an unknown option and an abbreviation are exit 2, one line naming the option;
#  - a bad value is exit 2, one line "TOOL: --flag: VALUE is not ...";
#  - `--opt=value` equals `--opt value`: the same sfd-sim log and the same sfd-replay OUT and
#    summary, byte for byte;
#  - the flags of sfd-node and sfd-replay are the keys of apps/config/sfd.yaml ('_' written '-',
#    the dot kept), the same on both, and docs/deploy.md's table lists exactly them;
#  - progress lines: none when stderr is not a terminal (the outputs above), one on a terminal
#    (script(1)) unless CI is set (sfd-replay, and sfd-sim thesis-loop: the thesis sweep).
#  - the Python scripts of tools/ (run with PYTHON): `--help` exit 0, `--version` "SCRIPT
#    VERSION", and an unknown option exit 2 with one line naming it on those without argparse.
# usage: cli_convention.sh BUILD_DIR [PYTHON]
set -euo pipefail
build="$1"; py="${2:-python3}"
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
apps="$build/apps"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

hdr="$src/core/include/sfd/sfd_version.h"
major="$(awk '/#define SFD_VERSION_MAJOR/ {print $3}' "$hdr")"
minor="$(awk '/#define SFD_VERSION_MINOR/ {print $3}' "$hdr")"
patch="$(awk '/#define SFD_VERSION_PATCH/ {print $3}' "$hdr")"
version="$major.$minor.${patch:-0}"

# usage_error EXPECTED-LINE CMD...: exit 2 and exactly that one line on stderr, nothing on stdout
usage_error() {
  local expected="$1"; shift
  local rc=0
  timeout 20 "$@" > out.txt 2> err.txt || rc=$?
  if [ "$rc" -ne 2 ] || [ "$(cat err.txt)" != "$expected" ] || [ -s out.txt ]; then
    fail "$*: exit $rc, stderr '$(cat err.txt)', expected exit 2 and '$expected'"
  else
    echo "ok: exit 2: $expected"
  fi
}

tools=(sfd-node sfd-replay sfd-sim sfd-hil sfd-bench sfd-euroc)
for t in "${tools[@]}"; do
  got="$("$apps/$t" --version)" || fail "$t --version: exit $?"
  [ "$got" = "$t $version" ] || fail "$t --version: '$got', expected '$t $version'"
  "$apps/$t" --help > help.txt || fail "$t --help: exit $?"
  head -1 help.txt | grep -q "^usage: $t" || fail "$t --help: no usage line"
done
echo "ok: --version ($version) and --help on ${tools[*]}"
for s in paper-uav mistracking moving-object worst-case euroc-semireal isolation uav-imu thesis-loop; do
  "$apps/sfd-sim" "$s" --help > help.txt || fail "sfd-sim $s --help: exit $?"
  head -1 help.txt | grep -q "^usage: sfd-sim $s" || fail "sfd-sim $s --help: no usage line"
done
for s in parity assoc; do
  "$apps/sfd-bench" "$s" --help > help.txt || fail "sfd-bench $s --help: exit $?"
  head -1 help.txt | grep -q "^usage: sfd-bench $s" || fail "sfd-bench $s --help: no usage line"
  "$apps/sfd-bench" "$s" --version | grep -qx "sfd-bench $version" || fail "sfd-bench $s --version"
done
echo "ok: --help on every subcommand (sfd-sim's 8 scenarios, sfd-bench parity and assoc)"

# The Python scripts of tools/ (tools/sfd_tool_cli.py): the same --help and --version.
for f in "$src"/tools/*.py; do
  name="$(basename "$f")"
  [ "$name" = sfd_tool_cli.py ] && continue
  timeout 60 "$py" "$f" --help > help.txt 2> help.err || fail "$name --help: exit $?: $(head -3 help.err)"
  got="$(timeout 60 "$py" "$f" --version 2>&1)" || fail "$name --version: exit $?"
  [ "$got" = "$name $version" ] || fail "$name --version: '$got', expected '$name $version'"
  if ! grep -q "^import argparse" "$f"; then
    usage_error "$name: unknown option --no-such-option ($name --help lists the options)" \
      "$py" "$f" --no-such-option
  fi
done
[ ! -e ./--version.png ] || fail "a script took --version for a file name"
echo "ok: --help and --version on the Python scripts of tools/"

# Unknown options (an abbreviation is one) and bad values, on every tool.
for t in "${tools[@]}"; do
  usage_error "$t: unknown option --no-such-option ($t --help lists the options)" \
    "$apps/$t" --no-such-option
done
usage_error "sfd-bench: unknown option --no-such-option (sfd-bench parity --help lists the options)" \
  "$apps/sfd-bench" parity --no-such-option
usage_error "sfd-sim: unknown option --fram (sfd-sim mistracking --help lists the options)" \
  "$apps/sfd-sim" mistracking --fram 10
usage_error "sfd-replay: unknown option --window-frame (sfd-replay --help lists the options)" \
  "$apps/sfd-replay" in.lcmlog --window-frame 3
usage_error "sfd-replay: --window-frames: 2.5 is not an integer" \
  "$apps/sfd-replay" in.lcmlog --window-frames=2.5
usage_error "sfd-node: --filter.window-size: x is not an integer" \
  "$apps/sfd-node" --lcm-url memq:// --filter.window-size x
usage_error "sfd-sim: --frames: 2.5 is not an integer" "$apps/sfd-sim" mistracking --frames 2.5
usage_error "sfd-sim: --pixel-sigma-px: -1 is not in 0..100" \
  "$apps/sfd-sim" mistracking --pixel-sigma-px=-1
usage_error "sfd-hil: --rate: fast is not a number" "$apps/sfd-hil" --sim mistracking --rate fast
usage_error "sfd-bench: --features: 0 is not in 1..512" "$apps/sfd-bench" parity --single --features 0
usage_error "sfd-bench: --trials: x is not an integer" "$apps/sfd-bench" assoc --trials=x
usage_error "sfd-euroc: --max-features: x is not an integer" "$apps/sfd-euroc" --max-features x
usage_error "sfd-euroc: --camera-id: -1 is not in 0..2147483647" "$apps/sfd-euroc" --camera-id=-1
usage_error "sfd-replay: --summary needs a value" "$apps/sfd-replay" in.lcmlog --summary
usage_error "sfd-replay: --salvage takes no value" "$apps/sfd-replay" in.lcmlog --salvage=1

# --opt=value equals --opt value, byte for byte (and no progress line off a terminal).
"$apps/sfd-sim" mistracking -o a.lcmlog --seed 3 --frames 60 --outlier-ratio 0.2 > /dev/null
"$apps/sfd-sim" mistracking --output=b.lcmlog --seed=3 --frames=60 --outlier-ratio=0.2 > /dev/null
cmp -s a.lcmlog b.lcmlog || fail "sfd-sim: --opt=value gives another log than --opt value"
"$apps/sfd-replay" a.lcmlog -o r1.lcmlog --summary s1.json --method both --false-alarm-rate 0.05 \
  --window-frames 4 --filter.window-size 4 --gyro-bias-rad-s 0,0,0 > /dev/null 2> r1.err
"$apps/sfd-replay" a.lcmlog --output=r2.lcmlog --summary=s2.json --method=both \
  --false-alarm-rate=0.05 --window-frames=4 --filter.window-size=4 --gyro-bias-rad-s=0,0,0 \
  > /dev/null 2> r2.err
cmp -s r1.lcmlog r2.lcmlog || fail "sfd-replay: --opt=value gives another OUT than --opt value"
cmp -s s1.json s2.json || fail "sfd-replay: --opt=value gives another summary than --opt value"
"$apps/sfd-replay" a.lcmlog -o r3.lcmlog > /dev/null 2> r3.err
cmp -s r1.lcmlog r3.lcmlog && fail "sfd-replay: the flags changed nothing (the check cannot fail)"
[ ! -s r1.err ] && [ ! -s r2.err ] || fail "sfd-replay printed on stderr off a terminal: $(cat r1.err)"
echo "ok: --opt=value == --opt value (sfd-sim log, sfd-replay OUT and summary); stderr quiet"

# Progress on a terminal (script(1) gives the tool a pty), quiet with CI set.
if command -v script > /dev/null; then
  env -u CI script -qec "'$apps/sfd-replay' a.lcmlog -o p.lcmlog" /dev/null > tty.txt
  grep -q "sfd-replay: [0-9]* frames, [0-9]* frames/s, done in" tty.txt ||
    fail "no progress line on a terminal: $(cat tty.txt)"
  cmp -s p.lcmlog r3.lcmlog || fail "the progress line changed OUT"
  CI=1 script -qec "'$apps/sfd-replay' a.lcmlog -o q.lcmlog" /dev/null > tty_ci.txt
  grep -q "frames/s" tty_ci.txt && fail "a progress line with CI set"
  # the thesis sweep (sfd-sim thesis-loop): runs done, cleared before each sweep's table
  env -u CI script -qec "'$apps/sfd-sim' thesis-loop --quick --runs 1 --frames 40" /dev/null > tl.txt
  grep -q "sfd-sim thesis-loop: 6 runs, [0-9]* runs/s, done in" tl.txt ||
    fail "sfd-sim thesis-loop: no progress line on a terminal: $(cat tl.txt)"
  "$apps/sfd-sim" thesis-loop --quick --runs 1 --frames 40 > tl_off.txt 2> tl_off.err
  [ ! -s tl_off.err ] && ! grep -q "runs/s" tl_off.txt ||
    fail "sfd-sim thesis-loop: a progress line off a terminal: $(cat tl_off.err)"
  echo "ok: progress line on a terminal (sfd-replay, sfd-sim thesis-loop), none with CI set"
fi

# The flags of sfd-node and sfd-replay: the YAML keys, both ways, and docs/deploy.md's table.
python3 - "$src/apps/config/sfd.yaml" "$src/docs/deploy.md" "$apps" <<'PY' || fail "flags and YAML keys differ"
import re, subprocess, sys
yaml_path, deploy, apps = sys.argv[1:]
keys, top = [], None
for line in open(yaml_path):
    if line.lstrip().startswith("#"):
        continue
    m = re.match(r"^(\s*)([A-Za-z0-9_]+):(.*)$", line.split(" #")[0].rstrip())
    if not m:
        continue
    indent, key, value = m.groups()
    if not indent:
        top = key if not value.strip() else None
        if top is None:
            keys.append(key)
    else:
        keys.append(top + "." + key)
want = {"--" + k.replace("_", "-") for k in keys}
bad = 0
for tool in ("sfd-node", "sfd-replay"):
    help_text = subprocess.run([apps + "/" + tool, "--help"], capture_output=True, text=True).stdout
    section = help_text.split("Configuration (", 1)[1]
    section = re.split(r"\n[A-Z]", section, maxsplit=1)[0]  # to the next heading
    flags = set(re.findall(r"^  (--[a-z0-9.-]+)", section, re.M)) - {"--config"}
    if flags != want:
        print("%s: flags without a key: %s; keys without a flag: %s"
              % (tool, sorted(flags - want), sorted(want - flags)))
        bad = 1
table = dict(re.findall(r"^\| `([a-z0-9_.]+)` \| `(--[a-z0-9.-]+)` \|$", open(deploy).read(), re.M))
if set(table) != set(keys) or any(table[k] != "--" + k.replace("_", "-") for k in keys):
    print("docs/deploy.md's flag table differs from sfd.yaml: %s"
          % sorted(set(table) ^ set(keys)))
    bad = 1
print("ok: %d YAML keys = the flags of sfd-node and sfd-replay = docs/deploy.md's table" % len(keys))
sys.exit(bad)
PY

if [ "$fails" -ne 0 ]; then echo "$fails failure(s)"; exit 1; fi
echo "cli_convention: all checks passed"
