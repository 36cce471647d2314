/* SPDX-License-Identifier: MIT */
/* fuzz.features: the input is one FEATURES message, handled by a node in the primed state
 * (calibrated, window full, IMU up to 0.995 s), followed by IMU at rest up to its time, one
 * well-formed frame 50 ms later and end of input: decode, validation (count, capacity, camera,
 * order, depth priors), the pending-frame path, the detector on a full window, and whether the
 * frame after it is still judged. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t g_buf[2 * SFD_NODE_MAX_MESSAGE];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fz_restore_primed(0);
    fz_handle(SFD_NODE_FEATURES, data, size);
    const int64_t t = g_fz_node.pipe.last_frame_utime;
    fz_imu_until(t, 400);
    if (t <= INT64_MAX - 50000) {
        fz_imu_until(t + 50000, 20);
        fz_handle(SFD_NODE_FEATURES, g_buf,
                  (size_t)fz_encode_features(g_buf, (int)sizeof g_buf, t + 50000, 0, 20));
    }
    fz_flush();
    return 0;
}
