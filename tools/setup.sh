#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Idempotent setup: installs from Debian and PyPI only what is missing.
# Usage: tools/setup.sh [--no-python]
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

# Debian packages (SPEC "Dependencies") plus the analysis tools CI runs (clang-14 with its
# sanitizer and libFuzzer runtimes, libclang-rt-14-dev, for the `fuzz` preset).
APT_PKGS=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libopencv-dev
  libcmocka-dev
  gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib binutils-arm-none-eabi
  g++-aarch64-linux-gnu qemu-user
  clang-format cppcheck clang-tidy
  clang-14 libclang-rt-14-dev
  valgrind
  python3 python3-pip python3-venv
)
# arm64 multiarch packages (for the aarch64 preset's unit tests).
APT_ARM64_PKGS=(libcmocka-dev:arm64 libcmocka0:arm64 libc6:arm64 libstdc++6:arm64)

missing=()
for p in "${APT_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

need_arm64=0
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "[setup] enabling Debian multiarch arm64"
  $SUDO dpkg --add-architecture arm64
  need_arm64=1
fi
for p in "${APT_ARM64_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || { missing+=("$p"); need_arm64=1; }
done

if [ "${#missing[@]}" -gt 0 ]; then
  echo "[setup] installing from Debian: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "[setup] Debian packages: all present"
fi

# Python tools: a venv inside the build tree area keeps the system Python clean.
if [ "${1:-}" != "--no-python" ]; then
  venv="$root/.venv"
  if [ ! -x "$venv/bin/python" ]; then
    echo "[setup] creating $venv"
    python3 -m venv "$venv"
  fi
  if ! "$venv/bin/python" -c 'import sys; sys.exit(0)' >/dev/null 2>&1; then
    echo "[setup] broken venv at $venv" >&2; exit 1
  fi
  req="$root/tools/requirements.txt"
  stamp="$venv/.req.sha256"
  want="$(sha256sum "$req" | cut -d' ' -f1)"
  if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
    echo "[setup] installing Python requirements"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$req"
    echo "$want" > "$stamp"
  else
    echo "[setup] Python requirements: all present"
  fi
fi
