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
# liblcm-java, libjchart2d-java and a JDK: the Java types jar and sfd-spy (lcm-spy needs jchart2d,
# which Debian's liblcm-java does not pull in). qemu-system-arm: the cortex-m7 preset runs the
# core unit tests on its mps2-an500 board (Cortex-M7; docs/embedded.md).
APT_PKGS=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  liblcm-java libjchart2d-java default-jdk-headless
  libopencv-dev
  libcmocka-dev
  nlohmann-json3-dev
  gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib binutils-arm-none-eabi qemu-system-arm
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

# Private arm64 sysroot for the aarch64 preset's apps (sfd-node, sfd-replay, sfd-sim; docs/deploy.md).
# Debian's liblcm1/liblcm-dev have no Multi-Arch field, so they cannot be installed for arm64
# beside the amd64 ones the host build uses; instead their arm64 .debs and those of every
# library they and OpenCV's core module (cv::FileStorage reads the YAML configuration, in
# apps/common) load are downloaded with `apt-get download` and unpacked with `dpkg-deb -x`
# into build/sysroot-arm64 (not committed). The set is the DT_NEEDED closure of liblcm.so.1,
# libopencv_core.so.406 and libcmocka.so.0 (package dependencies that no library loads, such as
# libglx-mesa0, are left out); the libc/libstdc++ packages make the sysroot complete for
# `qemu-aarch64 -L build/sysroot-arm64`. A stamp holds the list: unchanged list, nothing to do.
ARM64_SYSROOT_PKGS=(
  liblcm1 liblcm-dev libglib2.0-0 libpcre2-8-0
  libopencv-core406 libopencv-core-dev zlib1g libtbb12 libblas3 liblapack3 libgfortran5
  libglx0 libglvnd0 libx11-6 libxcb1 libxau6 libxdmcp6 libbsd0 libmd0
  libcmocka0 libcmocka-dev
  libc6 libgcc-s1 libstdc++6
)
sysroot="$root/build/sysroot-arm64"
want_sysroot="${ARM64_SYSROOT_PKGS[*]}"
if [ -f "$sysroot/.sfd-sysroot" ] && [ "$(cat "$sysroot/.sfd-sysroot")" = "$want_sysroot" ]; then
  echo "[setup] arm64 sysroot: present ($sysroot)"
else
  echo "[setup] building the arm64 sysroot in $sysroot"
  rm -rf "$sysroot"
  mkdir -p "$sysroot/.debs"
  debs=()
  for p in "${ARM64_SYSROOT_PKGS[@]}"; do debs+=("$p:arm64"); done
  # apt-get download writes into the current directory; as root it warns that the download is
  # unsandboxed (the _apt user cannot write there), which is harmless.
  if ! (cd "$sysroot/.debs" && apt-get download -q "${debs[@]}" 2>/dev/null); then
    echo "[setup] arm64 package lists missing or stale: apt-get update"
    $SUDO apt-get update -q
    (cd "$sysroot/.debs" && apt-get download -q "${debs[@]}")
  fi
  for d in "$sysroot"/.debs/*.deb; do dpkg-deb -x "$d" "$sysroot"; done
  # libblas.so.3 and liblapack.so.3 are update-alternatives links, which dpkg-deb -x does not make.
  ln -sfn blas/libblas.so.3 "$sysroot/usr/lib/aarch64-linux-gnu/libblas.so.3"
  ln -sfn lapack/liblapack.so.3 "$sysroot/usr/lib/aarch64-linux-gnu/liblapack.so.3"
  rm -rf "$sysroot/.debs" "$sysroot/usr/share/doc" "$sysroot/usr/share/locale" \
    "$sysroot/usr/share/man" "$sysroot/usr/lib/aarch64-linux-gnu/gconv"
  echo "$want_sysroot" > "$sysroot/.sfd-sysroot"
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
