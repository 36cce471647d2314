# SPDX-License-Identifier: MIT
# Per-target flag sets. Nothing here touches global CMAKE_<LANG>_FLAGS.

# Warning set (PX4-Matrix's list) for everything the project owns.
function(sfd_target_warnings target)
  set(common -Wall -Wextra -Wshadow -Wundef -Wfloat-equal -Wconversion -Wsign-conversion)
  target_compile_options(${target} PRIVATE ${common}
    $<$<COMPILE_LANGUAGE:CXX>:-Wold-style-cast -Wnon-virtual-dtor>)
  if(SFD_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# Tests, tools and host apps: the same base set without the conversion/float-equality warnings (tests
# compare exact bit patterns on purpose and mix integer counts with doubles freely).
function(sfd_host_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -Wundef)
  if(SFD_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# Flight-core rules: no exceptions, no RTTI, no thread-safe-static guards (they call
# __cxa_guard_acquire), no FMA contraction and no fast-math (bit-identical results with the same
# binary, and across targets wherever the libm calls agree), -O3 whatever the build type: at
# -O0/-O1/-Os Eigen keeps never-taken heap fallbacks that the symbol check would (rightly) flag,
# and -O3 over -O2 unrolls and vectorizes the small fixed-size kernels (the node's frame: 3.08M ->
# 2.0M instructions, callgrind) without changing a result: with no FMA contraction and no
# reassociation, every operation and its order stay the source's (replay logs byte-identical).
# -fstack-usage and -fcallgraph-info=su (GCC's; clang has no call-graph dump) feed
# tools/stack_report.py (worst-case stack, no recursion); every GCC build gets them, the clang
# fuzz build (SFD_BUILD_FUZZERS) goes without, and its presets run no stack proof.
function(sfd_target_flight_rules target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti -fno-threadsafe-statics>
    -ffp-contract=off -fno-fast-math -fno-associative-math
    -O3
    $<$<COMPILE_LANG_AND_ID:C,GNU>:-fstack-usage> $<$<COMPILE_LANG_AND_ID:CXX,GNU>:-fstack-usage>
    $<$<COMPILE_LANG_AND_ID:C,GNU>:-fcallgraph-info=su>
    $<$<COMPILE_LANG_AND_ID:CXX,GNU>:-fcallgraph-info=su>
    -Werror)
  target_compile_definitions(${target} PRIVATE EIGEN_NO_IO EIGEN_NO_AUTOMATIC_RESIZING
                             EIGEN_MPL2_ONLY)
  # ccache (Debian's 4.7) restores the .su files of a cache hit but not the .ci call graphs, which
  # would leave the stack checks with a partial graph: these targets compile without it.
  if(CMAKE_C_COMPILER_ID STREQUAL "GNU" OR CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    set_target_properties(${target} PROPERTIES C_COMPILER_LAUNCHER "" CXX_COMPILER_LAUNCHER "")
  endif()
endfunction()

function(sfd_target_sanitizers target)
  if(SFD_ENABLE_SANITIZERS)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                           -fno-sanitize-recover=all)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# libFuzzer build (SFD_BUILD_FUZZERS, preset `fuzz`, clang only): every target of the project,
# generated LCM code included, gets the fuzzer's coverage instrumentation and ASan + UBSan; the
# fuzz executables link libFuzzer itself (tests/fuzz). Directory-wide, so call it before the
# subdirectories are added.
function(sfd_enable_fuzzing_instrumentation)
  if(NOT CMAKE_C_COMPILER_ID STREQUAL "Clang" OR NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR
      "SFD_BUILD_FUZZERS needs clang for C and C++ (libFuzzer); got C: ${CMAKE_C_COMPILER_ID}, "
      "C++: ${CMAKE_CXX_COMPILER_ID}. Use the `fuzz` preset (clang-14 / clang++-14).")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer -g)
  add_link_options(-fsanitize=address,undefined)
endfunction()
