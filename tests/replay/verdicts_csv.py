#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the SFD_VERDICT messages of an LCM log as CSV (utime, track_id, status, stage,
statistic with 6 significant digits), for the golden replay regression.
usage: verdicts_csv.py LOG.lcmlog > verdicts.csv   (PYTHONPATH must hold the generated sfd types)"""
import sys

import lcm
from sfd import feature_verdict_t


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    print('utime,track_id,status,stage,statistic')
    for ev in lcm.EventLog(sys.argv[1], 'r'):
        if ev.channel != 'SFD_VERDICT':
            continue
        m = feature_verdict_t.decode(ev.data)
        for i in range(m.num_features):
            print('%d,%d,%d,%d,%.6g' % (m.utime, m.track_id[i], m.status[i], m.stage[i],
                                         m.statistic[i]))
    return 0


if __name__ == '__main__':
    sys.exit(main())
