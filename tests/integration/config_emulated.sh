#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.config_emulated (aarch64 preset): the cross-built sfd-replay reads its YAML
# configuration (cv::FileStorage, OpenCV core from the arm64 sysroot) under the emulator:
#   1. apps/config/sfd.yaml, which states every default, gives the golden verdicts
#      (tests/replay/golden.sh with --config);
#   2. the same file plus one unknown key is refused: exit status 2 and a message naming the key.
# Usage: config_emulated.sh BUILD_DIR PYTHON TYPES_DIR EMULATOR [EMULATOR ARGS...]
set -euo pipefail
build="$1"; py="$2"; pytypes="$3"; shift 3
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

SFD_RUNNER="$*" SFD_REPLAY_ARGS="--config $src/apps/config/sfd.yaml" \
  "$src/tests/replay/golden.sh" "$build" "$py" "$pytypes"

{ cat "$src/apps/config/sfd.yaml"; echo "no_such_key: 3"; } > "$tmp/bad.yaml"
set +e
"$@" "$build/apps/sfd-replay" "$src/tests/replay/golden.lcmlog" --config "$tmp/bad.yaml" \
  -o "$tmp/out.lcmlog" > "$tmp/stdout" 2> "$tmp/stderr"
rc=$?
set -e
if [ "$rc" -ne 2 ] || ! grep -q "unknown key no_such_key" "$tmp/stderr"; then
  echo "config with an unknown key: expected exit 2 naming the key, got $rc:"
  cat "$tmp/stderr"
  exit 1
fi
echo "unknown key refused: $(cat "$tmp/stderr")"
