#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Golden replay regression (integration.replay_golden). The committed log golden.lcmlog (made by
# sfd-sim, see regenerate below) is replayed with the default configuration; its verdicts must
# equal golden_verdicts.csv line for line. Any change of detector behaviour turns this red.
# To accept a deliberate change:  tests/replay/golden.sh BUILD_DIR PYTHON TYPES_DIR --regenerate
# then review `git diff tests/replay/` and commit it with the reason.
# SFD_RUNNER (environment), when set, prefixes the sfd-replay command: a cross build's binary runs
# under its emulator (integration.replay_golden_emulated: `qemu-aarch64 -L SYSROOT`) and must give
# the host's verdicts. SFD_REPLAY_ARGS adds arguments (e.g. `--config apps/config/sfd.yaml`, which
# states the defaults, so the verdicts must not change).
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"; mode="${4:-}"
read -r -a runner <<< "${SFD_RUNNER:-}"
read -r -a extra <<< "${SFD_REPLAY_ARGS:-}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
if [ "$mode" = "--regenerate" ]; then
  "$build/apps/sfd-sim" mistracking -o "$here/golden.lcmlog" --frames 12 --features 40 --seed 11 \
    --outlier-ratio 0.15 --jump-px 12
fi
"${runner[@]}" "$build/apps/sfd-replay" "$here/golden.lcmlog" -o "$tmp/out.lcmlog" "${extra[@]}" \
  >/dev/null
PYTHONPATH="$pytypes" "$py" "$here/verdicts_csv.py" "$tmp/out.lcmlog" > "$tmp/verdicts.csv"
if [ "$mode" = "--regenerate" ]; then
  cp "$tmp/verdicts.csv" "$here/golden_verdicts.csv"
  echo "regenerated golden.lcmlog and golden_verdicts.csv ($(wc -l < "$here/golden_verdicts.csv") lines)"
  exit 0
fi
if ! diff -u "$here/golden_verdicts.csv" "$tmp/verdicts.csv" > "$tmp/diff.txt"; then
  head -40 "$tmp/diff.txt"
  echo "golden replay: verdicts changed (regenerate on purpose with --regenerate, see the header)"
  exit 1
fi
echo "golden replay: $(($(wc -l < "$tmp/verdicts.csv") - 1)) verdicts identical to golden_verdicts.csv"
