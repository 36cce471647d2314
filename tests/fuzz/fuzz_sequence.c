/* SPDX-License-Identifier: MIT */
/* fuzz.sequence: the input is a configuration byte (every detection method, the window filter or
 * the single-state EKF, parity with known translation: fz_config_from_byte) and a sequence of
 * messages on the three input channels (format in fuzz_harness.h), played through one node from
 * a fresh start: the stateful ingest (IMU ring, pending frame, frame assembly, re-calibration,
 * the time-glitch policy) and the detectors behind it, with the invariants checked after every
 * message. Then a recovery oracle: whatever the input did, a clean stream on the followed camera
 * 10 s after the newest time the node accepted (from 0 when that would overflow) must be judged
 * again: of its FZ_TAIL_FRAMES frames at most the resync count minus one may be refused (the
 * time-glitch policy's stated cost, docs/time_glitches.md), every other one gets its verdict. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t g_buf[2 * SFD_NODE_MAX_MESSAGE];

enum { FZ_TAIL_FRAMES = 12 };

static void recovery_tail(void) {
    const sfd_node_t *n = &g_fz_node;
    /* the camera the node follows (any id, negative ones included), else camera 0 */
    const int32_t cam = (n->pipe.have_camera || n->camera_id >= 0) ? n->camera_id : 0;
    const int64_t ti = n->pipe.last_imu_utime, tf = n->pipe.last_frame_utime;
    const int64_t newest = ti > tf ? ti : tf;
    int64_t t0 = 1000000;
    if (newest != INT64_MIN) t0 = newest < INT64_MAX - 100000000 ? newest + 10000000 : 0;
    fz_handle(SFD_NODE_CAMERA_INFO, g_buf,
              (size_t)fz_encode_camera_info_id(g_buf, (int)sizeof g_buf, t0, cam));
    const int64_t before = fz_verdicts();
    int64_t t = t0;
    for (int f = 1; f <= FZ_TAIL_FRAMES; ++f) {
        const int64_t tf_us = t0 + 50000 * (int64_t)f;
        while (t < tf_us) {
            t += 5000;
            fz_handle(SFD_NODE_IMU, g_buf, (size_t)fz_encode_imu(g_buf, (int)sizeof g_buf, t));
        }
        fz_handle(SFD_NODE_FEATURES, g_buf,
                  (size_t)fz_encode_features(g_buf, (int)sizeof g_buf, tf_us, cam, 20));
    }
    fz_flush();
    const int64_t lost_at_most = n->cfg.time.resync_messages - 1;
    FZ_CHECK(fz_verdicts() - before >= FZ_TAIL_FRAMES - lost_at_most);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    sfd_node_config_t cfg;
    fz_config_from_byte(size > 0 ? data[0] : 0, &cfg);
    fz_reset(&cfg);
    size_t off = 1;
    for (int m = 0; m < FZ_SEQ_MAX_MESSAGES && off < size; ++m) {
        const unsigned kind = data[off] % FZ_SEQ_KINDS;
        size_t len = 0;
        if (off + 1 < size) len = data[off + 1];
        if (off + 2 < size) len |= (size_t)data[off + 2] << 8;
        off += FZ_SEQ_HEADER;
        if (off > size) off = size;
        if (len > size - off) len = size - off;
        const uint8_t *payload = data + off;
        off += len;
        switch (kind) {
            case FZ_SEQ_IMU:
                fz_handle(SFD_NODE_IMU, payload, len);
                break;
            case FZ_SEQ_CAMERA_INFO:
                fz_handle(SFD_NODE_CAMERA_INFO, payload, len);
                break;
            case FZ_SEQ_FEATURES:
                fz_handle(SFD_NODE_FEATURES, payload, len);
                break;
            case FZ_SEQ_IMU_BURST:
                fz_imu_burst(payload, len);
                break;
            default: {
                const int n = fz_compact_to_wire(payload, len, g_buf, (int)sizeof g_buf);
                FZ_CHECK(n > 0);
                fz_handle(SFD_NODE_FEATURES, g_buf, (size_t)n);
                break;
            }
        }
    }
    fz_flush();
    recovery_tail();
    return 0;
}
