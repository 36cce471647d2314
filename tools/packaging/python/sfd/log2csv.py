# SPDX-License-Identifier: MIT
"""python3 -m sfd.log2csv LOG OUTDIR [--channel NAME ...]: an sfd LCM log as CSV files.

Writes OUTDIR/CHANNEL.csv (one row per message) and, for FEATURES, SFD_VERDICT and TRUTH,
OUTDIR/CHANNEL.features.csv (one row per feature); see sfd.log.write_csv. Prints one line per
file written. Exit 0; 2 when LOG cannot be read or is not an LCM log, or OUTDIR cannot be
written (one line naming it).
"""
import argparse
import sys

from . import __version__
from .log import LogError, load_log, write_csv


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m sfd.log2csv",
                                 description="Writes the sfd messages of an LCM log as CSV.")
    ap.add_argument("log", help="LCM log (sfd-replay -o, sfd-sim -o, lcm-logger)")
    ap.add_argument("outdir", help="directory for the CSV files (created)")
    ap.add_argument("--channel", action="append", metavar="NAME",
                    help="only this channel (repeatable; default: every sfd channel)")
    ap.add_argument("--version", action="version", version="sfd " + __version__)
    args = ap.parse_args(argv)
    try:
        log = load_log(args.log, channels=args.channel)
    except (OSError, LogError) as e:
        print("log2csv: %s" % e, file=sys.stderr)
        return 2
    if args.channel:
        missing = [c for c in args.channel if c not in log]
        if missing:
            print("log2csv: %s: no sfd messages on channel %s" % (args.log, missing[0]),
                  file=sys.stderr)
            return 2
    try:
        written = write_csv(log, args.outdir)
    except OSError as e:
        print("log2csv: %s" % e, file=sys.stderr)
        return 2
    for path, rows in written:
        print("%s: %d rows" % (path, rows))
    for channel, n in sorted(log.skipped.items()):
        print("skipped %s: %d events of a type that is not sfd's" % (channel, n))
    for channel, n in sorted(log.malformed.items()):
        print("skipped %s: %d malformed events" % (channel, n))
    if log.truncated_at is not None:
        print("%s: last event cut short at byte %d (ignored)" % (args.log, log.truncated_at))
    return 0


if __name__ == "__main__":
    sys.exit(main())
