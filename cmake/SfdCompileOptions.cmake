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
# binary, and across targets wherever the libm calls agree), -O2 whatever the build type: at
# -O0/-O1/-Os Eigen keeps never-taken heap fallbacks that the symbol check would (rightly) flag.
# -fstack-usage and -fcallgraph-info=su feed tools/stack_report.py (worst-case stack, no recursion).
function(sfd_target_flight_rules target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti -fno-threadsafe-statics>
    -ffp-contract=off -fno-fast-math -fno-associative-math
    -O2 -fstack-usage -fcallgraph-info=su
    -Werror)
  target_compile_definitions(${target} PRIVATE EIGEN_NO_IO EIGEN_NO_AUTOMATIC_RESIZING
                             EIGEN_MPL2_ONLY)
endfunction()

function(sfd_target_sanitizers target)
  if(SFD_ENABLE_SANITIZERS)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                           -fno-sanitize-recover=all)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
