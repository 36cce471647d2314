/* SPDX-License-Identifier: MIT */
/* example.firmware_window: the firmware example's work (fw_window.c), run on the host, where it
 * can run: a motionless camera over a constant scene must give SFD_FW_FEATURES CONSISTENT
 * verdicts from the full parity window and from OPRF, with every call returning SFD_OK. */
#include <sfd/sfd.h>
#include <stdio.h>

#include "fw_window.h"

int main(void) {
    sfd_fw_report_t r;
    const int32_t st = sfd_fw_run_window(&r);
    printf(
        "status %d (%s), frames %d, parity flags 0x%x: %d consistent, %d spurious, %d untested\n",
        (int)st, sfd_status_str((sfd_status_t)st), (int)r.frames_pushed, (unsigned)r.parity_flags,
        (int)r.parity_consistent, (int)r.parity_spurious, (int)r.parity_untested);
    printf("OPRF: %d consistent, %d spurious, %d untested, EKF update status %d\n",
           (int)r.assoc_consistent, (int)r.assoc_spurious, (int)r.assoc_untested,
           (int)r.assoc_update_status);
    int passed = 0;
    int failed = 0;
    const int checks[] = {st == SFD_OK, r.frames_pushed == SFD_MAX_WINDOW,
                          r.parity_consistent == SFD_FW_FEATURES,
                          r.assoc_consistent == SFD_FW_FEATURES, r.assoc_update_status == SFD_OK};
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
