/* SPDX-License-Identifier: MIT */
/* fuzz.camera_info: the input is one CAMERA_INFO message, handled (1) by a fresh node, which then
 * receives IMU at rest and three frames of the fixed grid for the camera it follows (the third
 * completes a window), then sfd-sim's calibration (camera 0) and one more frame; (2) by a node
 * already calibrated with sfd-sim's camera and holding a full window, then three frames; each
 * ends with end of input. Covers the calibration's validation (camera model, extrinsics), the
 * choice of the camera to follow, re-calibration, and the detector running with whatever
 * calibration was accepted. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t g_buf[2 * SFD_NODE_MAX_MESSAGE];

static void frames(int64_t t0, int count) {
    const int32_t cam = g_fz_node.pipe.have_camera ? g_fz_node.camera_id : 0;
    for (int k = 0; k < count; ++k) {
        const int64_t t = t0 + 50000 * (int64_t)k;
        fz_imu_until(t, 20);
        fz_handle(SFD_NODE_FEATURES, g_buf,
                  (size_t)fz_encode_features(g_buf, (int)sizeof g_buf, t, cam, 20));
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    sfd_node_config_t cfg;
    fz_default_config(&cfg);
    fz_reset(&cfg);
    fz_handle(SFD_NODE_IMU, g_buf, (size_t)fz_encode_imu(g_buf, (int)sizeof g_buf, 900000));
    fz_handle(SFD_NODE_CAMERA_INFO, data, size);
    frames(1000000, 3);
    fz_handle(SFD_NODE_CAMERA_INFO, g_buf,
              (size_t)fz_encode_camera_info(g_buf, (int)sizeof g_buf, 1150000));
    frames(1150000, 1);
    fz_flush();

    fz_restore_primed(0);
    fz_handle(SFD_NODE_CAMERA_INFO, data, size);
    frames(1000000, 3);
    fz_flush();
    return 0;
}
