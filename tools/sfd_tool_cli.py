# SPDX-License-Identifier: MIT
"""The command-line convention of sfd's C++ tools (docs/deploy.md, "Command line") for the Python
scripts of tools/: `--help` exit 0, `--version` prints "SCRIPT MAJOR.MINOR.PATCH" of
core/include/sfd/sfd_version.h, a usage error is one line on stderr and exit 2.

    import sfd_tool_cli
    ap = argparse.ArgumentParser(...); sfd_tool_cli.add_version(ap, "review.py")
    args = sfd_tool_cli.positional(sys.argv, __doc__, 2, "plot_hil.py CSV PNG")  # no argparse

The version is read from the header next to the script: ../core/include/sfd/sfd_version.h in the
source tree, ../../include/sfd/sfd_version.h in an install tree (PREFIX/share/sfd)."""
import os
import re
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))


def version():
    """"MAJOR.MINOR.PATCH" of sfd_version.h (PATCH 0 while the header has none), or "unknown"."""
    for rel in (("..", "core", "include"), ("..", "..", "include")):
        path = os.path.join(_HERE, *rel, "sfd", "sfd_version.h")
        try:
            text = open(path, encoding="utf-8").read()
        except OSError:
            continue
        num = {k: re.search(r"#define SFD_VERSION_%s (\d+)" % k, text) for k in
               ("MAJOR", "MINOR", "PATCH")}
        if num["MAJOR"] and num["MINOR"]:
            return "%s.%s.%s" % (num["MAJOR"].group(1), num["MINOR"].group(1),
                                 num["PATCH"].group(1) if num["PATCH"] else "0")
    return "unknown"


def add_version(ap, prog):
    """`--version` on an argparse parser: "PROG 0.2.0", exit 0."""
    ap.add_argument("--version", action="version", version="%s %s" % (prog, version()),
                    help='print "%s %s", then exit 0' % (prog, version()))


def positional(argv, doc, count, usage, at_least=False):
    """argv[1:] of a script that takes COUNT positional arguments (COUNT or more with AT_LEAST)
    and no options: -h/--help prints DOC (exit 0), --version the version (exit 0); an option or
    another count is one line on stderr and exit 2. `--` ends the options."""
    prog = os.path.basename(argv[0])
    args = list(argv[1:])
    if args[:1] in (["-h"], ["--help"]):
        print(doc.strip())
        sys.exit(0)
    if args[:1] == ["--version"]:
        print("%s %s" % (prog, version()))
        sys.exit(0)
    if "--" in args:
        cut = args.index("--")
        opts, args = args[:cut], args[:cut] + args[cut + 1:]
    else:
        opts = args
    for a in opts:
        if a.startswith("-") and a != "-":
            print("%s: unknown option %s (%s --help lists the options)" % (prog, a, prog),
                  file=sys.stderr)
            sys.exit(2)
    if len(args) < count or (len(args) > count and not at_least):
        print("usage: %s" % usage, file=sys.stderr)
        sys.exit(2)
    return args


def import_lcm_types(prog):
    """The generated LCM Python types (package `sfd`): found on PYTHONPATH, else in
    $SFD_LCM_PYTHON, else in build/host/lcm_types/python of the source tree (review.py,
    strip_spurious.py). Returns the package;
    without it, one line on stderr naming PROG and exit 2."""
    try:
        from sfd import feature_verdict_t  # noqa: F401
    except ImportError:
        root = os.path.dirname(_HERE)
        for p in (os.environ.get("SFD_LCM_PYTHON", ""),
                  os.path.join(root, "build", "host", "lcm_types", "python")):
            if p and os.path.isdir(os.path.join(p, "sfd")):
                sys.path.insert(0, p)
                break
    try:
        import sfd
        return sfd
    except ImportError:
        print("%s: no generated LCM types (package sfd): build the host preset or set "
              "SFD_LCM_PYTHON" % prog, file=sys.stderr)
        sys.exit(2)
