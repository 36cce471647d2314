/* SPDX-License-Identifier: MIT */
/* fuzz.imu: the input is one IMU message, handled by a node in the primed state (calibrated, full
 * window, a frame at 1.0 s waiting for its IMU), then end of input: decode, validation, the IMU
 * ring, the pending frame and its motion assembly (gyro integration) and the detector behind it. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fz_restore_primed(1);
    fz_handle(SFD_NODE_IMU, data, size);
    fz_flush();
    return 0;
}
