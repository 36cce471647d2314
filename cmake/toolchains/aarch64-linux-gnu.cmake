# SPDX-License-Identifier: MIT
# aarch64 Linux (Debian cross toolchain, g++-aarch64-linux-gnu). The arm64 libraries come from the
# private sysroot tools/setup.sh unpacks from Debian's arm64 .debs (build/sysroot-arm64: LCM,
# GLib, OpenCV core, cmocka, glibc and what they load; Debian's liblcm cannot be co-installed for
# amd64 and arm64), then from the multiarch arm64 packages (libc6:arm64, libcmocka0:arm64) and
# the cross toolchain's libc (/usr/aarch64-linux-gnu). Tests run through qemu-aarch64 with the
# sysroot as its -L prefix (paths absent there fall back to the host's).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_NM aarch64-linux-gnu-nm CACHE FILEPATH "")
get_filename_component(_sfd_sysroot "${CMAKE_CURRENT_LIST_DIR}/../../build/sysroot-arm64" ABSOLUTE)
set(SFD_ARM64_SYSROOT "${_sfd_sysroot}" CACHE PATH "arm64 sysroot unpacked by tools/setup.sh")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;${SFD_ARM64_SYSROOT})
# Libraries in the sysroot that the linked ones load (GLib under liblcm, TBB/LAPACK/GLX under
# OpenCV core) are found through -rpath-link. Build-tree binaries carry the sysroot's library
# directory as RUNPATH (CMake's build RPATH); `cmake --install` removes it.
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "-Wl,-rpath-link,${SFD_ARM64_SYSROOT}/lib/aarch64-linux-gnu -Wl,-rpath-link,${SFD_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "${CMAKE_EXE_LINKER_FLAGS_INIT}")
# Search order: the private sysroot, the cross libc, multiarch /usr (headers in /usr/include).
set(CMAKE_FIND_ROOT_PATH ${SFD_ARM64_SYSROOT} /usr/aarch64-linux-gnu /usr)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
