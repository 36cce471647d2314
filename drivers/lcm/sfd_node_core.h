/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_node_core.h
 * @brief The node's message handling, shared by sfd-node (live LCM) and sfd-replay (log files),
 *        so that replay drives exactly the node's code path: decode and validate IMU,
 *        CAMERA_INFO and FEATURES, keep the IMU ring, assemble each frame's motion, run the
 *        parity detector and/or the EKF with its association method (sfd_node_nav.h), and
 *        publish SFD_VERDICT, SFD_STATE and SFD_TIMING through a caller-supplied function.
 *
 * Heap: none. All storage is in sfd_node_t (caller-owned, ~0.3 MiB: declare it static). Time
 * enters only through message timestamps; the optional clock function is used for SFD_TIMING's
 * durations only, never for decisions, so replays are deterministic.
 */
#ifndef SFD_NODE_CORE_H
#define SFD_NODE_CORE_H

#include <stdint.h>

#include <sfd/sfd.h>

#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_feature_verdict_t.h"
#include "sfd_imu_ring.h"
#include "sfd_lcm_codec.h"
#include "sfd_nav_state_t.h"
#include "sfd_truth_t.h"
#include "sfd_node_nav.h"
#include "sfd_timing_t.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Input message kinds (the app maps channel names to these). */
typedef enum {
    SFD_NODE_IMU = 0,
    SFD_NODE_CAMERA_INFO = 1,
    SFD_NODE_FEATURES = 2,
    SFD_NODE_TRUTH = 3 /**< evaluation only: used when cfg.nav.init_from_truth is set */
} sfd_node_input_t;

/** Output message kinds. */
typedef enum {
    SFD_NODE_OUT_VERDICT = 0,
    SFD_NODE_OUT_TIMING = 1,
    SFD_NODE_OUT_STATE = 2
} sfd_node_output_t;

typedef struct {
    sfd_params_t params;    /**< detector parameters (method: any sfd_method_t) */
    sfd_nav_config_t nav;   /**< the EKF and landmarks (required by oprf, ransac1, ransacf, both) */
    int32_t camera_id;      /**< camera to follow; -1 = the first CAMERA_INFO's */
    int32_t publish_timing; /**< 1: publish SFD_TIMING after every frame */
} sfd_node_config_t;

/** Publish callback: kind, encoded message, size, and the utime of the frame it belongs to. */
typedef void (*sfd_node_publish_fn)(void *ctx, sfd_node_output_t kind, const void *data,
                                    int32_t size, int64_t utime);
/** Monotonic clock in microseconds, for SFD_TIMING durations only (NULL: durations are 0). */
typedef int64_t (*sfd_node_clock_fn)(void *ctx);

/** Counters since init (published on SFD_TIMING and in the replay summary). */
typedef struct {
    int64_t rejected[SFD_REJECT_NUM_REASONS]; /**< by sfd_reject_reason_t */
    int64_t frames_in;                        /**< FEATURES messages received */
    int64_t frames_processed;                 /**< frames that produced a verdict */
    int64_t frames_untested; /**< of those, frames with no tested feature (window filling,
                                  IMU missing) */
    int64_t imu_in, camera_info_in;
} sfd_node_counters_t;

enum { SFD_NODE_MAX_MESSAGE = 16384 };

typedef struct {
    sfd_node_config_t cfg;
    sfd_node_publish_fn publish;
    sfd_node_clock_fn clock;
    void *ctx;
    sfd_node_counters_t counters;
    /* detector and sensor state */
    sfd_parity_t parity;
    sfd_nav_t nav;
    sfd_imu_ring_t ring;
    sfd_camera_t camera;
    sfd_extrinsics_t ext;
    int32_t camera_id;
    int32_t have_camera;
    int64_t last_utime[3]; /* per input kind */
    int64_t prev_frame_utime;
    int32_t have_prev_frame;
    int32_t have_pending; /* one frame may wait for its IMU */
    int64_t pending_ingest_us;
    /* scratch (kept here, not on the stack) */
    sfd_frame_t pending;
    sfd_frame_t frame;
    sfd_feature_frame_t wire_features;
    sfd_camera_info_t wire_camera;
    sfd_verdict_t verdict;
    sfd_feature_verdict_t wire_verdict;
    sfd_timing_t wire_timing;
    sfd_nav_state_t wire_state;
    sfd_truth_t wire_truth;
    sfd_truth_v1_t wire_truth_v1; /* scratch: TRUTH of logs before kind[] */
    int8_t final_status[SFD_MAX_FEATURES];
    uint8_t skip[SFD_MAX_FEATURES];
    sfd_imu_sample_t imu_scratch[SFD_MAX_IMU_SAMPLES];
    uint8_t out_buf[SFD_NODE_MAX_MESSAGE];
} sfd_node_t;

/** @brief Defaults: sfd_params_default(), camera_id -1 (follow the first CAMERA_INFO), timing
 *         published, sfd_nav_config_default(). */
void sfd_node_config_default(sfd_node_config_t *cfg);

/**
 * @brief Initializes the node. The detector starts when the first valid CAMERA_INFO arrives.
 * @return SFD_OK; SFD_ERR_INVAL for null arguments, invalid parameters, or a method that needs
 *         the filter (OPRF, RANSAC1, RANSACF, BOTH) with cfg->nav.enabled = 0.
 */
sfd_status_t sfd_node_init(sfd_node_t *node, const sfd_node_config_t *cfg,
                           sfd_node_publish_fn publish, sfd_node_clock_fn clock, void *ctx);

/** @brief Handles one received message. Never fails: bad input is counted and dropped. */
void sfd_node_handle(sfd_node_t *node, sfd_node_input_t kind, const void *data, int32_t size);

/** @brief End of input: a frame still waiting for IMU is judged now (UNTESTED, IMU_LATE). */
void sfd_node_flush(sfd_node_t *node);

#ifdef __cplusplus
}
#endif

#endif /* SFD_NODE_CORE_H */
