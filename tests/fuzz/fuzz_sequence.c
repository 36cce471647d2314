/* SPDX-License-Identifier: MIT */
/* fuzz.sequence: the input is a configuration byte and a sequence of messages on the three input
 * channels (format in fuzz_harness.h), played through one node from a fresh start, then end of
 * input: the stateful ingest (IMU ring, pending frame, frame assembly, re-calibration) and the
 * parity detector behind it, with the invariants checked after every message. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t g_buf[2 * SFD_NODE_MAX_MESSAGE];

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
    return 0;
}
