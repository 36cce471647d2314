#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Runs one target unit-test image on QEMU's mps2-an500 (Cortex-M7) and maps the result to CTest
# (docs/embedded.md). The image prints on the semihosting console and ends QEMU by semihosting
# SYS_EXIT_EXTENDED with main's status (the number of failed tests; 134 after a fault).
# Usage: run_m7.sh QEMU TIMEOUT_S IMAGE.elf [EXPECTED_STATUS EXPECTED_LINE]
#   without EXPECTED_*: passes iff QEMU exits 0 within TIMEOUT_S;
#   with them (the positive control): passes iff QEMU exits with EXPECTED_STATUS and the output
#   has the line EXPECTED_LINE.
set -uo pipefail

if [ $# -ne 3 ] && [ $# -ne 5 ]; then
  echo "usage: run_m7.sh QEMU TIMEOUT_S IMAGE.elf [EXPECTED_STATUS EXPECTED_LINE]" >&2
  exit 2
fi
qemu=$1 timeout_s=$2 image=$3
[ -x "$qemu" ] || { echo "run_m7.sh: $qemu: not an executable (tools/setup.sh installs qemu-system-arm)" >&2; exit 2; }
[ -f "$image" ] || { echo "run_m7.sh: $image: no such image" >&2; exit 2; }

out=$(mktemp)
trap 'rm -f "$out"' EXIT
# -nodefaults, -serial null, -monitor none, -nic none: no UART, monitor, display or network; the
# semihosting console (target=native) is QEMU's stderr, merged here into the captured output.
timeout --kill-after=5 "$timeout_s" "$qemu" -machine mps2-an500 -cpu cortex-m7 -nodefaults \
  -display none -serial null -monitor none -nic none -semihosting-config enable=on,target=native \
  -kernel "$image" >"$out" 2>&1
status=$?
# The board's LAN9118 Ethernet always exists; QEMU warns that no network is attached to it.
grep -vxF "qemu-system-arm: warning: nic lan9118.0 has no peer" "$out"

if [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
  echo "run_m7.sh: $(basename "$image"): no exit within ${timeout_s} s (hang, lockup or too slow)"
  exit 1
fi
if [ $# -eq 5 ]; then
  expected_status=$4 expected_line=$5
  if [ "$status" -ne "$expected_status" ]; then
    echo "run_m7.sh: $(basename "$image"): exit status $status, expected $expected_status"
    exit 1
  fi
  if ! grep -qxF -- "$expected_line" "$out"; then
    echo "run_m7.sh: $(basename "$image"): no line '$expected_line' in the output"
    exit 1
  fi
  echo "run_m7.sh: $(basename "$image"): exit status $status and '$expected_line', as expected"
  exit 0
fi
if [ "$status" -ne 0 ]; then
  echo "run_m7.sh: $(basename "$image"): exit status $status"
  exit 1
fi
exit 0
