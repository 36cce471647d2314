/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_nav.h
 * @brief The node's navigation side (SPEC "LCM interface"): the EKF started at rest from
 *        gravity and propagated with every IMU sample, the landmark map built from the tracks
 *        (first observation + depth prior, refined along the track), and the matches handed to
 *        the association methods (OPRF, 1-point RANSAC, F-matrix RANSAC, none).
 *
 * The node calls, per frame: sfd_nav_advance() (propagate to the frame), sfd_nav_build()
 * (matches of the tracks seen in the previous frame that have a landmark), then times
 * sfd_assoc_select() / sfd_assoc_apply() itself (SFD_TIMING stages) with &nav->work.assoc.scratch
 * as their work space, then sfd_nav_finish() (landmarks refined or created with the posterior
 * camera pose, the frame kept for the next; with the window filter it builds the filter's frame
 * in nav->work, over the matches and the filter copy, which are dead by then).
 *
 * Heap: none; all storage in sfd_nav_t (caller-owned, inside sfd_node_t).
 */
#ifndef SFD_NAV_H
#define SFD_NAV_H

#include <stdint.h>

#include "sfd_assoc.h"
#include "sfd_ekf.h"
#include "sfd_imu_ring.h"
#include "sfd_landmarks.h"
#include "sfd_parity.h"
#include "sfd_rest.h"
#include "sfd_window.h"

/** Slots of the previous frame's track index (load factor <= 1/2). */
#define SFD_NAV_TRACK_SLOTS (2 * SFD_MAX_FEATURES + 1)

#ifdef __cplusplus
extern "C" {
#endif

/** Configuration of the navigation side (YAML section `filter`, apps/config/sfd.yaml). */
typedef struct {
    int32_t enabled;             /**< 1: run the EKF (required by oprf, ransac1, ransacf, both) */
    int32_t window_filter;       /**< 1: the sliding-window filter (sfd_window.h), started when
                                      rest is detected (sfd_rest.h); 0: the single-state EKF
                                      with self-built landmarks (sfd_ekf.h, older) */
    int32_t window_size;         /**< clones L of the window filter, 2..SFD_MAX_WINDOW */
    int32_t window_depth_priors; /**< window filter: a track's depth priors used as measurements:
                                      0 none, 1 the first observation's, 2 also the newest's
                                      (default; sfd_window_params_t.use_depth_prior) */
    double window_gate_alpha;    /**< false-alarm rate of its per-track chi-square gate */
    int32_t window_flagged_earlier;    /**< window filter: 1 a SPURIOUS verdict ends its track, the
                                            observations before it used through the gate (default;
                                            not for sfd_nav_finish's whole_track); 0 deleted
                                            (sfd_window_params_t.flagged_earlier) */
    int32_t first_estimates;           /**< window filter: 1 first-estimate Jacobians (overrides the
                                            next), 0 current estimates */
    int32_t observability_constrained; /**< window filter, first_estimates 0: 1 current-estimate
                                            Jacobians with the observability constraint (the
                                            default), 0 without (core/docs/window_filter.md) */
    double keyframe_parallax_rad;      /**< window filter: 0 the oldest clone leaves (default);
                                            > 0 keyframes below this mean parallax leave instead,
                                            the newest params.window_frames - 1 clones kept
                                            consecutive (sfd_window_params_t) */
    sfd_ekf_noise_t noise;             /**< IMU noise densities */
    double p0_diag[SFD_EKF_DIM];       /**< initial variances, SFD_EKF_IDX_* order */
    double init_rest_s;                /**< IMU averaged at rest for the gravity start (s), > 0 */
    int32_t gyro_bias_at_rest;         /**< 1: the mean gyro at rest is the initial bias; 0: the
                                            configured params.gyro_bias_rad_s */
    double landmark_depth_var_m2;      /**< depth variance of a landmark whose feature has no depth
                                            prior (the default depth is params.default_depth_m) */
    double landmark_max_age_s;         /**< landmarks unseen for longer are dropped (s), > 0 */
    double landmark_gate_alpha;        /**< false-alarm rate of the landmark refinement gate */
    double min_parallax_px;            /**< OPRF degenerate-motion threshold (sfd_assoc_params_t) */
    int32_t init_from_truth;   /**< evaluation only (SPEC): start from the first two TRUTH poses
                                    (velocity from their difference) instead of at rest */
    int32_t consider_position; /**< 1: camera updates do not correct the position (sfd_ekf_t
                                    consider states): self-built landmarks hold no absolute
                                    position information */
    double init_accel_bias_m_s2[3]; /**< init_from_truth: the accelerometer bias the filter
                                         starts with (IMU frame, m/s^2; TRUTH carries none);
                                         the gyro bias is params.gyro_bias_rad_s */
} sfd_nav_config_t;

/** @brief Defaults: enabled; sfd_ekf_noise_default() with white noise 1.0e-3 rad/s/sqrt(Hz)
 *         and 1.2e-2 m/s^2/sqrt(Hz) (about three times, for a real IMU: nav.c); P0 position 1e-6
 * m^2 (the origin is defined by the start), velocity 1e-4, attitude 1e-4 rad^2 (yaw 1e-6), gyro
 * bias 1e-4, accel bias 1e-2; 1 s at rest with the gyro bias from it; unknown depth variance 100
 * m^2; landmarks dropped after 2 s unseen; gate alpha 0.001; 1 px parallax; start at rest (not from
 * TRUTH); position as a consider state. */
void sfd_nav_config_default(sfd_nav_config_t *cfg);

typedef struct {
    sfd_nav_config_t cfg;
    sfd_params_t params;
    sfd_ekf_t ekf; /**< window_filter: the window filter's IMU state (sfd_window_to_ekf), read
                        by the association methods, the landmark map and SFD_STATE */
    sfd_window_t win;
    sfd_window_result_t win_result; /**< of the last frame */
    int64_t win_gated;              /**< tracks the window filter's gate refused since init */
    int64_t win_used;               /**< tracks it used */
    int64_t ekf_utime;              /**< time the filter state refers to (us) */
    int32_t ready;                  /**< 1 once started from gravity */
    int32_t starts;                 /**< times the filter was (re)started */
    int32_t have_truth0;            /**< init_from_truth: the first TRUTH pose is held */
    int64_t truth0_utime;
    double truth0_p[3];
    sfd_assoc_t assoc;
    sfd_assoc_result_t result;
    sfd_landmark_map_t map;
    sfd_ekf_camera_t ekf_cam;
    /* the current frame */
    int32_t num_matches;
    /** Per-frame work, overlaid: the association's part lives from sfd_nav_build() to the
     *  association's update (sfd_pipeline_associate -> apply in sfd_pipeline_update); the
     *  window filter's part from its parity tests (sfd_pipeline_detect) and again in
     *  sfd_nav_finish(), after the association's update; the rest detector's within one
     *  sfd_nav_advance() before the filter starts or one sfd_nav_imu_at_rest() (before the
     *  parity tests). Nothing in it survives a frame. */
    union {
        struct {
            sfd_match_t matches[SFD_MAX_FEATURES]; /**< filled by sfd_nav_build() */
            sfd_ekf_t ekf; /**< window_filter: the association's update runs on this copy (its
                                verdicts count; the window filter makes the update) */
            sfd_assoc_work_t scratch; /**< the method's work space, select to apply */
        } assoc;
        /** the window filter's work space for its tests and its frame; the frame's
         *  observations are built in its u.obs */
        sfd_window_scratch_t window;
        /** the rest detector of a start at rest or of sfd_nav_imu_at_rest(): filled and
         *  evaluated within one call */
        sfd_rest_t rest;
    } work;
    int16_t match_feature[SFD_MAX_FEATURES]; /**< feature index of each match */
    int16_t feature_match[SFD_MAX_FEATURES]; /**< match index of each feature, -1 for none */
    float xn[SFD_MAX_FEATURES][2]; /**< normalized undistorted coordinates, rounded to float as
                                        the parity detector stores them (the same bits whether
                                        or not it ran: sfd_parity_newest_xn) */
    uint8_t ok[SFD_MAX_FEATURES];  /**< undistortion succeeded */
    /* the previous frame (observations kept for the next frame's matches) */
    int32_t prev_n;
    int64_t prev_track[SFD_MAX_FEATURES];
    float prev_uv[SFD_MAX_FEATURES][2]; /* undistorted pixels (float, as xn: a relative 6e-8) */
    /** track id -> first index in prev_track (open addressing, -1 empty), built with prev_track */
    int16_t prev_index[SFD_NAV_TRACK_SLOTS];
    double prev_R_CtoW[9];
    double prev_p_CinW_m[3];
    int32_t have_prev;
} sfd_nav_t;

/** @brief Association method of the navigation side for a detector method: OPRF, RANSAC1,
 *         RANSACF and NONE as themselves, BOTH -> OPRF, PARITY -> NONE (the filter is then updated
 *         with the features parity accepted). */
int32_t sfd_nav_assoc_method(int32_t detector_method);

/** @brief Initializes the state. @return SFD_OK; SFD_ERR_INVAL for null or invalid values. */
sfd_status_t sfd_nav_init(sfd_nav_t *nav, const sfd_nav_config_t *cfg, const sfd_params_t *params);

/** @brief A new calibration: the camera model of the EKF; landmarks and tracks start over. */
void sfd_nav_set_camera(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_extrinsics_t *ext);

/**
 * @brief Brings the filter to @p t_us: starts it from gravity when it is not running (needs
 *        init_rest_s of IMU before t_us), else propagates it with the ring's samples
 *        (zero-order hold of each sample until the next, the last one until t_us).
 * @return SFD_REJECT_NONE when the filter is at t_us and running; SFD_REJECT_IMU_GAP /
 *         SFD_REJECT_IMU_LATE / SFD_REJECT_CAPACITY from the ring, or SFD_REJECT_CORE when the
 *         filter refused (it is then stopped and restarts from gravity later; counted in
 *         `starts`). SFD_REJECT_NONE also when it just started (no prior to associate yet).
 */
int sfd_nav_advance(sfd_nav_t *nav, const sfd_imu_ring_t *ring, int64_t t_us);

/**
 * @brief 1 when the IMU of [max(t_us - init_rest_s, the ring's oldest sample), t_us] is at rest by
 *        the rest detector of the filter's start (the same blocks, at least 2; right after the
 *        IMU starts, 2 shorter blocks of at least 5 samples each, so that at 200 Hz the second
 *        frame at 20 Hz can be judged, at 100 Hz the third) and that window reaches back to
 *        @p since_us (the previous frame), up to the samples its whole blocks leave out at its
 *        start (fewer than one block: 5 ms right after the IMU starts). The parity detector's
 *        rest test (SFD_MOTION_AT_REST) relies on it. 0 otherwise, and for null arguments or a
 *        disabled filter. Uses nav->work (nothing in it survives a frame): call it outside the
 *        filter's and the association's stages. The rest detector tests the scatter of block
 *        means and |a| = g: a constant velocity, a small constant acceleration or a constant
 *        rotation pass it; the parity detector checks that the features agree.
 */
int sfd_nav_imu_at_rest(sfd_nav_t *nav, const sfd_imu_ring_t *ring, int64_t since_us, int64_t t_us);

/**
 * @brief A TRUTH pose (init_from_truth only; ignored otherwise or once running): the first one
 *        is kept, the second starts the filter at that pose with the velocity of the difference,
 *        the gyro bias params.gyro_bias_rad_s and the accelerometer bias
 *        cfg.init_accel_bias_m_s2.
 */
void sfd_nav_truth(sfd_nav_t *nav, int64_t utime, const double p_m[3], const double q_wxyz[4]);

/**
 * @brief Starts (or restarts) the filter at a given state at @p utime instead of at rest: a
 *        known start (evaluation, a filter handed over from another source). The landmarks
 *        are kept; the next frame has no previous one.
 * @param p0_diag nullable: initial variances (SFD_EKF_IDX_* order); for the window filter they
 *        replace its parameters' P0, and the attitude's are then of its global error (the same
 *        as the local ones when the three are equal); NULL: cfg.p0_diag (the window filter: its
 *        own P0).
 * @return SFD_OK; SFD_ERR_INVAL for null, non-finite values or a zero quaternion; SFD_ERR_STATE
 *         when the filter is not enabled; the filter's refusal otherwise (then not started).
 */
sfd_status_t sfd_nav_start_at(sfd_nav_t *nav, int64_t utime, const double p_m[3],
                              const double v_m_s[3], const double q_ItoW[4],
                              const double bg_rad_s[3], const double ba_m_s2[3],
                              const double p0_diag[SFD_EKF_DIM]);

/**
 * @brief Matches of the frame: features (not excluded by @p skip, nullable) whose track was in
 *        the previous frame and has a landmark. Fills nav->work.assoc.matches / match_feature /
 *        feature_match; undistorts every feature with @p cam.
 * @param parity nullable: a detector that has just judged this frame with the same camera; the
 *        coordinates it computed are taken from it (sfd_parity_newest_xn(), bit-identical), and
 *        only the features it rejected are undistorted again.
 * @return the number of matches.
 */
int32_t sfd_nav_build(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_frame_t *frame,
                      const uint8_t *skip, const sfd_parity_t *parity);

/**
 * @brief After the association: refines the landmarks of the features judged CONSISTENT with
 *        the posterior camera pose (gated; a known landmark, sfd_landmark_set(), is not refined),
 * creates landmarks for features without one (depth prior or the default), drops landmarks unseen
 * for landmark_max_age_s, and keeps the non-SPURIOUS observations as the next frame's previous
 * ones.
 * @param cam the camera given to sfd_nav_build() for this frame (the window filter's pixel noise
 *        through its distortion Jacobian is computed again from it).
 * @param status per feature, SFD_VERDICT_* (the frame's final verdicts).
 * @param whole_track per feature, nonzero when its SPURIOUS verdict condemns the track's earlier
 *        observations too (the parity evidence test or its ramp test): the window filter deletes
 *        them unused.
 *        Any other SPURIOUS verdict ends the track before it (window_flagged_earlier). NULL: none
 *        does.
 */
void sfd_nav_finish(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_frame_t *frame,
                    const int8_t *status, const uint8_t *whole_track);

#ifdef __cplusplus
}
#endif

#endif /* SFD_NAV_H */
