#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.config_validation: sfd-node and sfd-replay accept and refuse exactly the same
# configurations (one validation, apps/common/sfd_app_config.hpp; docs/deploy.md,
# "Configuration validation"):
#  - the shipped apps/config/sfd.yaml is valid for both (sfd-replay gives the same OUT and summary
#    as without it; sfd-node starts and stops cleanly on SIGINT);
#  - each bad config file (a copy of sfd.yaml with one bad value: the defects of issue 18 and one
#    per kind of rule) and each bad flag is exit 2 from both tools, before sfd-node opens LCM,
#    with the same one-line message naming the file (or flag), the key and the value;
#  - a flag that repairs a bad file is judged after the file: both accept the result.
# usage: config_validation.sh BUILD_DIR
set -euo pipefail
build="$1"
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
replay="$build/apps/sfd-replay"
node="$build/apps/sfd-node"
golden="$src/tests/replay/golden.lcmlog"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
cp "$src/apps/config/sfd.yaml" shipped.yaml
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# --- the shipped configuration ----------------------------------------------------------------
timeout -k 5 60 "$replay" "$golden" -o plain.lcmlog --summary plain.json > /dev/null
timeout -k 5 60 "$replay" "$golden" --config shipped.yaml -o conf.lcmlog --summary conf.json \
  > /dev/null ||
  fail "sfd-replay refuses the shipped sfd.yaml"
cmp -s plain.lcmlog conf.lcmlog && cmp -s plain.json conf.json ||
  fail "the shipped sfd.yaml (which states the defaults) changes sfd-replay's output"
# memq://: LCM inside the process (no network); SIGINT after 1 s is a clean stop (exit 0).
rc=0
timeout -k 5 --preserve-status -s INT 1 "$node" --config shipped.yaml --lcm-url memq:// \
  > node_ok.txt 2>&1 || rc=$?
[ "$rc" -eq 0 ] || fail "sfd-node with the shipped sfd.yaml: exit $rc: $(cat node_ok.txt)"
grep -q "sfd-node: stopped" node_ok.txt || fail "sfd-node with the shipped sfd.yaml did not run"

# run TOOL ARGS...: exit code in $rc, stderr in TOOL.err (sfd-node ends by timeout, exit 124, if it
# wrongly accepts the configuration and starts).
run() {
  local tool="$1"; shift
  rc=0
  if [ "$tool" = node ]; then
    timeout 10 "$node" "$@" > node.out 2> node.err || rc=$?
  else
    rm -f out.lcmlog
    timeout -k 5 60 "$replay" "$golden" -o out.lcmlog "$@" > replay.out 2> replay.err || rc=$?
    [ ! -e out.lcmlog ] || fail "sfd-replay $*: left an output"
  fi
}

# check TOOL EXPECTED ARGS...: exit 2 with exactly the one line "sfd-TOOL: EXPECTED".
check() {
  local tool="$1" expected="$2"; shift 2
  run "$tool" "$@"
  local got
  got="$(cat "$tool.err")"
  if [ "$rc" -ne 2 ]; then fail "sfd-$tool $*: exit $rc, expected 2: $got"; return 1; fi
  if [ "$(wc -l < "$tool.err")" -ne 1 ]; then fail "sfd-$tool $*: not one line: $got"; return 1; fi
  if [ "$got" != "sfd-$tool: $expected" ]; then
    fail "sfd-$tool $*:"$'\n'"   got      '$got'"$'\n'"   expected 'sfd-$tool: $expected'"
    return 1
  fi
}

# both EXPECTED ARGS...: both tools refuse ARGS with the same message (sfd-node on memq://
# unless ARGS set --lcm-url or a config file names lcm_url).
cases=0
both() {
  local expected="$1"; shift
  cases=$((cases + 1))
  check replay "$expected" "$@" || return 0
  check node "$expected" --lcm-url memq:// "$@" || return 0
  [ "$(sed 's/^sfd-replay: //' replay.err)" = "$(sed 's/^sfd-node: //' node.err)" ] ||
    fail "the two tools differ on $*"
  echo "exit 2 from both: $expected"
}

# bad NAME SED-EXPRESSION: NAME.yaml, the shipped file with one value changed (the edit must apply).
bad() {
  sed -e "$2" shipped.yaml > "$1.yaml"
  ! cmp -s shipped.yaml "$1.yaml" || { echo "config_validation: '$2' changed nothing"; exit 1; }
}

# --- bad config files: the defects of issue 18 ------------------------------------------------
bad gyro_nan 's/gyro_noise_rad_s_rthz: 1.0e-3/gyro_noise_rad_s_rthz: .nan/'
both "gyro_nan.yaml: filter.gyro_noise_rad_s_rthz: nan is not finite" --config gyro_nan.yaml
bad accel_neg 's/accel_noise_m_s2_rthz: 1.2e-2/accel_noise_m_s2_rthz: -1.2e-2/'
both "accel_neg.yaml: filter.accel_noise_m_s2_rthz: -0.012 is not >= 0" --config accel_neg.yaml
bad gravity 's/gravity_m_s2: 9.81/gravity_m_s2: -9.81/'
both "gravity.yaml: filter.gravity_m_s2: -9.81 is not > 0" --config gravity.yaml
bad enabled 's/enabled: 1/enabled: 7/'
both "enabled.yaml: filter.enabled: 7 is not 0 or 1" --config enabled.yaml
bad channels 's/verdict: "SFD_VERDICT"/verdict: "FEATURES"/'
both 'channels.yaml: channels.verdict: "FEATURES" is the same as channels.features' \
  --config channels.yaml
bad camera_id 's/camera_id: -1/camera_id: 123456789012/'
both "camera_id.yaml: camera_id: 123456789012 is outside the 32-bit integer range" \
  --config camera_id.yaml
bad camera_wrap 's/camera_id: -1/camera_id: 4294967297/'
both "camera_wrap.yaml: camera_id: 4294967297 is outside the 32-bit integer range" \
  --config camera_wrap.yaml
# a filter.* range error (sfd-node: exit 1 without the key before)
bad window_size 's/window_size: 5/window_size: 6/'
both "window_size.yaml: filter.window_size: 6 is not in 2..5" --config window_size.yaml

# --- one bad value per kind of rule ------------------------------------------------------------
bad window_real 's/window_size: 5/window_size: 2.5/'
both "window_real.yaml: filter.window_size: 2.5 is not an integer" --config window_real.yaml
bad gate 's/window_gate_alpha: 0.01/window_gate_alpha: 0.6/'
both "gate.yaml: filter.window_gate_alpha: 0.6 is not in (0, 0.5]" --config gate.yaml
bad rest 's/init_rest_s: 1.0/init_rest_s: 0/'
both "rest.yaml: filter.init_rest_s: 0 is not in (0, 60)" --config rest.yaml
bad lm_gate 's/landmark_gate_alpha: 0.001/landmark_gate_alpha: 1/'
both "lm_gate.yaml: filter.landmark_gate_alpha: 1 is not in (0, 1)" --config lm_gate.yaml
bad lm_age 's/landmark_max_age_s: 2.0/landmark_max_age_s: "2"/'
both 'lm_age.yaml: filter.landmark_max_age_s: "2" is not a number' --config lm_age.yaml
bad flag 's/gyro_bias_at_rest: 1/gyro_bias_at_rest: true/'
both 'flag.yaml: filter.gyro_bias_at_rest: "true" is not an integer' --config flag.yaml
bad alpha 's/false_alarm_rate: 0.01/false_alarm_rate: 0.6/'
both "alpha.yaml: false_alarm_rate: 0.6 is not in (0, 0.5]" --config alpha.yaml
bad sigma 's/pixel_sigma_px: 1.0/pixel_sigma_px: 0/'
both "sigma.yaml: pixel_sigma_px: 0 is not > 0" --config sigma.yaml
bad octal 's/window_frames: 3/window_frames: 03/'
both "octal.yaml: window_frames: 03 has a leading 0 (cv::FileStorage would read it as octal)" \
  --config octal.yaml
bad horizon 's/time_horizon_us: 500000/time_horizon_us: 0/'
both "horizon.yaml: time_horizon_us: 0 is not > 0" --config horizon.yaml
bad horizon_real 's/time_horizon_us: 500000/time_horizon_us: 2.5/'
both "horizon_real.yaml: time_horizon_us: 2.5 is not a whole number of microseconds" \
  --config horizon_real.yaml
bad resync 's/time_resync_messages: 5/time_resync_messages: 1001/'
both "resync.yaml: time_resync_messages: 1001 is not in 2..1000" --config resync.yaml
bad gap 's/max_imu_gap_us: 50000/max_imu_gap_us: 5000000000/'
both "gap.yaml: max_imu_gap_us: 5000000000 is outside the 32-bit integer range" --config gap.yaml
bad bias 's/gyro_bias_rad_s: .*/gyro_bias_rad_s: [ 0.0, .inf, 0.0 ]/'
both "bias.yaml: gyro_bias_rad_s[1]: inf is not finite" --config bias.yaml
bad hyp 's/max_hypotheses: 100/max_hypotheses: 0/'
both "hyp.yaml: max_hypotheses: 0 is not in 1..256" --config hyp.yaml
bad seed 's/seed: 1/seed: -1/'
both "seed.yaml: seed: -1 is not an unsigned integer (0..2^53)" --config seed.yaml
bad timing 's/publish_timing: 1/publish_timing: 2/'
both "timing.yaml: publish_timing: 2 is not 0 or 1" --config timing.yaml
bad chan_empty 's/imu: "IMU"/imu: ""/'
both 'chan_empty.yaml: channels.imu: "" is empty' --config chan_empty.yaml
bad method 's/method: "parity"/method: "oprf"/; s/enabled: 1/enabled: 0/'
both 'method.yaml: method: "oprf" needs filter.enabled: 1 (it is 0, from method.yaml)' \
  --config method.yaml
bad method_name 's/method: "parity"/method: "ransac"/'
both 'method_name.yaml: method: "ransac" is not one of none, parity, oprf, ransac1, ransacf, both' \
  --config method_name.yaml
bad unknown '$a no_such_key: 3'
both "unknown.yaml: unknown key no_such_key" --config unknown.yaml
bad syntax 's/gyro_bias_rad_s: .*/gyro_bias_rad_s: [ 0.0, 0.0/'
cases=$((cases + 1))
run replay --config syntax.yaml; rc_replay=$rc
run node --lcm-url memq:// --config syntax.yaml
if [ "$rc_replay" -ne 2 ] || [ "$rc" -ne 2 ] ||
   ! grep -Eq '^sfd-replay: syntax.yaml:[0-9]+: not valid YAML \(.+\)$' replay.err ||
   [ "$(sed 's/^sfd-replay: //' replay.err)" != "$(sed 's/^sfd-node: //' node.err)" ]; then
  fail "a YAML syntax error: exit $rc_replay/$rc: $(cat replay.err node.err)"
else
  echo "exit 2 from both: $(sed 's/^sfd-replay: //' replay.err)"
fi
both "missing.yaml: cannot open (No such file or directory)" --config missing.yaml
# lcm_url from the file: sfd-node without --lcm-url (the flag would override the file)
bad url 's|^lcm_url: .*|lcm_url: ""|'
cases=$((cases + 1))
check replay 'url.yaml: lcm_url: "" is empty' --config url.yaml &&
  check node 'url.yaml: lcm_url: "" is empty' --config url.yaml && echo "exit 2 from both: url"

# --- bad flags -----------------------------------------------------------------------------------
both "--method: ransac is not one of none, parity, oprf, ransac1, ransacf, both" --method ransac
bad method_off 's/enabled: 1/enabled: 0/'
both '--method: method: "ransacf" needs filter.enabled: 1 (it is 0, from method_off.yaml)' \
  --config method_off.yaml --method ransacf
both "gravity.yaml: filter.gravity_m_s2: -9.81 is not > 0" --config=gravity.yaml
# a flag per key, the same on both tools: its value parsed whole (types as for the file), its
# range judged with the file's (docs/deploy.md, "Command line")
both "--window-frames: 2.5 is not an integer" --window-frames 2.5
both "--window-frames: window_frames: 7 is not in 2..5" --window-frames=7
both "--window-frames: 99999999999 is outside the 32-bit integer range" --window-frames 99999999999
both "--group-size: x is not an integer" --group-size x
both "--false-alarm-rate: false_alarm_rate: nan is not finite" --false-alarm-rate nan
both "--false-alarm-rate: 0.1x is not a number" --false-alarm-rate 0.1x
both "--pixel-sigma-px: pixel_sigma_px: -1 is not > 0" --pixel-sigma-px -1
both "--default-depth-m: default_depth_m: 0 is not in [1.17549e-38, 3.40282e+38]" --default-depth-m=0
both "--filter.window-size: filter.window_size: 6 is not in 2..5" --filter.window-size 6
both "--max-imu-gap-us: 2.5 is not a whole number of microseconds (|value| <= 9e15)" \
  --max-imu-gap-us 2.5
both "--gyro-bias-rad-s: 0,1 is not three finite numbers X,Y,Z" --gyro-bias-rad-s 0,1
check replay "unknown option --no-such-key (sfd-replay --help lists the options)" \
  --no-such-key 1 && echo "exit 2: an unknown flag"
check node "unknown option --no-such-key (sfd-node --help lists the options)" \
  --lcm-url memq:// --no-such-key 1 && echo "exit 2: an unknown flag"
check replay "unknown option --filter.window (sfd-replay --help lists the options)" \
  --filter.window 3 && echo "exit 2: an abbreviation is an unknown option"
check node "unknown option --filter.window (sfd-node --help lists the options)" \
  --lcm-url memq:// --filter.window 3 && echo "exit 2: an abbreviation is an unknown option"
# channels and the LCM URL
both '--channels.imu: channels.imu: "FEATURES" is the same as channels.features' \
  --channels.imu FEATURES
both '--channels.state: channels.state: "SFD TIMING" contains '"' '"' (a channel name is matched exactly: no blanks, control or regular-expression characters)' \
  --channels.state "SFD TIMING"
# the spellings of sfd 0.1 still work (deprecated, with a notice): same result as the new ones
rm -f old.lcmlog new.lcmlog
timeout -k 5 60 "$replay" "$golden" -o old.lcmlog --alpha 0.05 --window 2 --no-isolation \
  > /dev/null 2> old.err || fail "the deprecated spellings: $(cat old.err)"
timeout -k 5 60 "$replay" "$golden" -o new.lcmlog --false-alarm-rate 0.05 --window-frames 2 \
  --parity-isolation 0 > /dev/null 2> new.err || fail "the new spellings: $(cat new.err)"
cmp -s old.lcmlog new.lcmlog || fail "deprecated spellings give another OUT than the new ones"
grep -q "^sfd-replay: --alpha is deprecated: use --false-alarm-rate$" old.err ||
  fail "no deprecation notice: $(cat old.err)"
[ ! -s new.err ] || fail "the new spellings print on stderr: $(cat new.err)"
check node '--lcm-url: lcm_url: "" is empty' --lcm-url "" && echo "exit 2: --lcm-url ''"

# --- a flag that repairs the file: judged after the overrides -----------------------------------
timeout -k 5 60 "$replay" "$golden" --config method.yaml --method parity > /dev/null 2> replay.err ||
  fail "sfd-replay --config method.yaml --method parity: $(cat replay.err)"
rc=0
timeout -k 5 --preserve-status -s INT 1 "$node" --config method.yaml --method parity \
  --lcm-url memq:// > node.out 2>&1 || rc=$?
[ "$rc" -eq 0 ] || fail "sfd-node --config method.yaml --method parity: exit $rc: $(cat node.out)"

if [ "$fails" -ne 0 ]; then echo "$fails failure(s)"; exit 1; fi
echo "config_validation: shipped sfd.yaml valid; $cases bad configurations refused alike by sfd-node and sfd-replay"
