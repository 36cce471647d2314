#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Static analysis over compile_commands.json: `lint.py clang-tidy BUILD` or `lint.py cppcheck BUILD`.
Optional trailing arguments restrict the run to files whose path contains one of them (a quick
check of the files you changed: `lint.py clang-tidy build/host core/src/ekf.cpp`).

Scope: the project's own translation units (core/, drivers/, apps/, tests/); generated code in the
build tree and third-party headers are not analysed. GCC-only flags (-fcallgraph-info, -fstack-usage)
are removed from the commands given to the clang-based tools. Exit 1 on any finding.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import sfd_tool_cli  # tools/sfd_tool_cli.py

GCC_ONLY = ('-fcallgraph-info', '-fstack-usage', '-fno-associative-math')


def load(build, root):
    with open(os.path.join(build, 'compile_commands.json'), encoding='utf-8') as fh:
        db = json.load(fh)
    keep = []
    seen = set()
    for e in db:
        f = os.path.realpath(e['file'])
        if f in seen:
            continue  # the same source in a second target (e.g. sfd_core_cap512): analyse once
        seen.add(f)
        rel = os.path.relpath(f, root)
        if rel.startswith('..') or rel.startswith('build') or '/canary_' in f:
            continue  # outside the tree, generated, or a deliberate rule-breaker (proof controls)
        if not rel.startswith(('core/', 'drivers/', 'apps/', 'tests/')):
            continue
        args = e.get('arguments') or e['command'].split()
        args = [a for a in args if not a.startswith(GCC_ONLY) and a != 'ccache' and
                not a.endswith('/ccache')]
        keep.append({'directory': e['directory'], 'file': f, 'arguments': args})
    return keep


def main():
    sys.argv[1:] = sfd_tool_cli.positional(sys.argv, __doc__, 2,
                                           'lint.py clang-tidy|cppcheck BUILD [FILE...]', True)
    if len(sys.argv) < 3 or sys.argv[1] not in ('clang-tidy', 'cppcheck'):
        print(__doc__)
        return 2
    tool, build = sys.argv[1], os.path.abspath(sys.argv[2])
    only = sys.argv[3:]  # optional: analyse only files whose path contains one of these
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    entries = load(build, root)
    if only:
        entries = [e for e in entries if any(o in e['file'] for o in only)]
    if not entries:
        print('lint: no translation units found')
        return 1
    tmp = tempfile.mkdtemp(prefix='sfd-lint-')
    try:
        with open(os.path.join(tmp, 'compile_commands.json'), 'w', encoding='utf-8') as fh:
            json.dump(entries, fh)
        if tool == 'clang-tidy':
            exe = shutil.which('clang-tidy-14') or shutil.which('clang-tidy')
            if not exe:
                print('lint: clang-tidy not found (run tools/setup.sh)')
                return 2
            failed = 0
            for e in entries:
                r = subprocess.run([exe, '-p', tmp, '--quiet', e['file']], capture_output=True,
                                   text=True, cwd=root)
                out = (r.stdout + r.stderr).strip()
                if r.returncode != 0:
                    failed += 1
                    print(out)
            print(f'clang-tidy: {len(entries)} translation units, {failed} with findings')
            return 1 if failed else 0
        exe = shutil.which('cppcheck')
        if not exe:
            print('lint: cppcheck not found (run tools/setup.sh)')
            return 2
        cmd = [exe, f'--project={os.path.join(tmp, "compile_commands.json")}', '--quiet',
               '--enable=warning,performance,portability', '--error-exitcode=1',
               '--inline-suppr', '--suppress=missingIncludeSystem', '--suppress=unmatchedSuppression',
               '--suppress=*:/usr/include/*', f'--cppcheck-build-dir={tmp}', '-j2',
               # IEEE 754 is asserted in core (static_assert on is_iec559): all-bits-zero is 0.0
               '--suppress=memsetClassFloat']
        r = subprocess.run(cmd, cwd=root)
        print(f'cppcheck: {len(entries)} translation units, exit {r.returncode}')
        return r.returncode
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
