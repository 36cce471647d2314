#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Worst-case stack per public core entry point, from GCC's -fcallgraph-info=su output.

Reads every *.ci file (VCG call graphs with per-function frame sizes) under --objdir, merges them
into one graph, and for each function named sfd_* (the C API) computes the deepest path:
own frame + max over callees. Fails (exit 1) when
  - any entry point exceeds --budget bytes,
  - the graph has a cycle (recursion, forbidden in core),
  - a function has an unbounded dynamic frame (alloca, VLA), or an indirect call is made.
Functions outside the core (libm, libc: sin, memcpy, ...) have no frame size in the graph; each is
charged --extern-allowance bytes and listed, so the report says what it assumed.
"""
import argparse
import glob
import os
import re
import sys
import sfd_tool_cli  # tools/sfd_tool_cli.py

NODE_RE = re.compile(r'node:\s*\{\s*title:\s*"([^"]+)"\s*label:\s*"([^"]*)"(.*)\}')
EDGE_RE = re.compile(r'edge:\s*\{\s*sourcename:\s*"([^"]+)"\s*targetname:\s*"([^"]+)"')
SIZE_RE = re.compile(r'\\n(\d+) bytes \(([a-z,]+)\)')


def parse(objdir):
    frames, kinds, labels, edges = {}, {}, {}, {}
    files = sorted(glob.glob(os.path.join(objdir, '**', '*.ci'), recursive=True))
    for path in files:
        with open(path, encoding='utf-8', errors='replace') as fh:
            for line in fh:
                m = NODE_RE.search(line)
                if m:
                    title, label = m.group(1), m.group(2)
                    labels.setdefault(title, label.split('\\n')[0])
                    s = SIZE_RE.search(label)
                    if s:
                        frames[title] = int(s.group(1))
                        kinds[title] = s.group(2)
                    continue
                m = EDGE_RE.search(line)
                if m:
                    edges.setdefault(m.group(1), set()).add(m.group(2))
    return files, frames, kinds, labels, edges


CTOR_DTOR_RE = re.compile(r'([CD])1(E|I)')
# A constructor or destructor label: 'ns::X::X(' or 'ns::X::~X(' (template arguments allowed).
CTOR_LABEL_RE = re.compile(r'(?:^|[\s:])(\w+)(?:<[^()]*>)?::~?\1\(')


def is_project_function(title):
    """True for a call-graph title (a C symbol or a mangled C++ name) of the project's own code:
    the C API sfd_*, namespace sfd, and the anonymous namespaces of its files. Such a callee must
    be in the graph and followed, not charged the external allowance."""
    return title.startswith(('sfd_', '_ZN3sfd', '_ZNK3sfd', '_ZN12_GLOBAL__N_1',
                             '_ZNK12_GLOBAL__N_1'))


def resolve_aliases(frames, kinds, labels, edges):
    """Gives a frame to callee titles that name a function the graph holds under another title,
    so that its stack is followed instead of charged as external:
      - a file-local title 'path/file.cpp:MANGLED' (GCC's title for a function with internal
        linkage, e.g. a template instantiated with a type from an anonymous namespace) is also
        the function that other objects' edges call 'MANGLED';
      - a complete-object constructor or destructor 'C1'/'D1' (GCC emits the base-object 'C2'/
        'D2' and makes 'C1'/'D1' an alias of it).
    Several candidates: each alias gets the largest frame and the union of their callees (the
    worst case). Returns the list of (alias, target) pairs added."""
    wanted = set()
    for callees in edges.values():
        wanted |= {c for c in callees if c not in frames}
    by_name = {}
    for title in list(frames):
        name = title.rsplit(':', 1)[1] if ':' in title else ''
        if name.startswith('_Z'):  # 'path/file.cpp:_Z...': a file-local C++ function
            by_name.setdefault(name, []).append(title)
    added = []
    for w in sorted(wanted):
        targets = list(by_name.get(w, [])) if w.startswith('_Z') else []
        label = labels.get(w, '')
        if not targets and CTOR_LABEL_RE.search(label):
            # the last C1/D1 of the mangled name is the constructor's (nested names come first)
            spans = list(CTOR_DTOR_RE.finditer(w))
            if spans:
                m = spans[-1]
                base = w[:m.start()] + m.group(1) + '2' + m.group(2) + w[m.end():]
                targets = [t for t in [base] + by_name.get(base, []) if t in frames]
        if not targets:
            continue
        frames[w] = max(frames[t] for t in targets)
        kinds[w] = 'static' if all(kinds[t] == 'static' for t in targets) else \
            next(kinds[t] for t in targets if kinds[t] != 'static')
        labels.setdefault(w, labels.get(targets[0], w))
        for t in targets:
            edges.setdefault(w, set()).update(edges.get(t, ()))
            added.append((w, t))
    return added


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sfd_tool_cli.add_version(ap, "stack_report.py")
    ap.add_argument('--objdir', required=True, help='directory holding the core objects and .ci files')
    ap.add_argument('--budget', type=int, default=16384, help='bytes per entry point (default 16384)')
    ap.add_argument('--extern-allowance', type=int, default=1024,
                    help='bytes charged for each call into a function outside the graph')
    ap.add_argument('--prefix', default='sfd_', help='entry points: functions whose symbol starts so')
    args = ap.parse_args()

    files, frames, kinds, labels, edges = parse(args.objdir)
    resolve_aliases(frames, kinds, labels, edges)
    if not files:
        print(f'stack_report: no .ci files under {args.objdir} (build with -fcallgraph-info=su)')
        return 1
    errors = []
    for f, k in kinds.items():
        # 'dynamic,bounded' (e.g. arguments pushed for a call) is bounded by the reported size;
        # plain 'dynamic' (alloca, VLA) is not and is rejected.
        if k not in ('static', 'dynamic,bounded'):
            errors.append(f'{labels.get(f, f)}: frame is {k}, unbounded')
    externs, extern_titles = set(), set()
    memo, state = {}, {}

    def depth(fn, path):
        # Iterative-depth DFS on a DAG; the graph is small, Python recursion is fine here.
        if fn in memo:
            return memo[fn]
        if state.get(fn) == 'active':
            cyc = path[path.index(fn):] + [fn]
            errors.append('recursion: ' + ' -> '.join(labels.get(c, c) for c in cyc))
            return 0
        state[fn] = 'active'
        if fn not in frames:
            if fn == '__indirect_call':
                errors.append(f'indirect call from {labels.get(path[-1], path[-1]) if path else "?"}')
            externs.add(labels.get(fn, fn))
            extern_titles.add(fn)
            memo[fn] = args.extern_allowance
            state[fn] = 'done'
            return memo[fn]
        best, best_path = 0, []
        for callee in sorted(edges.get(fn, ())):
            d = depth(callee, path + [fn])
            if d > best:
                best = d
        memo[fn] = frames[fn] + best
        state[fn] = 'done'
        return memo[fn]

    entries = sorted(t for t in frames if t.startswith(args.prefix))
    if not entries:
        errors.append(f'no entry points starting with {args.prefix!r}')
    rows = []
    for e in entries:
        rows.append((e, frames[e], depth(e, [])))
    print(f'{"entry point":40s} {"own (B)":>8s} {"worst (B)":>10s}')
    for e, own, worst in sorted(rows, key=lambda r: -r[2]):
        flag = '  OVER BUDGET' if worst > args.budget else ''
        print(f'{e:40s} {own:8d} {worst:10d}{flag}')
        if worst > args.budget:
            errors.append(f'{e}: worst-case stack {worst} B > budget {args.budget} B')
    worst_all = max((r[2] for r in rows), default=0)
    print(f'worst entry point: {worst_all} B of {args.budget} B budget; '
          f'{len(files)} objects, {len(frames)} functions with frames')
    if externs:
        print(f'external functions charged {args.extern_allowance} B each: ' + ', '.join(sorted(externs)))
    for x in sorted(x for x in extern_titles if is_project_function(x)):
        errors.append(f'{labels.get(x, x)}: a project function outside the call graph '
                      '(charged, not followed)')
    for e in errors:
        print('ERROR: ' + e)
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
