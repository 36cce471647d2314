/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_node_core.h
 * @brief The node's message handling, shared by sfd-node (live LCM) and sfd-replay (log files),
 *        so that replay drives exactly the node's code path: decode and validate IMU,
 *        CAMERA_INFO and FEATURES, choose the camera, hand everything to the core's pipeline
 *        (sfd/sfd_pipeline.h: IMU ring, filter, detectors, track bookkeeping), time its stages
 *        and publish SFD_VERDICT, SFD_STATE and SFD_TIMING through a caller-supplied function.
 *
 * Heap: none. All storage is in sfd_node_t (caller-owned, see sizeof: declare it static). Time
 * enters only through message timestamps; the optional clock function is used for SFD_TIMING's
 * durations only, never for decisions, so replays are deterministic.
 */
#ifndef SFD_NODE_CORE_H
#define SFD_NODE_CORE_H

#include <stdint.h>

#include <sfd/sfd.h>
#include <sfd/sfd_pipeline.h>

#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_feature_verdict_t.h"
#include "sfd_lcm_codec.h"
#include "sfd_nav_state_t.h"
#include "sfd_truth_t.h"
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
    sfd_params_t params;          /**< detector parameters (method: any sfd_method_t) */
    sfd_nav_config_t nav;         /**< the filter (required by oprf, ransac1, ransacf, both) */
    sfd_time_guard_params_t time; /**< time-glitch policy of the IMU and frame streams */
    int32_t camera_id;            /**< camera to follow; -1 = the first CAMERA_INFO's */
    int32_t publish_timing;       /**< 1: publish SFD_TIMING after every frame */
} sfd_node_config_t;

/** Publish callback: kind, encoded message, size, and the utime of the frame it belongs to. */
typedef void (*sfd_node_publish_fn)(void *ctx, sfd_node_output_t kind, const void *data,
                                    int32_t size, int64_t utime);
/** Monotonic clock in microseconds, for SFD_TIMING durations only (NULL: durations are 0). */
typedef int64_t (*sfd_node_clock_fn)(void *ctx);

/** Counters since init (published on SFD_TIMING and in the replay summary): the pipeline's,
 *  with the node's receive and decode counts added (node->pipe.counters). */
typedef sfd_pipeline_counters_t sfd_node_counters_t;

enum { SFD_NODE_MAX_MESSAGE = 16384 };

/** Inputs handled without a judged frame after which SFD_TIMING is published as a status report
 *  (frame_processed 0): about 1 Hz for a 200 Hz IMU and 20 Hz frames that are all refused, never
 *  while frames are judged (each judged frame publishes SFD_TIMING and restarts the count). */
enum { SFD_NODE_STATUS_EVERY_INPUTS = 200 };

typedef struct {
    sfd_node_config_t cfg;
    sfd_node_publish_fn publish;
    sfd_node_clock_fn clock;
    void *ctx;
    sfd_pipeline_t pipe; /**< filter, detectors, IMU ring, counters */
    int32_t camera_id;
    /* decode time of the frames the pipeline holds, by frame time (SFD_TIMING.ingest_us) */
    int64_t ingest_utime[SFD_PIPELINE_FRAME_SLOTS];
    int64_t ingest_us[SFD_PIPELINE_FRAME_SLOTS];
    int32_t ingest_next;
    int32_t inputs_since_timing; /**< inputs handled since the last SFD_TIMING */
    /* scratch (kept here, not on the stack) */
    sfd_frame_t frame;
    sfd_feature_frame_t wire_features;
    sfd_camera_info_t wire_camera;
    sfd_feature_verdict_t wire_verdict;
    sfd_timing_t wire_timing;
    sfd_nav_state_t wire_state;
    sfd_truth_t wire_truth;
    sfd_truth_v1_t wire_truth_v1; /* scratch: TRUTH of logs before kind[] */
    uint8_t out_buf[SFD_NODE_MAX_MESSAGE];
} sfd_node_t;

/** @brief Defaults: sfd_pipeline_config_default()'s parameters, filter and time guard
 *         (parity with the filter's translation, the alarm hold and the ramp test), camera_id -1
 * (follow the first CAMERA_INFO), timing published. */
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
