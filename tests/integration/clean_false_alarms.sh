#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.clean_false_alarms (issue 17, items 2 and 4): on logs without a spurious feature,
# with the shipped configuration and its at-rest start, a clean feature is flagged with
# probability alpha (0.01):
#  - an sfd-sim mistracking flight with --outlier-ratio 0 (400 frames, 1 px of noise);
#  - V1_02 semi-real with --spurious-fraction 0 (real IMU and trajectory, 0.5 px of noise while the
#    configuration says 1 px: the pixel noise scale must find it), when ../shared/data is there.
# The interval: the 99 % binomial interval of alpha over a third of the tests (consecutive
# windows of one track share frames, so the tests are not independent). parity and both are
# designed for at most alpha (parity's window and evidence tests each at alpha / 2, the window
# test with the shipped alarm hold at alarm_hold_alpha_scale of that, its held repeats paid out
# of the rest, the evidence test's split with its ramp test by evidence_ramp_share; both's parity stage at both_parity_share * alpha, its OPRF stage at the rest):
# their rate must be
# below the interval's top. So must the association methods'
# since their pixel noise is carried through the distortion Jacobian (issue 17 item 4; before,
# at the stretched image border their rates reached 1.31 % (oprf), 1.61 % (ransac1) and 3.77 %
# (ransacf) on the flight): oprf on both logs (measured 0.61 % flight, 0.42 % semi-real: set 2
# rescues some of set 1's alarms, so below alpha), ransac1 and ransacf on the flight (0.33 %,
# 1.04 %).
# usage: clean_false_alarms.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"; src="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cfg="$src/apps/config/sfd.yaml"
check() { # LOG NAME METHOD MODE(max|inside)
  "$build/apps/sfd-replay" "$1" --config "$cfg" --method "$3" --summary "$tmp/$2_$3.json" \
    >/dev/null
  python3 - "$tmp/$2_$3.json" "$2" "$3" "$4" <<'PYEOF'
import json, math, sys
path, name, method, mode = sys.argv[1:]
d = json.load(open(path))["detection"]
alpha = 0.01
assert d["spurious"] == 0, d
tested = d["fp"] + d["tn"]
rate = d["fp"] / tested
half = 2.576 * math.sqrt(alpha * (1 - alpha) / (tested / 3))
print(f"{name:10s} {method:7s} clean tested {tested:6d} flagged {d['fp']:5d} rate {rate:.4f} "
      f"(alpha {alpha}, 99% interval {alpha - half:.4f}..{alpha + half:.4f})")
assert tested > 20000, d
if mode == "max":
    assert rate <= alpha + half, (name, method, rate)
else:
    assert abs(rate - alpha) <= half, (name, method, rate)
PYEOF
}
"$build/apps/sfd-sim" mistracking -o "$tmp/flight.lcmlog" --frames 400 --seed 3 \
  --outlier-ratio 0 >/dev/null
check "$tmp/flight.lcmlog" flight parity max
check "$tmp/flight.lcmlog" flight both max
check "$tmp/flight.lcmlog" flight oprf max
check "$tmp/flight.lcmlog" flight ransac1 max
check "$tmp/flight.lcmlog" flight ransacf max
data="$(cd "$src/.." && pwd)/shared/data/euroc_v1_02_imu_gt"
if [ ! -f "$data/mav0/imu0/data.csv" ]; then
  echo "semi-real part SKIPPED: $data is absent"
  exit 0
fi
"$build/apps/sfd-sim" euroc-semireal --euroc "$data" -o "$tmp/v102.lcmlog" --seed 3 \
  --spurious-fraction 0 >/dev/null
check "$tmp/v102.lcmlog" v1_02 parity max
check "$tmp/v102.lcmlog" v1_02 both max
check "$tmp/v102.lcmlog" v1_02 oprf max
echo "clean_false_alarms: ok"
