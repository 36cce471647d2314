#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Size, state and stack report of a bare-metal firmware image, checked against budgets.

Measures, from the linked ELF and the compiler's call graphs:
  - text / data / bss (`SIZE elf`, Berkeley format) and the per-section table (`SIZE -A`);
    flash used = text + data (the .data initialisers live in flash), RAM used = data + bss
    (bss includes the reserved .stack section);
  - the size of the core-state object(s) (`NM -S`, --state-symbol), SPEC: <= 256 KiB for 256
    features and L = 5;
  - the worst-case stack of every public core entry point (sfd_*) over the core's and the
    firmware's -fcallgraph-info=su graphs (SPEC: <= 16 KiB per call), and of each --root
    (Reset_Handler) against the size of the image's .stack section;
  - that no constructor would be skipped (.init_array empty: the startup code runs none).
Functions outside the graphs (newlib's memcpy, libm's sqrt/sin/...) are charged
--extern-allowance bytes each and listed, as tools/stack_report.py does.

Check names: flash, ram, state, stack_entry, stack_root, graph, init_array. Exit 0 when every
check passes; with --expect-fail A,B exit 0 only when exactly those checks fail (the positive
control of a canary image, so a check gone blind turns red).
"""
import argparse
import os
import re
import subprocess
import sys
import sfd_tool_cli  # tools/sfd_tool_cli.py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stack_report import is_project_function, parse, resolve_aliases  # noqa: E402  (same directory)


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def sections(size_tool, elf):
    """{section name: size in bytes} from `size -A -d`."""
    out = {}
    for line in run([size_tool, '-A', '-d', elf]).splitlines():
        m = re.match(r'^(\.\S+)\s+(\d+)\s+(\d+)', line)
        if m:
            out[m.group(1)] = int(m.group(2))
    return out


def worst_stack(graphs, allowance, fn):
    """Deepest path from fn: own frame + max over callees, iteratively (no recursion here either).
    Returns (bytes, errors)."""
    files, frames, kinds, labels, edges = graphs
    errors, memo = [], {}
    stack = [(fn, iter(sorted(edges.get(fn, ()))), [fn])]
    best = {fn: 0}
    while stack:
        node, it, path = stack[-1]
        callee = next(it, None)
        if callee is None:
            stack.pop()
            memo[node] = frames[node] + best[node] if node in frames else allowance
            if stack:
                parent = stack[-1][0]
                best[parent] = max(best[parent], memo[node])
            continue
        if callee in memo:
            best[node] = max(best[node], memo[callee])
            continue
        if callee in path:
            errors.append('recursion: ' + ' -> '.join(path + [callee]))
            continue
        if callee == '__indirect_call':
            errors.append(f'indirect call from {node}')
        best[callee] = 0
        stack.append((callee, iter(sorted(edges.get(callee, ()))), path + [callee]))
    return memo.get(fn, 0), errors


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "firmware_report.py")
    ap.add_argument('--elf', required=True)
    ap.add_argument('--size-tool', default='arm-none-eabi-size')
    ap.add_argument('--nm', default='arm-none-eabi-nm')
    ap.add_argument('--objdir', action='append', required=True,
                    help='directory with .ci call graphs (repeat: core, firmware)')
    ap.add_argument('--flash-budget', type=int, required=True, help='bytes of flash')
    ap.add_argument('--ram-budget', type=int, required=True, help='bytes of RAM')
    ap.add_argument('--state-symbol', action='append', default=[],
                    help='object(s) holding the core state (repeat)')
    ap.add_argument('--state-budget', type=int, default=262144)
    ap.add_argument('--stack-budget', type=int, default=16384, help='bytes per sfd_* entry point')
    ap.add_argument('--root', action='append', default=[],
                    help='function whose worst path must fit the .stack section (repeat)')
    ap.add_argument('--extern-allowance', type=int, default=1024)
    ap.add_argument('--expect-fail', default='', help='comma-separated check names')
    args = ap.parse_args()

    failed = {}

    def check(name, ok, msg):
        print(('ok    ' if ok else 'FAIL  ') + f'{name:12s} {msg}')
        if not ok:
            failed.setdefault(name, []).append(msg)

    # --- sizes ------------------------------------------------------------------------------
    berkeley = run([args.size_tool, args.elf]).strip().splitlines()
    print('\n'.join(berkeley))
    text, data, bss = (int(x) for x in berkeley[-1].split()[:3])
    secs = sections(args.size_tool, args.elf)
    print('sections: ' + ', '.join(f'{k} {v}' for k, v in secs.items() if v))
    check('flash', text + data <= args.flash_budget,
          f'text + data = {text + data} B of {args.flash_budget} B')
    check('ram', data + bss <= args.ram_budget,
          f'data + bss = {data + bss} B of {args.ram_budget} B (bss includes .stack '
          f'{secs.get(".stack", 0)} B)')
    check('init_array', secs.get('.init_array', 0) == 0,
          f'.init_array {secs.get(".init_array", 0)} B (Reset_Handler runs no constructors)')

    # --- core state ---------------------------------------------------------------------------
    sizes = {}
    for line in run([args.nm, '-S', args.elf]).splitlines():
        parts = line.split()
        if len(parts) == 4:
            sizes[parts[3]] = int(parts[1], 16)
    for sym in args.state_symbol:
        if sym not in sizes:
            check('state', False, f'{sym}: no such sized symbol in the image')
            continue
        check('state', sizes[sym] <= args.state_budget,
              f'{sym} = {sizes[sym]} B of {args.state_budget} B')

    # --- stack --------------------------------------------------------------------------------
    merged = [[], {}, {}, {}, {}]
    for d in args.objdir:
        files, frames, kinds, labels, edges = parse(d)
        merged[0] += files
        merged[1].update(frames)
        merged[2].update(kinds)
        merged[3].update(labels)
        for k, v in edges.items():
            merged[4].setdefault(k, set()).update(v)
    resolve_aliases(merged[1], merged[2], merged[3], merged[4])
    graphs = tuple(merged)
    files, frames, kinds = graphs[0], graphs[1], graphs[2]
    if not files:
        check('graph', False, 'no .ci files under ' + ', '.join(args.objdir))
    for f, k in sorted(kinds.items()):
        if k not in ('static', 'dynamic,bounded'):
            check('graph', False, f'{f}: frame is {k}, unbounded')
    graph_errors = set()
    entries = sorted(t for t in frames if t.startswith('sfd_'))
    worst_entry, worst_name = 0, ''
    over = []
    for e in entries:
        w, errs = worst_stack(graphs, args.extern_allowance, e)
        graph_errors.update(errs)
        if w > worst_entry:
            worst_entry, worst_name = w, e
        if w > args.stack_budget:
            over.append(f'{e} {w} B')
    check('stack_entry', not over and bool(entries),
          f'worst sfd_* entry point {worst_name} = {worst_entry} B of {args.stack_budget} B'
          + (' (over: ' + ', '.join(over) + ')' if over else ''))
    reserved = secs.get('.stack', 0)
    for r in args.root:
        if r not in frames:
            check('stack_root', False, f'{r}: not in the call graphs')
            continue
        w, errs = worst_stack(graphs, args.extern_allowance, r)
        graph_errors.update(errs)
        check('stack_root', w <= reserved, f'{r} worst path = {w} B of the {reserved} B .stack')
    for x in sorted({c for cs in graphs[4].values() for c in cs if c not in frames}):
        if is_project_function(x):
            graph_errors.add(f'{x}: a project function outside the call graph (charged, not followed)')
    for e in sorted(graph_errors):
        check('graph', False, e)
    if not graph_errors:
        check('graph', True, f'{len(files)} call graphs, {len(frames)} functions: no recursion, '
              'no indirect call, every frame bounded')
    externs = sorted({c for cs in graphs[4].values() for c in cs if c not in frames
                      and c != '__indirect_call'})
    if externs:
        print(f'external functions charged {args.extern_allowance} B each: ' + ', '.join(externs))

    expected = {x for x in args.expect_fail.split(',') if x}
    if expected:
        ok = set(failed) == expected
        print(f'positive control: expected to fail {sorted(expected)}, failed {sorted(failed)}: '
              + ('as expected' if ok else 'NOT as expected'))
        return 0 if ok else 1
    print(f'firmware budgets: {"all met" if not failed else "EXCEEDED: " + ", ".join(sorted(failed))}')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
