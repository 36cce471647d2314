/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_rest.h
 * @brief Rest detection from the IMU alone, for the window filter's at-rest start (issue 16: rest
 *        is detected, not assumed; core/docs/rest_detection.md).
 *
 * The samples are averaged in blocks of B samples (default 20 = 0.1 s at 200 Hz); the last K
 * blocks (default 10 = 1 s) form the window. At rest the block means scatter only by the sensor
 * noise and by the vibration that is left after averaging over a block (a multicopter on the
 * ground with its rotors running vibrates at tens of Hz); motion moves them. The statistic
 *
 *     T = sum_b |w_b - w|^2 / s_w^2 + sum_b |a_b - a|^2 / s_a^2   ~  chi2(6 (K - 1)) at rest,   (1)
 *
 * with w_b, a_b the block means of gyro and accelerometer, w, a their means over the window and
 * s_w, s_a the per-axis standard deviation of one block mean at rest (configured), decides rest
 * when T <= chi2(6 (K - 1), 1 - alpha) and the mean specific force is gravity's magnitude within
 * a tolerance (free fall, or an accelerometer scale error, is not rest). At rest, w estimates the
 * gyro bias and a / |a| the direction of gravity's reaction in the IMU frame (the accelerometer
 * bias is not separable from gravity at rest: the caller gives it a prior, not this estimate).
 *
 * Fixed memory (SFD_REST_MAX_BLOCKS block means), no heap, no global state.
 */
#ifndef SFD_REST_H
#define SFD_REST_H
#include <stdint.h>
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/** Largest window, in blocks. */
#define SFD_REST_MAX_BLOCKS 64

typedef struct {
    int32_t block_samples;         /**< B: IMU samples per block, 1..1000 (20) */
    int32_t window_blocks;         /**< K: blocks in the window, 2..SFD_REST_MAX_BLOCKS (10) */
    double gyro_block_sigma_rad_s; /**< s_w of eq. (1), > 0 (0.005) */
    double accel_block_sigma_m_s2; /**< s_a of eq. (1), > 0 (0.05) */
    double alpha;                  /**< false-alarm rate of "moving" at rest, (0, 0.5] (0.001) */
    double gravity_m_s2;           /**< gravity's magnitude, > 0 (9.81) */
    double gravity_tol_m_s2;       /**< | |a| - g | allowed at rest, > 0 (0.5) */
    int64_t max_gap_us;            /**< a larger gap between samples restarts the window (50000) */
} sfd_rest_params_t;

/** The detector (caller-owned). */
typedef struct {
    sfd_rest_params_t p;
    double threshold;                      /**< chi2(6 (K - 1), 1 - alpha) */
    int64_t last_t_us;                     /**< newest sample's time; INT64_MIN before the first */
    int32_t in_block;                      /**< samples in the block being summed */
    int32_t blocks;                        /**< complete blocks held, <= K */
    int32_t next;                          /**< ring slot the next complete block goes to */
    uint32_t restarts;                     /**< windows restarted by a gap */
    int64_t block_start_us;                /**< first sample of the block being summed */
    double sum[6];                         /**< its sums: gyro x y z, accel x y z */
    double mean[SFD_REST_MAX_BLOCKS][6];   /**< complete blocks' means, ring */
    int64_t start_us[SFD_REST_MAX_BLOCKS]; /**< each block's first sample time */
    int64_t end_us[SFD_REST_MAX_BLOCKS];   /**< each block's last sample time */
} sfd_rest_t;

/** Verdict on the newest window. */
typedef struct {
    int32_t ready;             /**< 1: K complete blocks (otherwise nothing else is set) */
    int32_t at_rest;           /**< 1: T <= threshold and | |a| - g | <= gravity_tol */
    double statistic;          /**< T of eq. (1) */
    double threshold;          /**< chi2(6 (K - 1), 1 - alpha) */
    double gyro_mean_rad_s[3]; /**< w: the gyro bias estimate when at rest */
    double accel_mean_m_s2[3]; /**< a: mean specific force (IMU frame) */
    int64_t window_start_us;   /**< first sample of the window */
    int64_t window_end_us;     /**< last sample of the window */
} sfd_rest_result_t;

/** @brief The defaults in parentheses above. */
sfd_status_t sfd_rest_params_default(sfd_rest_params_t *params);

/** @brief Validates the parameters and empties the detector.
 *  @return SFD_OK; SFD_ERR_INVAL for null or a parameter out of range (detector unchanged). */
sfd_status_t sfd_rest_init(sfd_rest_t *rest, const sfd_rest_params_t *params);

/**
 * @brief One IMU sample (rad/s, m/s^2, IMU frame).
 * @return SFD_OK; SFD_ERR_INVAL (null, non-finite: nothing changed); SFD_ERR_ORDER when t_us is
 *         not after the previous sample (ignored). A gap over max_gap_us restarts the window
 *         (counted in `restarts`) before the sample is taken.
 */
sfd_status_t sfd_rest_push(sfd_rest_t *rest, int64_t t_us, const double gyro_rad_s[3],
                           const double accel_m_s2[3]);

/** @brief Eq. (1) on the newest K complete blocks.
 *  @return SFD_OK (out->ready 0 while fewer than K blocks); SFD_ERR_INVAL for null. */
sfd_status_t sfd_rest_evaluate(const sfd_rest_t *rest, sfd_rest_result_t *out);

#ifdef __cplusplus
}
#endif
#endif /* SFD_REST_H */
