#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fails when a static library references heap, exception, RTTI or static-guard machinery.

Lists the undefined symbols of every member of ARCHIVE with NM (nm -u) and rejects the C heap
(malloc, calloc, realloc, free, aligned allocators), C++ operator new/delete (any overload, 32- or
64-bit size_t), exception support (__cxa_throw, __cxa_allocate_exception, __cxa_begin_catch,
__gxx_personality_v0, _Unwind_Resume), thread-safe static guards (__cxa_guard_*), static destructor
registration (__cxa_atexit) and RTTI (typeinfo vtables of __cxxabiv1).
Exit 0 = clean, 1 = forbidden references found (listed with their object), 2 = usage/tool error.
"""
import re
import subprocess
import sys

import sfd_tool_cli  # tools/sfd_tool_cli.py

FORBIDDEN = re.compile(
    r'^(malloc|calloc|realloc|free|aligned_alloc|posix_memalign|memalign|valloc|pvalloc'
    r'|_Znw[jm].*|_Zna[jm].*|_ZdlPv.*|_ZdaPv.*'
    r'|__cxa_throw|__cxa_allocate_exception|__cxa_begin_catch|__cxa_rethrow|__gxx_personality_v0'
    r'|_Unwind_Resume|__cxa_guard_acquire|__cxa_guard_release|__cxa_guard_abort|__cxa_atexit'
    r'|_ZTVN10__cxxabiv1.*|_ZTI.*)$')


def main(argv):
    nm, archive = sfd_tool_cli.positional(argv, __doc__, 2, 'check_core_symbols.py NM ARCHIVE')
    try:
        out = subprocess.run([nm, '-A', '-u', archive], check=True, capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        print(f'check_core_symbols: cannot run {nm} on {archive}: {exc}', file=sys.stderr)
        return 2
    undefined, bad = 0, []
    for line in out.splitlines():
        # "archive.a:member.o:                 U symbol"
        parts = line.split()
        if len(parts) < 2 or parts[-2] != 'U':
            continue
        undefined += 1
        sym = parts[-1]
        if FORBIDDEN.match(sym):
            bad.append((line.split(':')[1] if line.count(':') >= 2 else '?', sym))
    print(f'{archive}: {undefined} undefined references scanned')
    for member, sym in bad:
        print(f'FORBIDDEN: {member} references {sym}')
    if bad:
        print(f'{len(bad)} forbidden reference(s): core must not allocate, throw, or use RTTI')
        return 1
    print('clean: no heap, exception, RTTI or static-guard references')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
