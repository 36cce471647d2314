#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# README command (1): set up, build, and run the main job on its built-in default, a simulated
# flight: the paper's UAV scenario through the parity-space detector (sfd-sim paper-uav), the
# isolation comparison on a simulated flight with mistracks (sfd-sim isolation), and their plots.
# Results: the tables printed here, CSV and PNG files in out/ (or $SFD_OUT).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash tools/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc 2>/dev/null || echo 2)" --target sfd-sim
out="${SFD_OUT:-$root/out}"
mkdir -p "$out"
./build/host/apps/sfd-sim paper-uav --csv-dir "$out" "$@"
echo
./build/host/apps/sfd-sim isolation --csv-dir "$out"
echo
.venv/bin/python tools/plot_paper.py "$out"
