/* SPDX-License-Identifier: MIT */
/* example.firmware_window: the firmware example's work (fw_window.c), run on the host, where it
 * can run: a motionless camera over a constant scene through the whole pipeline must give
 * SFD_FW_FEATURES CONSISTENT verdicts on the last frame, a running filter that used the tracks
 * and stayed within a centimetre of its start, with every call returning SFD_OK. */
#include <sfd/sfd.h>
#include <stdio.h>

#include "fw_window.h"

int main(void) {
    sfd_fw_report_t r;
    const int32_t st = sfd_fw_run_window(&r);
    printf("status %d, frames judged %d; last frame: %d consistent, %d spurious, %d untested\n",
           (int)st, (int)r.frames_judged, (int)r.consistent, (int)r.spurious, (int)r.untested);
    printf("filter running %d, tracks used %d, position error %d mm\n", (int)r.has_state,
           (int)r.tracks_used, (int)r.position_err_mm);
    int passed = 0;
    int failed = 0;
    const int checks[] = {st == SFD_OK,
                          r.frames_judged == SFD_FW_FRAMES,
                          r.consistent == SFD_FW_FEATURES,
                          r.spurious == 0,
                          r.has_state == 1,
                          r.tracks_used > SFD_FW_FEATURES,
                          r.position_err_mm <= 10};
    for (unsigned i = 0; i < sizeof checks / sizeof checks[0]; ++i) {
        if (checks[i]) {
            ++passed;
        } else {
            ++failed;
            printf("check %u failed\n", i);
        }
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
