#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# README command (2): set up, build and run the whole test suite:
#   host       Release: unit tests, proofs (symbols, interposer, stack, sizes), lint
#   host-asan  Debug with AddressSanitizer + UndefinedBehaviorSanitizer
#   host-native  Release for this CPU (-march=native; AVX-512 on the CI machine): the unit tests
#              only, where a miscompile shows (GCC 12.2 vectorized window_basis with a misaligned
#              load, core/src/parity_space.cpp); stack and size budgets are the other presets' proofs
#   cortex-m7  core cross-built for arm-none-eabi (hard float): symbol, stack and size proofs; the
#              firmware example's image and its text/data/bss, state and stack budgets; the core
#              unit tests on QEMU's mps2-an500 Cortex-M7 (m7.unit.*, docs/embedded.md)
#   aarch64    core, LCM driver, sfd-node/replay/sim cross-built against the arm64 sysroot
#              (tools/setup.sh); unit tests, proofs and the golden replay under qemu-aarch64
#   fuzz       clang-14 libFuzzer targets (ASan + UBSan), 20 s each from sfd-sim seeds (fuzz.*)
# Usage: tools/test.sh [--host-only]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash tools/setup.sh

presets=(host host-asan host-native cortex-m7 aarch64 fuzz)
if [ "${1:-}" = "--host-only" ]; then presets=(host); fi

jobs="$(nproc 2>/dev/null || echo 2)"
total_pass=0
total_fail=0
for p in "${presets[@]}"; do
  echo "=== preset $p: configure + build ==="
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p" -j "$jobs"
  echo "=== preset $p: ctest ==="
  log="$(mktemp)"
  set +e
  ctest --preset "$p" -j "$jobs" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  line="$(grep -E '[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -1 || true)"
  rm -f "$log"
  if [ -z "$line" ]; then echo "preset $p: ctest printed no summary (rc=$rc)"; total_fail=$((total_fail + 1)); continue; fi
  failed="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"$line")"
  outof="$(sed -E 's/.* failed out of ([0-9]+).*/\1/' <<<"$line")"
  total_pass=$((total_pass + outof - failed))
  total_fail=$((total_fail + failed))
  if [ "$rc" -ne 0 ] && [ "$failed" -eq 0 ]; then total_fail=$((total_fail + 1)); fi
done
echo "presets: ${presets[*]}"
echo "sfd: ${total_pass} passed, ${total_fail} failed"
[ "$total_fail" -eq 0 ]
