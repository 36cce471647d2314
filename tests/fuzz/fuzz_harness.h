/* SPDX-License-Identifier: MIT */
/**
 * @file fuzz_harness.h
 * @brief Shared by the libFuzzer targets: one caller-owned node (static), re-initialised
 *        deterministically per input, driven through sfd_node_handle()/sfd_node_flush() exactly as
 *        sfd-node and sfd-replay drive it, with the invariants a flight user relies on checked
 *        after every message (a violation prints a line and calls abort(), which libFuzzer
 *        reports as a crash):
 *
 *  - a FEATURES message is accepted exactly when it decodes, its count is within the wire and
 *    core capacities, a calibration is known for its camera and its utime is new;
 *  - every accepted frame gets exactly one SFD_VERDICT (by the next frame or at the latest at
 *    flush), in order, listing exactly the frame's features (count, track ids, order), with the
 *    frame's utime and camera_id, valid status/stage values and finite statistics;
 *  - every published message decodes with LCM's generated code;
 *  - counters only grow (node counters after each call, SFD_TIMING's rejected[] across messages),
 *    each input bumps its own input counter by one, frames_processed counts the verdicts;
 *  - SFD_TIMING follows its frame's verdict, or is a status report (frame_processed 0, no
 *    durations); in each, every frame received is refused, judged or held (at most 2);
 *  - once the node follows a camera, it never switches to another.
 */
#ifndef SFD_FUZZ_HARNESS_H
#define SFD_FUZZ_HARNESS_H

#include <stddef.h>
#include <stdint.h>

#include "sfd_node_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The node under test (caller-owned, static: ~0.36 MiB). */
extern sfd_node_t g_fz_node;

/** Aborts with a message naming the violated invariant. */
#define FZ_CHECK(cond)                                   \
    do {                                                 \
        if (!(cond)) fz_fail(__FILE__, __LINE__, #cond); \
    } while (0)
void fz_fail(const char *file, int line, const char *what);

/** Default configuration (sfd_params_default, camera -1 = follow the first, timing on). */
void fz_default_config(sfd_node_config_t *cfg);

/** Clears the node's whole storage, initialises it with @p cfg and resets the checker. */
void fz_reset(const sfd_node_config_t *cfg);

/** One message through sfd_node_handle(), with the invariants checked. */
void fz_handle(sfd_node_input_t kind, const void *data, size_t size);

/** End of input through sfd_node_flush(): no frame may be left without its verdict. */
void fz_flush(void);

/** Verdicts published since the last fz_reset(). */
int64_t fz_verdicts(void);

/* --- Well-formed messages for priming (the same calibration as sfd-sim's logs) -------------- */

/** Encodes sfd-sim's CAMERA_INFO (camera 0, EuRoC-like radtan) into @p buf; returns the size. */
int fz_encode_camera_info(uint8_t *buf, int cap, int64_t utime);

/** The same calibration for another camera id. */
int fz_encode_camera_info_id(uint8_t *buf, int cap, int64_t utime, int32_t camera_id);
/** Encodes an IMU sample at rest (zero rate, gravity on z). */
int fz_encode_imu(uint8_t *buf, int cap, int64_t utime);
/** Encodes a frame of @p n features on a fixed grid, track ids 1..n (a static camera). */
int fz_encode_features(uint8_t *buf, int cap, int64_t utime, int32_t camera_id, int n);

/** Sends IMU samples every 5 ms after the newest one the node accepted, up to and including
 *  @p until_us (at most @p max_samples; beyond that, one sample at @p until_us). */
void fz_imu_until(int64_t until_us, int max_samples);

/**
 * Primed state for the single-channel targets: sfd-sim's calibration, IMU at rest every 5 ms
 * from 0.8 s to 0.995 s, frames (fz_encode_features, 20 features) at 0.85, 0.90, 0.95 s, so the
 * window is full (L = 3) and the next frame at 1.0 s, sfd-sim's first, is tested. With
 * @p pending_frame, a frame at 1.0 s has also arrived and waits for its IMU.
 * Built once, then copied into g_fz_node per input (deterministic and cheap).
 */
void fz_restore_primed(int pending_frame);

/* --- The sequence target's input format (fuzz_sequence.c; make_seeds.c writes it) ---------- */

/**
 * Byte 0: configuration (FZ_CFG_* bits, 0 = the defaults). Then records, at most
 * FZ_SEQ_MAX_MESSAGES: a selector byte (its value modulo FZ_SEQ_KINDS is a FZ_SEQ_* kind), a
 * little-endian 16-bit length and that many payload bytes (fewer at the end of the input). The end
 * of input is sfd_node_flush().
 */
enum {
    FZ_SEQ_IMU = 0,              /**< payload: the IMU wire message */
    FZ_SEQ_CAMERA_INFO = 1,      /**< payload: the CAMERA_INFO wire message */
    FZ_SEQ_FEATURES = 2,         /**< payload: the FEATURES wire message (20 504 bytes) */
    FZ_SEQ_FEATURES_COMPACT = 3, /**< payload: fz_compact_features layout, encoded to the wire
                                      by the target before sfd_node_handle() */
    FZ_SEQ_IMU_BURST = 4,        /**< payload: fz_imu_burst layout: many IMU wire messages */
    FZ_SEQ_KINDS = 5,
    FZ_SEQ_MAX_MESSAGES = 1024,
    FZ_SEQ_HEADER = 3
};

/** Configuration byte: parity window L (bits 0-1: default 3, 2, 4, 5), bit 3 follow camera 0
 *  (else the first CAMERA_INFO's), bit 4 isolation off, bit 5 approximate covariance (28), bits
 *  6-7 group size (default 3, 1, 2, 4), each clamped to the build's capacities. Bit 2 clear:
 *  parity, with the filter's translation when bits 6-7 are both set. Bit 2 set: bits 4-5 pick a
 *  filter method (none, oprf, both, ransac1; ransacf with bit 0), bits 6-7 both set the
 *  single-state EKF, and `both` with L = 2 the window filter's keyframe option. */
void fz_config_from_byte(uint8_t b, sfd_node_config_t *cfg);

/** Compact FEATURES payload: utime (int64), camera_id (int32), num_features (int32), then per
 *  feature track_id (int64), u, v, depth, depth_var (doubles), all little-endian; features not
 *  present in the payload are zero. */
enum { FZ_COMPACT_HEADER = 16, FZ_COMPACT_FEATURE = 40 };

/** Builds the wire FEATURES message of a compact payload into @p buf; returns its size. */
int fz_compact_to_wire(const uint8_t *payload, size_t len, uint8_t *buf, int cap);

/** IMU burst payload: utime of the first sample (int64), step (int32, us), count (uint16, at most
 *  FZ_BURST_MAX), gyro[3], accel[3] (doubles), little-endian, missing bytes zero: @p count IMU
 *  wire messages at utime + k * step (wrapping), each through sfd_node_handle(). Reaches the
 *  ring's overflow and the per-interval sample capacity within a short input. */
enum { FZ_BURST_SIZE = 62, FZ_BURST_MAX = 2 * SFD_IMU_RING_CAPACITY };
void fz_imu_burst(const uint8_t *payload, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* SFD_FUZZ_HARNESS_H */
