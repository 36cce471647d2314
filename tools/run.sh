#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# README command (1): set up, build, and run the main job on its built-in default, a simulated
# flight (sfd-sim paper-uav). Extra arguments go to sfd-sim (e.g. --seed 7 --frames 400).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash tools/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc 2>/dev/null || echo 2)" --target sfd-sim
exec ./build/host/apps/sfd-sim paper-uav "$@"
