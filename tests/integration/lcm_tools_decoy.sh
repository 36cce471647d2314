#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# integration.lcm_tools_decoy (issue 19 item 4): the build and the tests take lcm-gen, lcm-logger
# and lcm-logplayer from Debian by absolute path, whatever is first on PATH (a PyPI `lcm` puts
# its own there). Decoy lcm-gen / lcm-logger / lcm-logplayer that write a marker file and exit 1
# go first on PATH; then
#  - a fresh configure of the tree (apps and tests off) builds the LCM types (C, C++, Python, and
#    the Java jar when a JDK is present), and the generated C, C++ and Python equal the main
#    build's;
#  - integration.node_logplayer's script (Debian's lcm-logplayer into sfd-node, lcm-logger
#    recording) passes;
#  - no decoy ran (no marker);
#  - a configure pointed at an lcm-gen that reports 1.5.1 (PyPI's version) fails naming it.
# usage: lcm_tools_decoy.sh SOURCE_DIR BUILD_DIR PYTHON PYTHONPATH_FOR_TYPES [HEAPCOUNT_PRELOAD_SO]
set -euo pipefail
src="$1"; build="$2"; py="$3"; pytypes="$4"; preload="${5:-}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "lcm_tools_decoy: $*" >&2; exit 1; }

mkdir "$tmp/decoy"
marker="$tmp/decoy_ran.txt"
for tool in lcm-gen lcm-logger lcm-logplayer; do
  printf '#!/bin/sh\necho "decoy %s ran: $*" >> "%s"\nexit 1\n' "$tool" "$marker" > "$tmp/decoy/$tool"
  chmod +x "$tmp/decoy/$tool"
done
export PATH="$tmp/decoy:$PATH"
[ "$(command -v lcm-gen)" = "$tmp/decoy/lcm-gen" ] || fail "decoy lcm-gen is not first on PATH"
[ "$(command -v lcm-logger)" = "$tmp/decoy/lcm-logger" ] || fail "decoy lcm-logger not first"
[ "$(command -v lcm-logplayer)" = "$tmp/decoy/lcm-logplayer" ] || fail "decoy lcm-logplayer not first"

# A fresh configure (no cache: every tool path is the default) builds the types.
scratch="$tmp/build"
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$src" -B "$scratch" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSFD_BUILD_TESTS=OFF \
  -DSFD_BUILD_APPS=OFF "${launcher[@]}" > "$tmp/configure.txt" 2>&1 || {
  cat "$tmp/configure.txt"; fail "configure with decoys on PATH failed"; }
grep -q '^SFD_LCM_GEN:FILEPATH=/usr/bin/lcm-gen$' "$scratch/CMakeCache.txt" ||
  fail "SFD_LCM_GEN is not /usr/bin/lcm-gen: $(grep SFD_LCM_GEN "$scratch/CMakeCache.txt")"
targets=(sfd_lcm_types sfd_lcmtypes sfd_lcm_types_cpp sfd_lcm_types_python)
if grep -q '^build sfd_lcmtypes_java:' "$scratch/build.ninja"; then
  targets+=(sfd_lcmtypes_java)
fi
cmake --build "$scratch" --target "${targets[@]}" > "$tmp/build.txt" 2>&1 || {
  cat "$tmp/build.txt"; fail "building ${targets[*]} with decoys on PATH failed"; }
# Same generator, same code: the generated C, C++ and Python equal the main build's.
for d in c cpp python/sfd; do
  diff -r -x __pycache__ "$build/lcm_types/$d" "$scratch/lcm_types/$d" > "$tmp/diff.txt" || {
    cat "$tmp/diff.txt"; fail "lcm_types/$d generated in the scratch build differs from $build's"; }
done
echo "lcm_tools_decoy: built ${targets[*]} with decoys first on PATH; generated C, C++ and Python equal"

# The logplayer/logger test, decoys still first on PATH and no tool path given.
env -u SFD_LCM_LOGGER -u SFD_LCM_LOGPLAYER \
  "$src/tests/integration/node_logplayer.sh" "$build" "$py" "$pytypes" "$preload" \
  > "$tmp/node_logplayer.txt" 2>&1 || {
  cat "$tmp/node_logplayer.txt"; fail "node_logplayer.sh failed with decoys first on PATH"; }
grep -q "node verdicts identical to sfd-replay for all 60 frames" "$tmp/node_logplayer.txt" ||
  { cat "$tmp/node_logplayer.txt"; fail "node_logplayer.sh did not compare the verdicts"; }
echo "lcm_tools_decoy: node_logplayer.sh passed with decoys first on PATH"

if [ -e "$marker" ]; then
  cat "$marker"; fail "a decoy ran"
fi

# An lcm-gen of another version (PyPI's 1.5.1), named explicitly: configure stops naming it.
printf '#!/bin/sh\necho "lcm-gen 1.5.1"\n' > "$tmp/lcm-gen-1.5"
chmod +x "$tmp/lcm-gen-1.5"
if cmake -S "$src" -B "$tmp/build15" -G Ninja -DSFD_BUILD_TESTS=OFF -DSFD_BUILD_APPS=OFF \
  -DSFD_LCM_GEN="$tmp/lcm-gen-1.5" > "$tmp/configure15.txt" 2>&1; then
  fail "configure accepted SFD_LCM_GEN=$tmp/lcm-gen-1.5 (version 1.5.1)"
fi
# (CMake wraps its messages: whitespace is collapsed before the match)
tr -s ' \n' '  ' < "$tmp/configure15.txt" |
  grep -q "SFD_LCM_GEN=$tmp/lcm-gen-1.5: '--version' says \"lcm-gen 1.5.1\" (exit 0), not lcm-gen 1.3.x" || {
  cat "$tmp/configure15.txt"; fail "configure refused lcm-gen 1.5.1 without naming it"; }
echo "lcm_tools_decoy: no decoy ran; an lcm-gen reporting 1.5.1 is refused at configure"
