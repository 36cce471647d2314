/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_reject.h
 * @brief Why an input (IMU sample, calibration, frame) was not used, or a frame was judged
 *        UNTESTED. The numbers equal the wire's sfd_timing_t REJECT_* constants, so that a
 *        transport can publish the pipeline's counters as they are.
 */
#ifndef SFD_REJECT_H
#define SFD_REJECT_H

#ifdef __cplusplus
extern "C" {
#endif

/** Rejection reasons (identical to sfd_timing_t's REJECT_* constants). */
typedef enum {
    SFD_REJECT_NONE = -1,
    SFD_REJECT_DECODE = 0,    /**< the buffer does not decode (short, corrupt, wrong type) */
    SFD_REJECT_COUNT = 1,     /**< num_features outside [0, wire capacity] */
    SFD_REJECT_NONFINITE = 2, /**< NaN/Inf where a number is required (IMU), or an IMU axis
                                   beyond the physical bounds of sfd_imu.h */
    SFD_REJECT_ORDER = 3,     /**< utime not after the channel's previous message */
    SFD_REJECT_CAMERA_ID = 4, /**< camera_id unknown (no CAMERA_INFO for it) */
    SFD_REJECT_DEPTH =
        5, /**< depth prior unusable (counted; the feature is kept as "unknown depth") */
    SFD_REJECT_NO_CAMERA_INFO = 6, /**< features before any calibration */
    SFD_REJECT_IMU_GAP = 7,        /**< IMU does not cover the frame interval */
    SFD_REJECT_IMU_LATE = 8,       /**< waited too long for IMU */
    SFD_REJECT_IMU_OVERFLOW = 9,   /**< IMU ring full: a sample a frame may need overwritten */
    SFD_REJECT_CAPACITY = 10,      /**< more features than the core's SFD_MAX_FEATURES */
    SFD_REJECT_CORE = 11,          /**< the core refused the frame (status code) */
    SFD_REJECT_TIME_JUMP = 12,     /**< utime farther than the horizon from its stream (a glitch,
                                        or one of the first messages of a restarted stream) */
    SFD_REJECT_RESTART = 13,       /**< not a message: the pipeline's frame or IMU side restarted
                                        on another time base (sfd_time_guard.h) */
    SFD_REJECT_FEATURE_NONFINITE = 14, /**< features (not frames) with a NaN/Inf pixel coordinate:
                                            kept, never judged (UNTESTED) */
    SFD_REJECT_FEATURE_DUPLICATE = 15, /**< features whose track id came earlier in the frame */
    SFD_REJECT_FEATURE_OUTSIDE = 16,   /**< features outside the calibrated image (kept) */
    SFD_REJECT_CALIB_INTRINSICS = 17,  /**< CAMERA_INFO: size, focal lengths or principal point
                                            not valid (<= 0, NaN) */
    SFD_REJECT_CALIB_DISTORTION = 18,  /**< CAMERA_INFO: unknown model, or its coefficients */
    SFD_REJECT_CALIB_EXTRINSICS = 19,  /**< CAMERA_INFO: T_imu_cam not a rigid transform */
    SFD_REJECT_FRAME_GAP = 20,         /**< not a message: frames missing between accepted
                                            frames (a gap of k frame periods counts k - 1) */
    SFD_REJECT_NUM_REASONS = 21
} sfd_reject_reason_t;

/** Name of a rejection reason ("decode", "count", ...); "unknown" out of range. */
const char *sfd_reject_reason_str(int reason);

#ifdef __cplusplus
}
#endif

#endif /* SFD_REJECT_H */
