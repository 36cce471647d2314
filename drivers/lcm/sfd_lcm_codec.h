/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_lcm_codec.h
 * @brief Decode and validation of sfd's LCM messages into core structs, malloc-free: the generated
 *        fixed-capacity types decode into caller-owned storage, and every check happens here,
 *        before the core sees anything (SPEC "LCM interface").
 *
 * Rejections carry a reason (sfd/sfd_reject.h, numbered as timing_t's REJECT_* constants), so
 * the node can count them and publish the counts on SFD_TIMING.
 */
#ifndef SFD_LCM_CODEC_H
#define SFD_LCM_CODEC_H

#include <stdint.h>

#include <sfd/sfd.h>
#include <sfd/sfd_reject.h>

#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_imu_t.h"
#include "sfd_truth_t.h"
#include "sfd_truth_v1_t.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief Decodes an IMU message and validates it (finite values).
 * @return SFD_REJECT_NONE on success (out filled), else the reason (out untouched).
 */
int sfd_lcm_decode_imu(const void *data, int size, sfd_imu_sample_t *out);

/**
 * @brief Decodes CAMERA_INFO into a validated camera model and extrinsics.
 * @param msg  caller-owned scratch for the wire struct.
 * @return SFD_REJECT_NONE on success; SFD_REJECT_DECODE; by cause of a calibration the camera
 *         model or the extrinsics reject: SFD_REJECT_CALIB_INTRINSICS (size <= 0, focal lengths
 *         not > 0, a NaN/Inf intrinsic), SFD_REJECT_CALIB_DISTORTION (unknown model, NaN/Inf or,
 *         for pinhole, non-zero coefficients), SFD_REJECT_CALIB_EXTRINSICS (not a rigid
 *         transform).
 */
int sfd_lcm_decode_camera_info(const void *data, int size, sfd_camera_info_t *msg,
                               sfd_camera_t *camera, sfd_extrinsics_t *ext, int32_t *camera_id);

/**
 * @brief Decodes FEATURES into a core frame. Counts above the core capacity are rejected (the
 *        core never sees a truncated frame); non-finite pixels are passed on (the core marks them
 *        UNTESTED/BAD_INPUT so that the verdict still lists them); a depth prior that is
 *        non-finite or has a negative/non-finite variance is replaced by "unknown" (depth 0),
 *        and *depth_fixed counts how many were.
 * @param msg  caller-owned scratch for the wire struct (41 KiB: keep it static).
 * @return SFD_REJECT_NONE on success; SFD_REJECT_DECODE; SFD_REJECT_COUNT (negative or above the
 *         wire capacity); SFD_REJECT_CAPACITY (above SFD_MAX_FEATURES).
 */
int sfd_lcm_decode_features(const void *data, int size, sfd_feature_frame_t *msg,
                            sfd_frame_t *frame, int32_t *camera_id, int *depth_fixed);

/**
 * @brief Decodes TRUTH in the current layout (truth_t, with kind[]) or the one logs before kind[]
 *        carry (truth_v1_t); a v1 message gets kind = KIND_UNSPECIFIED for its spurious features
 *        and KIND_CLEAN for the others, so readers see one layout.
 * @param legacy  caller-owned scratch for the v1 wire struct (5 KiB: keep it static).
 * @return SFD_REJECT_NONE on success (out filled; its entries past num_features are
 *         unspecified); SFD_REJECT_DECODE (neither layout, or a kind[] outside KIND_CLEAN ..
 *         KIND_UNSPECIFIED, or kind and spurious disagreeing on whether a feature is spurious);
 *         SFD_REJECT_COUNT (num_features outside [0, CAPACITY]); SFD_REJECT_NONFINITE (pose).
 */
int sfd_lcm_decode_truth(const void *data, int size, sfd_truth_t *out, sfd_truth_v1_t *legacy);

#ifdef __cplusplus
}
#endif

#endif /* SFD_LCM_CODEC_H */
